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
from pathlib import Path
from typing import Any

from rocas._lock import locked_directory
from rocas.pipeline.confidence import phase_confidence, start_second_opinion
from rocas.pipeline.config import AnalyzeConfig
from rocas.pipeline.cyber_phase import phase_cyber, start_screening
from rocas.pipeline.diff_phase import phase_diff
from rocas.pipeline.physical_phase import phase_physical
from rocas.pipeline.replay_phase import phase_replay
from rocas.pipeline.report import build_report, write_report
from rocas.pipeline.rundir import (
    Progress,
    Run,
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
) -> dict[str, Any]:
    """Run (or resume) the whole analysis; returns the report object (``--json``).

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
    state: dict[str, Any] = {"done": {}}
    try:
        with contextlib.ExitStack() as lock:
            held = out.is_dir()
            if held:  # before reading it: another process may be writing it
                lock.enter_context(locked_directory(out))
            state = prepare_run_dir(out, resume, label, cfg, digest)
            if not held:  # made just now
                lock.enter_context(locked_directory(out))
            _warm_up(ex, cfg)
            resumed = bool(state["done"])
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
        if not state["done"]:  # the run's state, which each finished phase adds to
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


def answer_text(run: Run, fix: dict[str, float], module: str | None) -> str:
    """The misconfiguration found, in words, before phase V checks it ("name original -> fix")."""
    space = run.cyber_space(module)
    return ", ".join(f"{name} {float(space.variable(name).original):.4g} -> {value:.4g}"  # type: ignore[arg-type]
                     for name, value in sorted(fix.items()))


def _analyze(run: Run, scenario: Scenario | None, recording: Path | None) -> dict[str, Any]:
    run.progress("replay", {})
    phase_replay(run, scenario, recording)
    replay = run.state["done"]["replay"]
    if not replay["reproduced"] or run.accident is None:
        return write_report(run.out, build_report(run.state, run.accident, "not_reproduced"))
    if uses_workers(run.executor, run.cfg) or max(1, getattr(run.executor, "workers", 1)) == 1:
        start_second_opinion(run)  # needs only the accident: on a worker while phase II runs
    physical = phase_physical(run)
    if "chosen" not in physical:
        return write_report(run.out, build_report(run.state, run.accident, "no_reference"))
    run.progress("diff", {})
    phase_diff(run)
    # the screening of the diff's module runs on a worker while the confidence phase runs here
    start_screening(run, run.state["done"]["diff"]["deviating_module"])
    run.progress("confidence", {})
    phase_confidence(run)  # may adopt the references' majority: read the diff's summary after it
    diff = run.state["done"]["diff"]
    cyber = phase_cyber(run, diff["deviating_module"])
    diff = run.state["done"]["diff"]  # the second suspect's module when its fix is reported
    if "fix" not in cyber:
        return write_report(run.out, build_report(run.state, run.accident, "no_configuration_fix"))
    if not run.done("validation"):
        run.progress("answer", {"module": diff["deviating_module"], "fix": answer_text(run, cyber["fix"],
                                                                                   diff["deviating_module"])})
    phase_validation(run, cyber["fix"], diff["deviating_module"])
    return write_report(run.out, build_report(run.state, run.accident, "misconfiguration"))


