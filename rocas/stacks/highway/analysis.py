"""The highway stack's own analysis entry points, which ``rocas analyze`` and ``rocas bench``
reach through the stack's declared capabilities (``analyze_recording`` and ``bench``,
:data:`rocas.stacks.base.CAPABILITIES`): a stack that drives in another simulator's world
analyses its accidents in that world, with its own co-mutation
(:func:`rocas.stacks.highway.comutation.analyze`).

A recording of this stack carries its scene (attachment), its parameter overrides and seed
(``rocas.ego``): one file is enough to simulate the accident again. The bench analyses each
catalog entry's accident (simulated at the entry's own seed, as its recording holds it) with
the searches seeded by the bench's seed, and scores it with :func:`rocas.pipeline.bench.score`
in the rows the built-in bench prints.
"""

from __future__ import annotations

import json
import os
import statistics
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rocas.errors import InputError, UsageError
from rocas.recording.topology import EGO_METADATA
from rocas.stacks.highway.accidents import CatalogEntry, entries, entry
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
        searches' seed.
    """

    source: str
    analysis: Analysis
    seed: int

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
                               "reference_modules": list(a.reference_modules)},
                "triggering_entity": {"entity": who, "property": prop} if who else None,
                "reference_change": dict(a.reference_change),
                "misconfiguration": [{"parameter": k, "original": original[k], "mutated": v}
                                     for k, v in sorted(a.fix.items())],
                "other_fixes": [dict(f) for f in a.alternatives],
                "validation": {"avoided": a.validated, "variants": a.variants},
                "timings_s": {k: round(v, 3) for k, v in a.seconds.items()},
                "simulations": dict(a.simulations)}

    def lines(self) -> list[str]:
        return [f"{self.source}: {self.verdict}", "  " + self.analysis.summary()]


def _executor(workers: int | None, executor: str) -> Any:
    from rocas.search.executor import make_executor

    if workers is not None and workers < 1:
        raise UsageError(f"--workers must be at least 1, not {workers}", "e.g. --workers 2")
    return make_executor(executor, workers or os.cpu_count() or 1)


def analyze_recording(path: str | os.PathLike[str], out: Path, *, seed: int = 0,
                      workers: int | None = None, executor: str = "local") -> HighwayReport:
    """The co-mutation on a recorded accident, its searches seeded by ``seed``; writes
    ``out/report.json``.

    Raises:
        InputError: not a highway recording; NotReproducedError: it has no accident.
    """
    scene, params, sim_seed = read_accident(path)
    ex = _executor(workers, executor)
    try:
        a = analyze(scene, params, sim_seed, executor=ex, search_seed=seed)
    finally:
        ex.close()
    report = HighwayReport(str(path), a, seed)
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.json").write_text(json.dumps(report.to_json(), indent=1, default=str))
    return report


def _row(e: CatalogEntry, a: Analysis, seconds: float) -> dict[str, Any]:
    """A scored row of the bench table (the shape :mod:`rocas.pipeline.bench` gives it)."""
    from rocas.pipeline.bench import score

    fixable = bool(e.parameter)
    expected = {"verdict": "misconfiguration" if fixable else "no_configuration_fix",
                "deviating_module": e.module or None,
                "parameters": [e.parameter] if fixable else [],
                "fixes": [{e.parameter: e.fix}] if fixable else [],
                "trigger_entity": None, "trigger_property": None, "trigger_replayed": None}
    report = HighwayReport(e.key, a, 0).to_json()
    who, prop = trigger(a)
    found = {"verdict": report["verdict"], "deviating_module": a.module,
             "parameters": [m["parameter"] for m in report["misconfiguration"]],
             "changes": report["misconfiguration"], "trigger_entity": who,
             "trigger_property": prop, "robust": None}
    if not fixable:
        # no module is at fault: a right answer names none, or only the diff's
        expected["deviating_module"] = found["deviating_module"] if not a.fix else None
    marks = score(expected, found)
    return {"id": e.key.split("_", 1)[0], "type": e.key.split("_", 1)[0], "title": e.title,
            "expected": expected, "found": found, "marks": marks, "hit": marks["hit"],
            "seconds": round(seconds, 2), "timings_s": dict(a.seconds),
            "simulations": dict(a.simulations), "diff_module": a.deviating_module,
            "confidence": a.confidence}


def _bench_one(chosen: Sequence[CatalogEntry], seed: int, ex: Any,
               progress: Callable[[str], None]) -> dict[str, Any]:
    rows = []
    for e in chosen:
        progress(f"{e.key}: analyze (seed {seed})")
        t0 = time.perf_counter()
        a = analyze(e.scene, e.params, e.seed, executor=ex, search_seed=seed)
        rows.append(_row(e, a, time.perf_counter() - t0))
    totals: dict[str, float] = {}
    for r in rows:
        for k, v in r["timings_s"].items():
            totals[k] = totals.get(k, 0.0) + v
    whole = sum(totals.values()) or 1.0
    return {"stack": "highway", "seed": seed, "entries": rows,
            "hits": sum(r["hit"] for r in rows), "total": len(rows), "agreement": None,
            "time_breakdown": {k: round(v / whole, 4) for k, v in totals.items()},
            "time_total_s": round(whole, 2), "search_space_reduction_mean": None,
            "scope_comparison": [], "instances": []}


def bench(ids: Sequence[str] | None, seeds: Sequence[int], *, workers: int | None = None,
          executor: str = "local", progress: Callable[[str], None] = lambda _: None
          ) -> dict[str, Any]:
    """The catalog (``ids``, default all) analysed and scored once per seed: each seed's
    bench (``runs``), the hits per seed and per entry, as :func:`rocas.pipeline.bench.
    run_bench_seeds` returns them.

    Raises:
        UsageError: an unknown entry, no seed, or a repeated seed.
    """
    if not seeds or len(set(seeds)) != len(seeds):
        raise UsageError("the bench needs distinct seeds", "e.g. --seeds 0,1,2")
    chosen = [entry(i) for i in ids] if ids else entries()
    ex = _executor(workers, executor)
    try:
        runs = [_bench_one(chosen, s, ex, progress) for s in seeds]
    finally:
        ex.close()
    from rocas.pipeline.bench import per_seed

    seconds = [r["seconds"] for res in runs for r in res["entries"]]
    return {"stack": "highway", **per_seed(seeds, runs), "agreement_per_seed": {},
            "median_seconds": statistics.median(seconds) if seconds else None,
            "min_seconds": min(seconds) if seconds else None}

