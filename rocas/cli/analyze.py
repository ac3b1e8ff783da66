"""``rocas analyze ACCIDENT.mcap``: from an accident recording to its misconfiguration."""

from __future__ import annotations

import argparse
import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rocas._fs import check_parent_exists, check_writable, safe_component
from rocas._json import dumps as json_dumps
from rocas.cli.console import Env, safe
from rocas.cli.exit_codes import ExitStatus

if TYPE_CHECKING:
    from rocas.pipeline.report import Report

HELP = "find the triggering entity, the deviating module and the misconfiguration of an accident"


def add_search_arguments(p: argparse.ArgumentParser,
                         seeded: str = "the searches and the validation variants") -> None:
    """The options of an analysis that ``rocas bench`` passes on too (defaults as in
    :class:`rocas.pipeline.config.AnalyzeConfig`); ``seeded`` says what --seed seeds."""
    p.add_argument("--seed", type=int, default=0, help=f"seed of {seeded} (default 0)")
    p.add_argument("--budget", type=int, default=240,
                   help="simulations per search phase; the cyber phase's screening (up to four per "
                        "parameter) comes out of it, but at least one generation of new mutants "
                        "follows (default 240)")
    p.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    p.add_argument("--validation", type=int, default=200, metavar="K",
                   help="perturbed variants in the regression test (default 200)")
    p.add_argument("--no-screening", dest="screening", action="store_false",
                   help="start the cyber search without trying each parameter alone first "
                        "(a plain genetic search, as the paper's has no screening)")
    p.add_argument("--references", type=int, default=2, metavar="N",
                   help="also diff the accident against N other accident-free references and "
                        "report how many name the same module (default 2)")
    p.add_argument("--no-second-opinion", dest="second_opinion", action="store_false",
                   help="skip module substitution, the deviating module's second opinion")


def add_executor_arguments(p: argparse.ArgumentParser) -> None:
    """--executor and --address (the Ray cluster), shared with ``rocas triage``."""
    from rocas.search.executor import executor_names

    p.add_argument("--executor", default="local",
                   help=f"where simulations run: {', '.join(executor_names())} (default local)")
    p.add_argument("--address", metavar="ADDR", default=None,
                   help="with --executor ray: the cluster to join (default: RAY_ADDRESS, or a "
                        "local Ray)")


def executor_from_arguments(args: argparse.Namespace) -> Any:
    """The executor --executor/--address name when it is not the plain one of
    ``AnalyzeConfig.executor`` (a Ray cluster at an address), else None.

    Raises:
        UsageError: --address without --executor ray.
    """
    if args.address is None:
        return None
    if args.executor != "ray":
        from rocas.errors import UsageError

        raise UsageError("--address is for --executor ray", "add --executor ray, or drop --address")
    from rocas.search.ray_executor import RayExecutor

    return RayExecutor(args.workers, address=args.address)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("source", metavar="ACCIDENT.mcap",
                   help="accident recording (or a scenario file / example name with --scenario)")
    p.add_argument("--scenario", action="store_true",
                   help="SOURCE is a scenario (file or example name) to simulate as the accident")
    p.add_argument("--stack", metavar="NAME", default=None,
                   help="with --scenario: the stack that drives the ego (default: the scenario's; "
                        "a recording names its own)")
    p.add_argument("--out", metavar="RUN_DIR", help="run directory (default: runs/<name>)")
    add_search_arguments(p)
    p.add_argument("--population", type=int, default=24, help="individuals per generation (default 24)")
    p.add_argument("--scope", choices=("module", "all"), default="module",
                   help="cyber search over the deviating module (default) or every parameter")
    add_executor_arguments(p)
    p.add_argument("--stack-file", metavar="STACK.toml",
                   help="run every simulation through this external stack's command (its "
                        "'stack' must be the recording's; results cached in RUN_DIR/external)")
    p.add_argument("--delta", type=float, default=3.0, metavar="S", help="Algorithm 1 window (default 3)")
    p.add_argument("--resume", action="store_true", help="continue the analysis in RUN_DIR")
    p.add_argument("--replace", action="store_true",
                   help="start afresh: remove the analysis RUN_DIR holds first (only a rocas "
                        "run directory is removed)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no progress bars and no early 'found' line on stderr: only the result")
    p.add_argument("--rrd", metavar="OUT.rrd", help="write a Rerun recording of every phase")


