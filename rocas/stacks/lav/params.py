"""The LAV-like stack's parameter inventory, read from its configuration file
(``config.toml`` next to this module: default, range, unit and description per parameter)."""

from __future__ import annotations

import tomllib
from functools import cache
from importlib import resources

from rocas.stacks.base import ParamSpec

MODULES = ("gnss", "pnp", "planner", "brake", "controller")


@cache
def parameters() -> tuple[ParamSpec, ...]:
    """Every parameter, in the file's order."""
    data = tomllib.loads(resources.files(__package__).joinpath("config.toml").read_text())
    specs = []
    for module in MODULES:
        for name, d in data[module].items():
            low, high = d["range"]
            specs.append(ParamSpec(module, name, float(d["default"]), float(low), float(high),
                                   d["unit"], d["doc"]))
    return tuple(specs)
