"""``rocas simulate SCENARIO -o OUT.mcap``: run a stack (the built-in ADS unless the scenario
or ``--stack`` names another) in the built-in world."""

from __future__ import annotations

import argparse
import dataclasses

from rocas._fs import check_writable
from rocas._json import dumps as json_dumps
from rocas.cli.console import Env, printable
from rocas.errors import UsageError

HELP = "simulate a scenario with a stack (default: the built-in ADS), recording every channel to MCAP"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", metavar="SCENARIO",
                   help="scenario TOML file, or the name of a shipped example "
                        "(junction_straight, wet_truck_turn, ...)")
    p.add_argument("-o", "--output", metavar="OUT.mcap", required=True,
                   help="recording to write (appears only when the run completes)")
    p.add_argument("--set", dest="assignments", action="append", default=[],
                   metavar="MODULE.PARAM=VALUE",
                   help="override an ADS parameter (repeatable; see 'rocas params')")
    p.add_argument("--stack", metavar="NAME", default=None,
                   help="the stack that drives the ego (ads, lav, ...; default: the scenario's)")
    p.add_argument("--seed", type=int, default=None, help="random seed (default: the scenario's)")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="simulated seconds (default: the scenario's)")
    p.add_argument("--json", action="store_true", help="print the outcome as JSON")
    p.add_argument("--no-progress", action="store_true", help="do not draw a progress bar")


def run(args: argparse.Namespace, env: Env) -> int:
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    from rocas.cli.params import parse_set_options
    from rocas.rollout import load_scenario, simulate

    if not str(args.output).endswith(".mcap"):
        raise UsageError(f"output {args.output!r} should end in .mcap")
    if args.seed is not None and args.seed < 0:
        raise UsageError("--seed must be >= 0")
    check_writable(args.output)
    scenario = load_scenario(args.scenario)
    if args.duration is not None:
        if not 0 < args.duration <= 600:
            raise UsageError("--duration must be in (0, 600] seconds")
        scenario = dataclasses.replace(scenario, duration_s=args.duration)
    if args.stack is not None:
        from rocas.rollout import with_stack

        scenario = with_stack(scenario, args.stack)
    overrides = parse_set_options(args.assignments, "simulate", scenario.ego.stack)
    if args.no_progress:
        result = simulate(scenario, overrides, args.seed, output=args.output)
    else:
        with Progress(TextColumn("[bold]simulating[/] {task.description}"), BarColumn(),
                      TextColumn("{task.percentage:>3.0f}%"), TimeRemainingColumn(),
                      console=env.err(), transient=True) as progress:
            task = progress.add_task(scenario.name, total=scenario.num_ticks)
            result = simulate(scenario, overrides, args.seed, output=args.output,
                              on_tick=lambda _t: progress.advance(task))
    out = result.outcome
    if args.json:
        payload = {"scenario": scenario.name, "recording": result.recording,
                   "messages": result.messages, "seed": args.seed if args.seed is not None
                   else scenario.seed, "overrides": overrides, **dataclasses.asdict(out)}
        if payload["min_separation_m"] == float("inf"):
            payload["min_separation_m"] = None
        print(json_dumps(payload, indent=2), file=env.stdout)
    else:
        print(printable(f"{scenario.name}: {out.summary()} -> {result.recording} "
                        f"({result.messages} messages)"), file=env.stdout)
    return 0
