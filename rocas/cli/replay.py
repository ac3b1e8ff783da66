"""``rocas replay ACCIDENT.mcap``: rebuild the scenario from a recording and run it again."""

from __future__ import annotations

import argparse

from rocas._fs import check_writable
from rocas._json import dumps as json_dumps
from rocas.cli.console import Env, printable
from rocas.errors import NotReproducedError, UsageError

HELP = "rebuild the scenario of a recording, re-run it closed-loop and report the fidelity"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("recording", metavar="ACCIDENT.mcap",
                   help="a recording made by 'rocas simulate' (world attachment, pose, obstacles)")
    p.add_argument("-o", "--output", metavar="REPLAY.mcap", default=None,
                   help="also record the replay (appears only when the run completes)")
    p.add_argument("--set", dest="assignments", action="append", default=[],
                   metavar="MODULE.PARAM=VALUE",
                   help="replay with a changed ADS parameter (a what-if; repeatable)")
    p.add_argument("--json", action="store_true", help="print the report as one JSON object")


def _accident(a: object | None) -> str:
    if a is None:
        return "none (clean run)"
    other = f" with {a.other}" if getattr(a, "other", None) else ""  # type: ignore[attr-defined]
    t = a.time_s  # type: ignore[attr-defined]
    when = f" at t={t:.2f} s" if t is not None else ""
    return f"{a.kind}{other}{when}"  # type: ignore[attr-defined]


def run(args: argparse.Namespace, env: Env) -> int:
    from rocas.cli.params import parse_set_options
    from rocas.replay import replay

    if args.output is not None and not str(args.output).endswith(".mcap"):
        raise UsageError(f"output {args.output!r} should end in .mcap")
    if args.output is not None:
        check_writable(args.output)
    overrides = parse_set_options(args.assignments, "replay")
    report = replay(args.recording, overrides or None, output=args.output)
    rec = report.reconstruction
    assert rec is not None
    for line in rec.warnings:  # damage: in JSON mode too (and in the JSON's "warnings")
        env.warn(line)
    if args.json:
        print(json_dumps(report.to_dict(), indent=2), file=env.stdout)
    else:
        out = env.stdout
        print(printable(f"{rec.scenario.name}: {len(rec.scenario.actors)} actors rebuilt from "
                        f"perception ({', '.join(a.id for a in rec.scenario.actors) or 'none'})"),
              file=out)
        print(printable(f"  original: {_accident(report.original)}"), file=out)
        what_if = f" (with {', '.join(args.assignments)})" if overrides else ""
        print(printable(f"  replay{what_if}: {_accident(report.accident)} -- "
                        f"{report.outcome.summary()}"), file=out)
        verdict = "reproduced" if report.reproduced else "NOT reproduced"
        if report.only_emergency:
            verdict = ("the emergency before the recorded collision reproduced, not the "
                       "collision")
        print(f"  {verdict}; ego error before the accident: RMSE {report.ego_rmse_m:.2f} m, "
              f"max {report.ego_max_error_m:.2f} m (to t={report.compared_until_s:.2f} s); "
              f"{report.wall_time_s:.1f} s", file=out)
        if report.output:
            print(f"  replay recorded to {report.output}", file=out)
        for note in rec.notes:
            if note not in rec.warnings:
                env.warn(note)
    if not report.reproduced and not overrides:
        raise NotReproducedError(
            f"replay of {args.recording} did not reproduce the recorded accident "
            f"({_accident(report.original)}; replay: {_accident(report.accident)})",
            "the reconstruction is in the report; perception may have missed an actor that "
            "mattered, or the run is sensitive to sensor noise")
    return 0
