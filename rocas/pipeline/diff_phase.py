"""Phase III: the differential analysis of the accident and its reference (Algorithm 1)."""

from __future__ import annotations

import json
import time
from typing import Any

from rocas._fs import write_text_atomic
from rocas.pipeline.rundir import Run


def phase_diff(run: Run) -> dict[str, Any]:
    from rocas.analysis.diff import diff

    if run.done("diff"):
        return run.state["done"]["diff"]
    t0 = time.perf_counter()
    result = diff(run.out / "accident.mcap", run.out / "reference.mcap", delta_s=run.cfg.delta_s)
    data = result.to_json()
    write_text_atomic(run.out / "diff.json", json.dumps(data, indent=1))
    summary = {"deviating_module": data["deviating_module"], "path": data["path"],
               "control_channel": data["control_channel"], "fallback": data["fallback"],
               "entries": data["entries"], "warnings": data["warnings"]}
    run.finish("diff", summary, time.perf_counter() - t0, 0)
    return summary
