"""``rocas diff ACCIDENT.mcap REFERENCE.mcap``: find the initial deviating module."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from rocas._fs import check_writable
from rocas._json import dumps as json_dumps
from rocas.cli.console import Env, printable, prose, safe

if TYPE_CHECKING:
    from rocas.analysis.changepoints import ChangePointConfig
    from rocas.analysis.diff import DiffResult

HELP = "diff two recordings channel by channel and find the initial deviating module"


def _positive(value: str) -> float:
    try:
        x = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {value!r}") from None
    if not x > 0 or x != x or x == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {value!r}")
    return x


def _non_negative(value: str) -> float:
    try:
        x = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {value!r}") from None
    if not x >= 0 or x == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {value!r}")
    return x


def add_analysis_arguments(p: argparse.ArgumentParser) -> None:
    """Options shared by every command that runs a differential analysis."""
    g = p.add_argument_group("differential analysis")
    g.add_argument("--cmg", metavar="FILE", help="CMG JSON that supplies or overrides topology")
    g.add_argument("--control-channel", metavar="TOPIC", help="channel Algorithm 1 starts from")
    g.add_argument("--bin", type=_positive, default=0.1, metavar="S",
                   help="MDR bin width in seconds (default 0.1)")
    g.add_argument("--delta", type=_non_negative, default=3.0, metavar="S",
                   help="Algorithm 1 reaction window in seconds (default 3)")
    g.add_argument("--atol", type=_non_negative, default=0.0,
                   help="absolute tolerance for floating-point fields (default exact)")
    g.add_argument("--rtol", type=_non_negative, default=0.0,
                   help="relative tolerance for floating-point fields (default exact)")
    g.add_argument("--baseline", type=_positive, default=3.0, metavar="S",
                   help="seconds at the start whose MDR is taken as noise (default 3)")
    g.add_argument("--penalty-scale", type=_positive, default=3.0,
                   help="PELT penalty = scale * baseline variance * ln(n) (default 3)")
    g.add_argument("--penalty", type=_positive, default=None,
                   help="fixed PELT penalty (overrides the noise-derived one)")
    g.add_argument("--strict-bins", action="store_true",
                   help="pair messages only within their own bin (no adjacent-bin pairing)")
    g.add_argument("--smooth", type=int, default=5, metavar="BINS",
                   help="running-median width applied before PELT (default 5; 1 = off)")
    g.add_argument("--align", default="auto", metavar="HOW",
                   help="put the reference on the accident's clock: auto (by identical "
                   "messages, else by each channel's first message; default), first (each "
                   "file's first message), log-time (no offset), or a TOPIC (its first message "
                   "in each file)")
    g.add_argument("--ignore-field", action="append", default=[], metavar="PATTERN",
                   help="leave a field out of every message: PATH or TOPIC:PATH with shell "
                   "wildcards, e.g. 'header.stamp.*' (repeatable)")
    g.add_argument("--exact", action="store_true",
                   help="compare leaves exactly even when the runs differ from their first "
                   "messages (no learned tolerances or fields set aside)")
    g.add_argument("--allow-unrelated", action="store_true",
                   help="diff a pair that does not look like two runs of the same thing "
                   "(with a warning) instead of refusing it")


def change_point_config(args: argparse.Namespace) -> ChangePointConfig:
    from rocas.analysis.changepoints import ChangePointConfig

    if args.smooth < 1:
        from rocas.errors import UsageError

        raise UsageError(f"--smooth must be at least 1, got {args.smooth}")
    return ChangePointConfig(
        baseline_s=args.baseline, penalty_scale=args.penalty_scale, penalty=args.penalty,
        smooth_bins=args.smooth,
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("accident", metavar="ACCIDENT.mcap", help="the accident recording")
    p.add_argument("reference", metavar="REFERENCE.mcap", help="the accident-free reference")
    add_analysis_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--rrd", metavar="OUT.rrd", help="write a Rerun recording of the analysis")


def _num(x: float | None, fmt: str = ".3f") -> str:
    return "—" if x is None else format(x, fmt)


def render(result: DiffResult, env: Env) -> None:
    """The terminal report: Table 3 of the paper, the walk and the verdict."""
    from rich.table import Table
    from rich.text import Text

    from rocas.analysis.entries import entries_text

    out = env.out()
    p = result.pinpoint
    table = Table(title="Channels (MDR change points)", title_justify="left")
    for col, kw in (("channel", {}), ("writer", {}), ("t* [s]", {"justify": "right"}),
                    ("MDR before", {"justify": "right"}), ("MDR after", {"justify": "right"}),
                    ("change", {"justify": "right"})):
        table.add_column(col, **kw)
    on_path = set(p.path)
    for c in result.channels:
        change = "—"
        if c.mdr_after is not None and c.mdr_before is not None:
            change = f"{c.mdr_after - c.mdr_before:+.3f}"
        topic = Text(printable(c.topic), style="bold" if c.topic in on_path else "")
        if c.only_in:
            topic.append(printable(f" (only in {c.only_in})"), style="yellow")
        converges = c.change_points.converges_s
        if converges:
            topic.append(f" (converges at {converges[0]:.2f} s)", style="cyan")
        table.add_row(topic, safe(", ".join(c.writers)) or "—", _num(c.change_point_s, ".2f"),
                      _num(c.mdr_before), _num(c.mdr_after), change)
    out.print(table)
    out.print()
    for line in result.comparison_notes():
        prose(out, line)
    if p.fallback:
        prose(out, f"Note: {p.fallback}.")
    if p.deviating_module:
        prose(out, "Walk:  " + " -> ".join(p.path))
        out.print(Text.assemble("Initial deviating module: ",
                                (printable(p.deviating_module), "bold red")))
    else:
        out.print(Text(
            f"No deviating module: no module reachable from {printable(p.control_channel)} has a change "
            + ("point." if p.fallback else "point within the reaction window."), style="yellow"))
    e = result.entries
    if e is not None and e.deviating_module != p.deviating_module:
        prose(out, "Note: " + entries_text(
            {c.topic: c.entered_s for c in result.channels if c.entered_s is not None},
            e.deviating_module) + " (rocas analyze decides between the two with module "
            "substitution).")
    if p.exclusions:
        out.print()
        out.print("Other modules:")
        for m, why in sorted(p.exclusions.items()):
            prose(out, f"  {m}: {why}")


def run(args: argparse.Namespace, env: Env) -> int:
    from rocas.analysis.diff import diff
    from rocas.cli.inputs import load_cmg_file

    if args.rrd:
        check_writable(args.rrd)
    with env.progress("Reading both recordings", enabled=not args.json) as progress:
        result = diff(
            args.accident,
            args.reference,
            cmg=load_cmg_file(args.cmg) if args.cmg else None,
            control_channel_topic=args.control_channel,
            bin_s=args.bin,
            delta_s=args.delta,
            atol=args.atol,
            rtol=args.rtol,
            change_points=change_point_config(args),
            strict_bins=args.strict_bins,
            allow_unrelated=args.allow_unrelated,
            progress=progress.update if progress.enabled else None,
            align=args.align,
            ignore_fields=args.ignore_field,
            learn_noise=not args.exact,
        )
    for w in result.warnings:
        env.warn(w)
    if args.rrd:
        from rocas.viz.diff import write_diff_rrd

        write_diff_rrd(result, args.rrd)
    if args.json:
        env.stdout.write(json_dumps(result.to_json(), indent=2) + "\n")
    else:
        render(result, env)
        if args.rrd:
            env.out().print(f"Rerun recording: {safe(args.rrd)}")
    return 0
