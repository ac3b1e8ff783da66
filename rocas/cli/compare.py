"""``rocas compare RUN_A RUN_B``: what differs between two analyses (before and after a change
to the stack, two seeds, two budgets)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from rocas._fs import check_writable
from rocas._json import dumps as json_dumps
from rocas.cli.console import Env, safe
from rocas.cli.exit_codes import ExitStatus

if TYPE_CHECKING:
    from rocas.pipeline.compare import Comparison

HELP = "show what differs between two analyses' run directories"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("run_a", metavar="RUN_A", help="run directory of a finished 'rocas analyze'")
    p.add_argument("run_b", metavar="RUN_B", help="the run directory to compare it with")
    p.add_argument("--all", action="store_true",
                   help="list every field, not only the ones that differ")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--rrd", metavar="OUT.rrd",
                   help="also write a Rerun recording of both reports side by side "
                        "(open it with 'rocas view OUT.rrd')")


def run(args: argparse.Namespace, env: Env) -> int:
    from rocas.pipeline.compare import compare_reports, read_analysis_report

    a, b = Path(args.run_a), Path(args.run_b)
    if args.rrd:
        check_writable(args.rrd)
    report_a, report_b = read_analysis_report(a), read_analysis_report(b)
    comparison = compare_reports(a, report_a, b, report_b)
    if args.rrd:
        from rocas.viz.compare import write_compare_rrd

        write_compare_rrd(args.rrd, comparison, (report_a, report_b))
    if args.json:
        env.stdout.write(json_dumps(comparison.to_json(), indent=2) + "\n")
        return ExitStatus.SUCCESS
    render(comparison, env, every_field=args.all)
    if args.rrd:
        env.out().print(f"Rerun recording: {safe(args.rrd)} (open it with 'rocas view "
                        f"{safe(args.rrd)}')", soft_wrap=True)
    return ExitStatus.SUCCESS


def render(comparison: Comparison, env: Env, *, every_field: bool = False) -> None:
    """The fields that differ (all with ``every_field``), then the costs per phase."""
    from rich.table import Table

    con = env.out()
    differing = comparison.differing
    con.print(f"A: {safe(comparison.run_a)}\nB: {safe(comparison.run_b)}", soft_wrap=True)
    if comparison.same_answer:
        head = "same answer (verdict, triggering entity, deviating module, misconfiguration)"
    else:
        head = "different answers: " + ", ".join(
            f.name for f in differing if f.name in ("verdict", "triggering entity",
                                                    "deviating module", "misconfiguration"))
    con.print(head, soft_wrap=True)
    shown = comparison.fields if every_field else differing
    if shown:
        t = Table(show_header=True, box=None, padding=(0, 1))
        for col in ("field", "A", "B", ""):
            t.add_column(col, style="bold" if col == "field" else None)
        for f in shown:
            t.add_row(safe(f.name), safe(f.a or "-"), safe(f.b or "-"), "" if f.same else "differs")
        con.print(t)
    else:
        con.print("every field and setting agrees")
    same = [f.name for f in comparison.fields if f.same and not f.name.startswith("setting ")]
    if same and not every_field:
        con.print(f"same: {', '.join(safe(n) for n in same)}", soft_wrap=True)
    t = Table(show_header=True, box=None, padding=(0, 1))
    for col in ("phase", "seconds A", "seconds B", "simulations A", "simulations B"):
        t.add_column(col, justify="left" if col == "phase" else "right")
    for c in comparison.costs:
        t.add_row(safe(c.phase), *("-" if v is None else f"{v:.1f}" for v in (c.seconds_a, c.seconds_b)),
                  *("-" if v is None else str(v) for v in (c.simulations_a, c.simulations_b)))
    con.print(t)
