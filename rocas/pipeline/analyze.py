"""``rocas analyze``: the paper's whole pipeline (sections 4-5) with a resumable run directory.

Phases, one module each: replay (:mod:`~rocas.pipeline.replay_phase`) -> physical mutation
(:mod:`~rocas.pipeline.physical_phase`) -> differential analysis
(:mod:`~rocas.pipeline.diff_phase`) -> cyber mutation, then minimisation
(:mod:`~rocas.pipeline.cyber_phase`) -> validation (:mod:`~rocas.pipeline.validation`). Every
phase writes its result into the run directory (:mod:`~rocas.pipeline.rundir`); searches
checkpoint every generation, so ``resume=True`` continues an interrupted run from its last
finished phase and generation without recomputing or losing anything. The report
(:mod:`~rocas.pipeline.report`) is built from the finished phases' results alone.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Mapping
from pathlib import Path

from rocas._lock import locked_directory
from rocas.pipeline.confidence import phase_confidence, start_second_opinion
from rocas.pipeline.config import AnalyzeConfig
from rocas.pipeline.cyber_phase import phase_cyber, start_screening
from rocas.pipeline.diff_phase import phase_diff
from rocas.pipeline.physical_phase import phase_physical
from rocas.pipeline.replay_phase import phase_replay
from rocas.pipeline.report import Report, build_report, write_report
from rocas.pipeline.rundir import (
    Progress,
    Run,
    RunState,
    damaged,
    noop,
    prepare_run_dir,
    remove_if_empty,
    source_identity,
)
from rocas.pipeline.validation import phase_validation
from rocas.scenarios.model import Scenario
from rocas.search.executor import Executor, make_executor


def analyze(
    source: str | os.PathLike[str] | Scenario,
    out: str | os.PathLike[str],
    cfg: AnalyzeConfig | None = None,
    *,
    resume: bool = False,
    progress: Progress = noop,
    executor: Executor | None = None,
) -> Report:
    """Run (or resume) the whole analysis; returns the report (``report.to_json()`` is the
    ``--json`` object).

    Args:
        source: an accident recording (replayed) or a Scenario (simulated as the accident).
        out: the run directory.
        cfg: settings (None: the defaults).
        resume: continue the analysis already in ``out``.
        progress: ``progress(phase, info)`` called as the phases advance.
        executor: an executor to use instead of ``cfg.executor``/``cfg.workers``.
    """
    out = Path(out)
    cfg = cfg if cfg is not None else AnalyzeConfig()
    scenario = source if isinstance(source, Scenario) else None
    recording = None if scenario is not None else Path(source)  # type: ignore[arg-type]
    label, digest = source_identity(source)
    own = executor is None
    ex = executor if executor is not None else make_executor(cfg.executor, cfg.workers)
    # the folders this call makes: removed again if nothing was finished in them
    made = [d for d in (out, *out.parents) if not d.exists()]
    state: RunState | None = None
    try:
        with contextlib.ExitStack() as lock:
            held = out.is_dir()
            if held:  # before reading it: another process may be writing it
                lock.enter_context(locked_directory(out))
            state = prepare_run_dir(out, resume, label, cfg, digest)
            if not held:  # made just now
                lock.enter_context(locked_directory(out))
            _warm_up(ex, cfg)
            resumed = bool(state.results)
            try:
                return _analyze(Run(out, cfg, ex, progress, state), scenario, recording)
            except (KeyError, TypeError, ValueError, AttributeError, IndexError, RecursionError) as exc:
                if not resumed:
                    raise
                # a run directory is someone's data: what read_state and the phases' own
                # checks let through is still damage, not a bug (the full story: --traceback)
                raise damaged(out, "a file", f"holds values of the wrong shape "
                                             f"({type(exc).__name__}: {exc})") from exc
    except BaseException:
        if own:  # an interruption or an error: end the workers without waiting for their tasks
            getattr(ex, "abort", ex.close)()
        if state is None or not state.results:  # the run's state, which each finished phase adds to
            remove_if_empty(made)
        raise
    finally:
        if own:
            ex.close()


def _warm_up(executor: Executor, cfg: AnalyzeConfig) -> None:
    """Start the executor's workers (when it has some to start) while the replay runs, if the
    analysis will use them: module substitution, started on one ahead of the confidence phase
    when there are alternate references to ask (start_second_opinion), or a validation whose
    waves give every worker PARALLEL_MIN_BATCH variants. Their start-up (a second or so
    of imports each) then overlaps the replay instead of delaying the first phase that needs
    them."""
    from rocas.pipeline.evaluate import prepare_worker

    warm_up = getattr(executor, "warm_up", None)
    workers = max(1, getattr(executor, "workers", 1))
    if warm_up is None or workers == 1:
        return
    if uses_workers(executor, cfg):
        warm_up(prepare_worker)


def uses_workers(executor: Executor, cfg: AnalyzeConfig) -> bool:
    """Whether the analysis starts the executor's workers anyway (see _warm_up): then module
    substitution can run on one of them ahead of the confidence phase at no start-up cost."""
    from rocas.pipeline.evaluate import PARALLEL_MIN_BATCH

    workers = max(1, getattr(executor, "workers", 1))
    return workers > 1 and bool(cfg.alternate_references
                                or 2 * cfg.validation_variants >= workers * PARALLEL_MIN_BATCH)


def answer_text(run: Run, fix: Mapping[str, float], module: str | None) -> str:
    """The misconfiguration found, in words, before phase V checks it ("name original -> fix")."""
    space = run.cyber_space(module)
    return ", ".join(f"{name} {float(space.variable(name).original):.4g} -> {value:.4g}"  # type: ignore[arg-type]
                     for name, value in sorted(fix.items()))


def _analyze(run: Run, scenario: Scenario | None, recording: Path | None) -> Report:
    """The phases in order, each reading its predecessors' results; the report's verdict is
    the phase the analysis stopped after."""
    run.progress("replay", {})
    replay = phase_replay(run, scenario, recording)
    if not replay.reproduced or run.accident is None:
        return _finish(run, "not_reproduced")
    if uses_workers(run.executor, run.cfg) or max(1, getattr(run.executor, "workers", 1)) == 1:
        start_second_opinion(run)  # needs only the accident: on a worker while phase II runs
    if phase_physical(run).chosen is None:
        return _finish(run, "no_reference")
    run.progress("diff", {})
    diff = phase_diff(run)
    # the screening of the diff's module runs on a worker while the confidence phase runs here
    start_screening(run, diff.deviating_module)
    run.progress("confidence", {})
    phase_confidence(run)  # may revise the diff's module: the current answer is read after it
    cyber = phase_cyber(run, run.answer().deviating_module)
    if cyber.fix is None:
        return _finish(run, "no_configuration_fix")
    module = run.answer().deviating_module  # the second suspect's when its fix is reported
    if not run.done("validation"):
        run.progress("answer", {"module": module, "fix": answer_text(run, cyber.fix, module)})
    phase_validation(run, cyber.fix, module)
    return _finish(run, "misconfiguration")


def _finish(run: Run, verdict: str) -> Report:
    """Build the report from the finished phases' results and write report.json/report.md."""
    return write_report(run.out, build_report(run.state, run.accident, verdict))
