"""``rocas simulate SCENARIO -o OUT.mcap``: run a stack (the built-in ADS unless the scenario
or ``--stack`` names another) in the built-in world."""

from __future__ import annotations

import argparse
import dataclasses

from rocas._fs import check_writable
from rocas._json import dumps as json_dumps
from rocas.cli.console import Env, printable
from rocas.errors import ScenarioError, UsageError

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

    from rocas.ads.run import simulate
    from rocas.cli.params import parse_set_options
    from rocas.scenarios import resolve_scenario

    if not str(args.output).endswith(".mcap"):
        raise UsageError(f"output {args.output!r} should end in .mcap")
    if args.seed is not None and args.seed < 0:
        raise UsageError("--seed must be >= 0")
    check_writable(args.output)
    scenario = resolve_scenario(args.scenario)
    if args.duration is not None:
        if not 0 < args.duration <= 600:
            raise UsageError("--duration must be in (0, 600] seconds")
        scenario = dataclasses.replace(scenario, duration_s=args.duration)
    if args.stack is not None:
        from rocas.stacks.rollout import with_stack

        scenario = with_stack(scenario, args.stack)
    if scenario.ego.stack != "ads":  # another stack: rocas.stacks.rollout, its own inventory
        from rocas.stacks.registry import get_stack
        from rocas.stacks.rollout import resolve
        from rocas.stacks.rollout import simulate as simulate_stack

        overrides = {}
        for a in args.assignments:
            name, eq, value = a.partition("=")
            if not eq:
                raise UsageError(f"--set {a!r}: expected MODULE.PARAM=VALUE")
            overrides[name.strip()] = value.strip()
        try:
            overrides = resolve(get_stack(scenario.ego.stack), overrides, "--set").overrides()
        except ScenarioError as exc:
            raise UsageError(exc.message, exc.hint) from None
        result = simulate_stack(scenario, overrides, args.seed, output=args.output)
    else:
        overrides = parse_set_options(args.assignments, "simulate")
    ticks = scenario.num_ticks
    if scenario.ego.stack != "ads":
        pass  # simulated above
    elif args.no_progress:
        result = simulate(scenario, overrides, args.seed, output=args.output)
    else:
        with Progress(TextColumn("[bold]simulating[/] {task.description}"), BarColumn(),
                      TextColumn("{task.percentage:>3.0f}%"), TimeRemainingColumn(),
                      console=env.err(), transient=True) as progress:
            task = progress.add_task(scenario.name, total=ticks)
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
