"""``rocas params``: list the built-in ADS's named parameters."""

from __future__ import annotations

import argparse
import json

from rocas.cli.console import Env
from rocas.errors import UsageError

HELP = "list the built-in ADS's parameters (default, range, unit, description)"


def parse_set_options(assignments: list[str], command: str) -> dict[str, float]:
    """The ``--set MODULE.PARAM=VALUE`` options of ``rocas <command>`` as overrides.

    A malformed option or an unknown parameter is a usage error (exit 2), not bad input.

    Raises:
        UsageError: naming the option, with the closest parameter name or where to look.
    """
    from rocas.stacks.ads.params import parse_assignment
    from rocas.errors import ScenarioError

    try:
        return dict(parse_assignment(a) for a in assignments)
    except ScenarioError as exc:
        hint = exc.hint or "see 'rocas params'"
        raise UsageError(exc.message, f"{hint}; 'rocas {command} --help' for the options") from None


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--module", metavar="M",
                   help="only this module (localization, canbus, perception, prediction, "
                        "planning, control)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace, env: Env) -> int:
    from rich.table import Table

    from rocas.stacks.ads.params import MODULES, parameters

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
