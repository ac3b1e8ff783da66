"""``rocas params``: list the built-in ADS's named parameters."""

from __future__ import annotations

import argparse
import json

from rocas.cli.console import Env
from rocas.errors import UsageError

HELP = "list the built-in ADS's parameters (default, range, unit, description)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--module", metavar="M",
                   help="only this module (localization, canbus, perception, prediction, "
                        "planning, control)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace, env: Env) -> int:
    from rich.table import Table

    from rocas.ads.params import MODULES, parameters

    if args.module is not None and args.module not in MODULES:
        raise UsageError(f"unknown module {args.module!r}", f"choose from {', '.join(MODULES)}")
    items = parameters(args.module)
    if args.json:
        print(json.dumps([{"name": p.full_name, "module": p.module, "default": p.default,
                           "low": p.low, "high": p.high, "unit": p.unit,
                           "description": p.description} for p in items], indent=2),
              file=env.stdout)
        return 0
    table = Table(title=f"{len(items)} ADS parameters", title_justify="left")
    for col, kw in (("name", {"no_wrap": True}), ("default", {"justify": "right"}),
                    ("range", {"justify": "right"}), ("unit", {}), ("description", {})):
        table.add_column(col, **kw)
    for p in items:
        table.add_row(p.full_name, f"{p.default:g}", f"[{p.low:g}, {p.high:g}]", p.unit,
                      p.description)
    env.out().print(table)
    return 0