def run(args: argparse.Namespace, env: Env) -> int:
    from rocas.pipeline.analyze import analyze
    from rocas.pipeline.config import AnalyzeConfig
    from rocas.pipeline.validation import validation_simulations

    cfg = AnalyzeConfig(seed=args.seed, budget=args.budget, population=args.population, scope=args.scope,
                        executor=args.executor, workers=args.workers, delta_s=args.delta,
                        validation_variants=args.validation, screening=args.screening,
                        alternate_references=args.references, second_opinion=args.second_opinion)
    if args.scenario:
        from rocas.rollout import load_scenario

        source: Any = load_scenario(args.source)
        if args.stack is not None:
            from rocas.rollout import with_stack

            source = with_stack(source, args.stack)
        name = source.name
    else:
        if args.stack is not None:
            from rocas.errors import UsageError

            raise UsageError("--stack goes with --scenario",
                             "a recording names its stack in its rocas.stack metadata")
        source = Path(args.source)
        if not source.exists():
            from rocas.errors import InputError

            raise InputError(f"no such file: {source}", "check the path")
        name = source.stem
        own = _own_analysis(source)
        if own is not None:
            return _run_own_analysis(own, args, env)
    # the name comes from the scenario or the file: one harmless component under runs/, never
    # a path of its own (an absolute name or ../.. would put the run anywhere)
    out = Path(args.out) if args.out else Path("runs") / safe_component(name)
    if args.out:
        check_parent_exists(out)  # the run directory is made; a mistyped folder above it is not
    if args.replace:
        if args.resume:
            from rocas.errors import UsageError

            raise UsageError("--replace and --resume contradict each other",
                             "--resume continues the analysis, --replace starts it afresh")
        remove_run_dir(out)
    if args.rrd:
        check_writable(args.rrd)  # before minutes of work, not after
    progress: Any = (_Quiet() if args.quiet else
                     _Progress(env, {"validation": validation_simulations(cfg.validation_variants)}))
    executor = executor_from_arguments(args)
    if args.stack_file:
        cfg = dataclasses.replace(cfg, stack=_use_stack_file(args.stack_file, source, out))
    try:
        with progress:
            report = analyze(source, out, cfg, resume=args.resume, progress=progress,
                             executor=executor)
            progress.settle(report.evaluations)
        if args.rrd:
            _write_rrd(args.rrd, out, report)
    except KeyboardInterrupt as exc:
        exc.kept = kept_after_interrupt(out, args.rrd)  # type: ignore[attr-defined]
        raise
    finally:
        if executor is not None:
            executor.close()
    if args.json:
        env.stdout.write(json_dumps(report.to_json(), indent=2) + "\n")
    else:
        render(report, out, env)
        if args.rrd:
            env.out().print(f"Rerun recording: {safe(args.rrd)}")
    return ExitStatus.NOT_REPRODUCED if report.verdict == "not_reproduced" else ExitStatus.SUCCESS


def remove_run_dir(out: Path) -> None:
    """``--replace``: remove the run directory ``out`` (holding its lock, so an analysis still
    writing it is not pulled from under it). Nothing happens when it does not exist.

    Raises:
        UsageError: ``out`` is not a rocas run directory (no state.json, and not empty), or
            another process is writing it.
    """
    import shutil

    from rocas._fs import is_temporary
    from rocas._lock import locked_directory
    from rocas.errors import UsageError

    if out.is_symlink():
        raise UsageError(f"{out} is a symbolic link: --replace removes only a run directory "
                         "itself", "give the directory it points to as --out")
    if not out.is_dir():
        return  # nothing to replace (a file of that name is refused as before)
    if not (out / "state.json").is_file() and any(not is_temporary(p) for p in out.iterdir()):
        raise UsageError(f"{out} is not a rocas run directory: --replace removes only those",
                         "choose another --out")
    with locked_directory(out):
        shutil.rmtree(out)


def _use_stack_file(path: str, source: Any, out: Path) -> str:
    """Register the stack file's external stack under its name (workers get it with their
    tasks) and return the name, which drives the analysis's simulations.

    Raises:
        UsageError: the file is unreadable or its command simulates another stack.
    """
    from rocas.errors import UsageError
    from rocas.stacks.external import ExternalStack
    from rocas.stacks.registry import register

    ext = ExternalStack.from_file(Path(path).resolve(), (out / "external").resolve())
    if isinstance(source, Path):

        wanted = _recording_stack(source)
    else:
        wanted = source.ego.stack
    if ext.stack != wanted:
        raise UsageError(f"{path}: its command simulates stack {ext.stack!r}, the accident's "
                         f"is {wanted!r}", f'declare stack = "{wanted}" in the stack file')
    register(ext, replace=True)
    return ext.name


