"""``rocas params``: list a registered stack's named parameters (the built-in ADS's by default)."""

from __future__ import annotations

import argparse
import json

from rocas.cli.console import Env, safe
from rocas.errors import UsageError
from rocas.scenarios.model import DEFAULT_STACK

HELP = "list a stack's parameters (default, range, unit, description)"


def parse_set_options(assignments: list[str], command: str, stack: str = DEFAULT_STACK
                      ) -> dict[str, float]:
    """The ``--set MODULE.PARAM=VALUE`` options of ``rocas <command>`` as overrides of the
    registered stack ``stack``.

    A malformed option or an unknown parameter is a usage error (exit 2), not bad input.

    Raises:
        UsageError: naming the option, with the closest parameter name or where to look.
    """
    from rocas.errors import ScenarioError
    from rocas.stacks.base import parse_assignment
    from rocas.stacks.registry import get_stack

    specs = get_stack(stack).parameters
    try:
        return dict(parse_assignment(a, specs) for a in assignments)
    except ScenarioError as exc:
        hint = (exc.hint or "see 'rocas params --stack NAME'").replace("NAME", stack)
        raise UsageError(exc.message, f"{hint}; 'rocas {command} --help' for the options") from None


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--stack", default=DEFAULT_STACK, metavar="NAME",
                   help=f"the registered stack whose parameters to list (default: {DEFAULT_STACK})")
    p.add_argument("--module", metavar="M", help="only this module of the stack")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace, env: Env) -> int:
    from rich.table import Table

    from rocas.stacks.registry import get_stack

    stack = get_stack(args.stack)
    if args.module is not None and args.module not in stack.modules:
        raise UsageError(f"unknown module {args.module!r}",
                         f"choose from {', '.join(stack.modules)}")
    items = [p for p in stack.parameters if args.module is None or p.module == args.module]
    if args.json:
        print(json.dumps([{"name": p.full_name, "module": p.module, "default": p.default,
                           "low": p.low, "high": p.high, "unit": p.unit,
                           "description": p.description} for p in items], indent=2),
              file=env.stdout)
        return 0
    table = Table(title=f"{len(items)} parameters of stack {safe(stack.name)}",
                  title_justify="left")
    for col, kw in (("name", {"no_wrap": True}), ("default", {"justify": "right"}),
                    ("range", {"justify": "right"}), ("unit", {}), ("description", {})):
        table.add_column(col, **kw)
    for p in items:
        table.add_row(safe(p.full_name), f"{p.default:g}", f"[{p.low:g}, {p.high:g}]",
                      safe(p.unit), safe(p.description))
    env.out().print(table)
    return 0
