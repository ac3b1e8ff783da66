"""The highway stack's own analysis of a recording, which ``rocas analyze`` reaches through
the stack's declared capability ``analyze_recording`` (:data:`rocas.stacks.base.CAPABILITIES`):
a stack that drives in another simulator's world analyses its accidents in that world, with its
own co-mutation (:func:`rocas.stacks.highway.comutation.analyze`). Its bench, scored in the
rows the built-in bench prints, is :mod:`rocas.stacks.highway.bench`.

A recording of this stack carries its scene (attachment), its parameter overrides and seed
(``rocas.ego``): one file is enough to simulate the accident again.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rocas.errors import InputError, UsageError
from rocas.recording.topology import EGO_METADATA
from rocas.stacks.highway.comutation import Analysis, analyze, physical_space
from rocas.stacks.highway.scene import Scene, scene_from_dict


def read_accident(path: str | os.PathLike[str]) -> tuple[Scene, dict[str, float], int]:
    """The scene, parameter overrides and seed a highway recording was made with.

    Raises:
        InputError: the file is no recording of this stack (no scene attachment, no
            ``rocas.ego`` metadata).
    """
    from rocas.recording.reader import Recording
    from rocas.stacks.highway.record import SCENE_ATTACHMENT

    rec = Recording(path).scan()
    meta = dict(rec.metadata).get(EGO_METADATA)
    data = rec.attachment(SCENE_ATTACHMENT)
    if data is None or meta is None:
        raise InputError(f"{path}: no highway scene in this recording",
                         "record it with python -m rocas.stacks.highway record")
    try:
        params = {str(k): float(v) for k, v in json.loads(meta.get("params", "{}")).items()}
        return scene_from_dict(json.loads(data), str(path)), params, int(meta.get("seed", "0"))
    except (ValueError, TypeError) as exc:
        raise InputError(f"{path}: unreadable highway scene or parameters ({exc})",
                         "record it again") from None


def trigger(a: Analysis) -> tuple[str | None, str | None]:
    """The triggering entity and property: the reference's largest change of one vehicle's
    property, as a share of that property's search range (an enum change counts as whole,
    :meth:`rocas.search.space.Variable.change`)."""
    if not a.reference_change:
        return None, None
    spans = {v.name: v for v in physical_space(a.accident.scene).variables}

    def share(name: str) -> float:
        v = spans[name]
        return v.change(a.reference_change[name])

    best = max(sorted(a.reference_change), key=share)
    who, prop = best.split(".", 1)
    return who, prop


@dataclass(frozen=True)
class HighwayReport:
    """One analysis as ``rocas analyze`` prints it (``lines``) and as ``--json`` (``to_json``).

    Attributes:
        source: the recording analysed; analysis: what the co-mutation found; seed: the
        searches' seed; rrd: its Rerun view (``RUN_DIR/analysis.rrd``, which ``rocas analyze
        --rrd`` copies and ``rocas view RUN_DIR`` opens), None when none was written.
    """

    source: str
    analysis: Analysis
    seed: int
    rrd: Path | None = None

    @property
    def verdict(self) -> str:
        return "misconfiguration" if self.analysis.fix else "no_configuration_fix"

    def to_json(self) -> dict[str, Any]:
        a = self.analysis
        who, prop = trigger(a)
        original = dict(a.accident.params)
        return {"stack": "highway", "source": self.source, "seed": self.seed,
                "verdict": self.verdict, "deviating_module": a.module,
                "diff_module": a.deviating_module, "searched_module": a.searched_module,
                "confidence": {"level": a.confidence, "agreement": a.agreement,
                               "reference_modules": list(a.reference_modules),
                               "substitution": None if a.substitution is None else {
                                   "stance": a.stance, **a.substitution.to_dict()}},
                "triggering_entity": {"entity": who, "property": prop} if who else None,
                "reference_change": dict(a.reference_change),
                "misconfiguration": [{"parameter": k, "original": original[k], "mutated": v}
                                     for k, v in sorted(a.fix.items())],
                "other_fixes": [dict(f) for f in a.alternatives],
                "validation": {"avoided": a.validated, "variants": a.variants},
                "timings_s": {k: round(v, 3) for k, v in a.seconds.items()},
                "simulations": dict(a.simulations)}

    def lines(self) -> list[str]:
        # one printed line per line of the summary (a newline in a line prints as "\n")
        return [f"{self.source}: {self.verdict}",
                *("  " + ln.strip() for ln in self.analysis.summary().splitlines())]


def _executor(workers: int | None, executor: str) -> Any:
    from rocas.search.executor import make_executor

    if workers is not None and workers < 1:
        raise UsageError(f"--workers must be at least 1, not {workers}", "e.g. --workers 2")
    return make_executor(executor, workers or os.cpu_count() or 1)


def analyze_recording(path: str | os.PathLike[str], out: Path, *, seed: int = 0,
                      workers: int | None = None, executor: str = "local") -> HighwayReport:
    """The co-mutation on a recorded accident, its searches seeded by ``seed``; writes
    ``out/report.json`` and its Rerun view ``out/analysis.rrd``
    (:func:`rocas.stacks.highway.view.write_analysis_rrd`: the run directory holds no
    recordings to draw it from later, and it takes a fraction of a second).

    Raises:
        InputError: not a highway recording; NotReproducedError: it has no accident;
        OutputError: the view cannot be written.
    """
    from rocas.stacks.highway.view import write_analysis_rrd

    scene, params, sim_seed = read_accident(path)
    ex = _executor(workers, executor)
    try:
        a = analyze(scene, params, sim_seed, executor=ex, search_seed=seed)
    finally:
        ex.close()
    out.mkdir(parents=True, exist_ok=True)
    write_analysis_rrd(out / "analysis.rrd", a, str(path))
    report = HighwayReport(str(path), a, seed, out / "analysis.rrd")
    (out / "report.json").write_text(json.dumps(report.to_json(), indent=1, default=str))
    return report