def _recording_stack(path: Path) -> str:
    """The stack a recording names in its ``rocas.stack`` metadata (the default stack when it
    names none)."""
    from rocas.recording.formats import open_recording
    from rocas.recording.topology import STACK_METADATA
    from rocas.scenarios.model import DEFAULT_STACK

    meta = dict(open_recording(str(path)).scan().metadata)
    return str(meta.get(STACK_METADATA, {}).get("name", DEFAULT_STACK))


def _own_analysis(path: Path) -> Callable[..., Any] | None:
    """The recording's stack's own ``analyze_recording`` when the stack declares one (a stack
    that drives in another simulator's world analyses there; rocas.stacks.base.CAPABILITIES),
    else None. A recording that cannot be read here is left to the analysis, which reports
    why."""
    from rocas.errors import RocasError
    from rocas.stacks.registry import get_stack

    try:
        stack = get_stack(_recording_stack(path))
    except RocasError:
        return None
    return getattr(stack, "analyze_recording", None)


#: options of ``rocas analyze`` a stack's own analysis takes (the others are rocas's pipeline's)
_OWN_ANALYSIS_OPTIONS = ("source", "out", "seed", "workers", "executor", "json", "quiet", "rrd")


def _run_own_analysis(own: Callable[..., Any], args: argparse.Namespace, env: Env) -> int:
    """``rocas analyze`` of a recording whose stack analyses in its own world.

    Raises:
        UsageError: an option only rocas's own pipeline reads was given.
    """
    from rocas.cli.inputs import refuse_options_not_taken

    refuse_options_not_taken(args, add_arguments, [args.source], _OWN_ANALYSIS_OPTIONS,
                             "this recording's stack analyses in its own world",
                             unlisted=("source",))
    out = Path(args.out) if args.out else Path("runs") / safe_component(Path(args.source).stem)
    if args.out:
        check_parent_exists(out)
    if args.rrd:
        check_writable(args.rrd)  # before minutes of work, not after
    report = own(Path(args.source), out, seed=args.seed, workers=args.workers,
                 executor=args.executor)
    if args.rrd:
        _copy_own_rrd(report, args.rrd)
    if args.json:
        env.stdout.write(json_dumps(report.to_json(), indent=2) + "\n")
    else:
        for line in report.lines():
            for part in line.split("\n"):  # a report's line may hold several (a summary)
                env.out().print(safe(part))
        env.out().print(f"Run directory: {safe(str(out))}")
        if args.rrd:
            env.out().print(f"Rerun recording: {safe(args.rrd)}")
    return ExitStatus.SUCCESS


def _copy_own_rrd(report: Any, path: str) -> None:
    """``--rrd`` of a stack's own analysis: a copy of the view it wrote into its run directory
    (its report's ``rrd``; the highway stack's is ``RUN_DIR/analysis.rrd``).

    Raises:
        UsageError: the stack's analysis wrote no view.
    """
    import shutil

    from rocas._fs import atomic_path
    from rocas.errors import UsageError

    written = getattr(report, "rrd", None)
    if written is None or not Path(written).is_file():
        raise UsageError("this recording's stack wrote no Rerun view of its analysis",
                         "run it again without --rrd")
    with atomic_path(path) as tmp:
        shutil.copyfile(written, tmp)


def kept_after_interrupt(out: Path, rrd: str | None) -> str:
    """What an interrupted ``rocas analyze`` left in ``out``, read from the disk: the
    interrupt message's part in parentheses."""
    from rocas.pipeline.rundir import finished_phases

    done = finished_phases(out)
    if (out / "report.json").exists() and done:
        # the analysis had finished (or had been resumed to its end): only the .rrd is missing
        return (f"the analysis is complete in {out} (report.json)"
                + (f"; {rrd} was not written, run again with --resume --rrd {rrd}" if rrd else ""))
    checkpoints = sorted(p.name for p in out.glob("*.ckpt")) if out.is_dir() else []
    if not done and not checkpoints:
        return "no phase had finished, nothing was kept"
    kept = []
    if done:
        kept.append(f"finished phases ({', '.join(done)})")
    if checkpoints:
        kept.append(f"checkpoints of the phase under way ({', '.join(checkpoints)})")
    return f"{' and '.join(kept)} are kept in {out}; continue with --resume"


