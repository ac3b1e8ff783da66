"""Phase III: the differential analysis of the accident and its reference (Algorithm 1)."""

from __future__ import annotations

import json
import time

from rocas._fs import write_text_atomic
from rocas.pipeline.results import DiffPhaseResult
from rocas.pipeline.rundir import Run


def phase_diff(run: Run) -> DiffPhaseResult:
    """Diff accident.mcap against reference.mcap (diff.json holds the whole diff); returns the
    phase's result, the answer later phases may revise (never rewrite)."""
    from rocas.analysis.diff import diff

    done = run.get(DiffPhaseResult)
    if done is not None:
        return done
    t0 = time.perf_counter()
    result = diff(run.out / "accident.mcap", run.out / "reference.mcap", delta_s=run.cfg.delta_s)
    data = result.to_json()
    write_text_atomic(run.out / "diff.json", json.dumps(data, indent=1))
    summary = diff_result_of(data)
    run.finish(summary, time.perf_counter() - t0, 0)
    return summary


def diff_result_of(data: dict) -> DiffPhaseResult:  # type: ignore[type-arg]
    """The phase's result from a diff's JSON (:meth:`rocas.analysis.diff.DiffResult.to_json`)."""
    return DiffPhaseResult(deviating_module=data["deviating_module"], path=tuple(data["path"]),
                           control_channel=data["control_channel"], fallback=data["fallback"],
                           entries=data["entries"], warnings=tuple(data["warnings"]))