def _write_rrd(path: str, out: Path, report: Report) -> None:
    try:
        from rocas.viz.analysis import write_run_dir_rrd  # the full debugger layout
    except ImportError:
        write_run_dir_rrd = None
    if write_run_dir_rrd is not None:
        write_run_dir_rrd(path, out)
        return
    from rocas.analysis.diff import diff
    from rocas.viz.diff import write_diff_rrd

    if (out / "reference.mcap").exists():
        write_diff_rrd(diff(out / "accident.mcap", out / "reference.mcap",
                            delta_s=report.settings.delta_s), path)


class _Quiet:
    """``--quiet``: the progress callback that shows nothing."""

    def __enter__(self) -> _Quiet:
        return self

    def __exit__(self, *exc: Any) -> None:
        return None

    def __call__(self, phase: str, info: dict[str, Any]) -> None:
        return None

    def settle(self, evaluations: dict[str, int]) -> None:
        return None


class _Progress:
    """A rich progress bar per phase on stderr. A phase is finished (its bar filled, its clock
    stopped, its count shown as simulations run) when the next one starts or the run ends."""

    def __init__(self, env: Env, totals: dict[str, int]) -> None:
        self._totals = totals
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        self._p = Progress(TextColumn("{task.description:<12}"), BarColumn(),
                           TextColumn("{task.fields[count]:>9}"), TextColumn("{task.fields[info]}"),
                           TimeElapsedColumn(), console=env.err(), transient=False)
        self._tasks: dict[str, Any] = {}
        self._done: dict[str, int] = {}  # phase -> simulations counted so far
        self._best: dict[str, float] = {}  # phase -> best accident-free objective so far

    def __enter__(self) -> _Progress:
        self._p.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        if exc[0] is None:
            self._finish_all()
        self._p.__exit__(*exc)

    def _finish_all(self) -> None:
        for phase, task in self._tasks.items():
            if self._p.tasks[task].finished:
                continue
            n = self._done.get(phase)
            self._p.update(task, total=max(n or 1, 1), completed=max(n or 1, 1),
                           count=f"{n} sims" if n else "done")
            self._p.stop_task(task)

    def settle(self, evaluations: dict[str, int]) -> None:
        """End every bar on the count the report's "simulations" line gives for its phase.

        The bars count as the phases report; the report counts what each phase simulated in
        all, which for the cyber phase includes the shrinking of its fixes (the minimise bar's
        simulations) and for a resumed run the work done before the interruption."""
        search = self._done.get("cyber")
        for phase, n in evaluations.items():
            task = self._tasks.get(phase)
            if task is None:
                continue
            self._done[phase] = n
            info = self._p.tasks[task].fields.get("info", "")
            if phase == "cyber" and search is not None and n > search and "minimise" in self._tasks:
                info = f"{info}; search {search} + minimise {n - search}".lstrip("; ")
            self._p.update(task, total=max(n, 1), completed=max(n, 1), count=f"{n} sims",
                           info=info)
            self._p.stop_task(task)
        if "minimise" in self._tasks and "cyber" in evaluations and search is not None:
            task = self._tasks["minimise"]
            extra = evaluations["cyber"] - search
            if extra > 0:
                self._p.update(task, count=f"{extra} sims")

    def __call__(self, phase: str, info: dict[str, Any]) -> None:
        if phase == "answer":  # the answer before phase V checks it: said at once, above the bars
            self._p.console.print(f"[bold]found[/bold]: {safe(info['module'])} misconfigured, "
                                  f"{safe(info['fix'])} (validating the fix)", highlight=False)
            return
        if "planned" in info:  # a search's planned simulations, sent as it starts
            info = dict(info)
            self._totals[phase] = info.pop("planned")
        if phase not in self._tasks:
            self._finish_all()
            total = self._totals.get(phase)
            self._tasks[phase] = self._p.add_task(
                phase, total=total, info="", count=f"0/{total}" if total else "")
        task = self._tasks[phase]
        if not info:
            return
        if "generation" in info:
            n = info["evaluations"]
            self._done[phase] = n
            text = f"gen {info['generation']}, feasible {info['feasible']}"
            if info.get("best_feasible") is not None:
                self._best[phase] = min(self._best.get(phase, math.inf), info["best_feasible"])
            if phase in self._best:
                text += f", best {info.get('best_objective', 'objective')} {self._best[phase]:.3f}"
            self._p.update(task, completed=n, count=f"{n}/{self._totals.get(phase, '?')}", info=text)
        else:
            if phase == "validation" and "simulations" in info:
                info = dict(info)  # the count column shows the simulations, the text the rest
                total = self._done[phase] = info.pop("simulations")
                n = info.pop("evaluations", 0)
                self._p.update(task, total=total, completed=n, count=f"{n}/{total}")
            self._p.update(task, info=safe(", ".join(f"{k} {v}" for k, v in info.items())))


def render(report: Report, out: Path, env: Env) -> None:
    """A report in the shape of one row of the paper's Table 4, and its explanation."""
    from rich.panel import Panel
    from rich.table import Table

    t = Table(show_header=False, box=None, padding=(0, 1))
    t.add_column(style="bold")
    t.add_column()

    def row(label: str, text: str, markup: str = "") -> None:
        t.add_row(label, safe(text) + markup)  # names from data print as they read

    _render_facts(report, row)
    _render_answer(report, row)
    _render_fixes(report, row)
    _render_costs(report, out, row)
    con = env.out()
    con.print(t)
    con.print(Panel(safe(report.explanation), title="why", expand=False))


Row = Callable[..., None]


def _render_facts(report: Report, row: Row) -> None:
    """The verdict, the warnings, the replay and the accident."""
    from rocas.pipeline.report import accident_text, replay_text

    row("verdict", report.verdict.replace("_", " ")
        + ("" if report.complete else "  (from less than the whole recording)"))
    for w in report.warnings:
        row("warning", w)
    if report.replay:
        row("replay", replay_text(report))
    if report.accident:
        row("accident", accident_text(report.accident))


def _render_answer(report: Report, row: Row) -> None:
    """The triggering entity, the deviating module with its walk (and why the walk ended
    where it did) and the confidence."""
    from rocas.pipeline.report import change, confidence_text, walk_notes

    trig = report.triggering_entity
    if trig:
        for p in trig.properties:
            row("triggering entity", f"{trig.entity} ({trig.kind}): {change(p, '->')}")
    if report.deviating_module:
        walk = " -> ".join(report.path) or "-"
        row("deviating module", f"{report.deviating_module}   walk: {walk}")
        for text in walk_notes(report):
            row("", f"({text})")
    if report.confidence:
        row("confidence", confidence_text(report))


def _render_fixes(report: Report, row: Row) -> None:
    """The misconfiguration, the other fixes, the validation and the robust value."""
    from rocas.pipeline.report import (
        change,
        other_fix_text,
        regression_text,
        robust_text,
        sweep_text,
        validation_text,
    )

    for m in report.misconfiguration:
        row("misconfiguration", change(m, "->"))
    for alt in report.alternatives:
        row("nearly as small", ", ".join(change(m, "->") for m in alt.misconfiguration)
            + f"  (h2 {alt.h2:.4g})")
    for fix in report.other_fixes:
        row("larger fix", other_fix_text(fix, "->"))
    v = report.validation
    if v and v.variants:
        orig, fixed = validation_text(v)
        row("validation", f"{v.variants} variants: accident-free {orig:.0f} % "
            f"(original) vs {fixed:.0f} % (fixed)"
            + (f"; {regression_text(v)}" if regression_text(v) else ""),
            "  [red]fix makes it worse[/red]" if v.fix_makes_it_worse else "")
        row("robust value", robust_text(report, "->") + (f"; {sweep_text(v)}" if sweep_text(v) else ""))


def _render_costs(report: Report, out: Path, row: Row) -> None:
    """The search space, the time and simulations per phase, the settings, the run directory."""
    from rocas.pipeline.report import settings_text

    ss = report.search_space
    if ss.parameters_searched:
        row("search space", f"{ss.parameters_searched} of {ss.parameters_total} parameters "
            f"({100 * (ss.reduction or 0):.1f} % reduction)")
    row("time", ", ".join(f"{k} {s:.1f} s" for k, s in report.timings_s.items()))
    row("simulations", ", ".join(f"{k} {n}" for k, n in report.evaluations.items()))
    row("settings", settings_text(report))
    row("run directory", str(out))
