"""``rocas bench --stack highway``: the highway catalog analysed and scored once per seed,
which the CLI reaches through the stack's declared ``bench`` capability
(:data:`rocas.stacks.base.CAPABILITIES`).

Each catalog entry's accident is simulated at the entry's own seed (as its recording holds it)
and analysed by :func:`rocas.stacks.highway.comutation.analyze` with the searches seeded by the
bench's seed, every simulation on the executor named (``serial``, ``local`` worker processes,
``ray``): the answers do not depend on it, nor on the number of workers. Each answer is scored
with :func:`rocas.pipeline.bench.score` in the rows the built-in bench prints, with its seconds
and simulations per phase (physical, diff, cyber, validation).
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from rocas.errors import UsageError
from rocas.pipeline.bench import agreement_summary
from rocas.stacks.highway.accidents import CatalogEntry, entries, entry
from rocas.stacks.highway.analysis import HighwayReport, _executor, trigger
from rocas.stacks.highway.comutation import Analysis, Budget, analyze


def confidence_row(a: Analysis) -> dict[str, Any] | None:
    """The confidence in the bench row's shape (:func:`rocas.pipeline.bench._confidence`):
    level, references naming the answer's module of those diffed, substitution's stance and
    module; no other reference is ever adopted here."""
    if a.confidence is None:
        return None
    agree = a.agreement or {"same": 0, "runs": 0}
    return {"level": a.confidence, "same": agree["same"], "runs": agree["runs"],
            "adopted": False, "stance": a.stance,
            "substitution": None if a.substitution is None else a.substitution.module}


def row(e: CatalogEntry, a: Analysis, seconds: float) -> dict[str, Any]:
    """A scored row of the bench table (the shape :mod:`rocas.pipeline.bench` gives it), with
    ``timings_s`` [s] and ``simulations`` per phase."""
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
            "confidence": confidence_row(a)}


def _sums(rows: Sequence[Mapping[str, Any]], key: str) -> dict[str, float]:
    """Per phase, the rows' ``key`` table summed (phases in first-seen order)."""
    totals: dict[str, float] = {}
    for r in rows:
        for k, v in r[key].items():
            totals[k] = totals.get(k, 0) + v
    return totals


def bench_seed(chosen: Sequence[CatalogEntry], seed: int, ex: Any, *, budget: Budget | None = None,
               progress: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """One seed's bench over ``chosen`` on the executor ``ex``: the rows, the hits, the time
    share per phase (``time_breakdown``), and per phase the seconds [s] (``time_per_phase_s``)
    and simulations (``simulations_per_phase``) summed over the entries."""
    rows = []
    for e in chosen:
        progress(f"{e.key}: analyze (seed {seed})")
        t0 = time.perf_counter()
        a = analyze(e.scene, e.params, e.seed, executor=ex, budget=budget or Budget(),
                    search_seed=seed)
        rows.append(row(e, a, time.perf_counter() - t0))
    seconds = _sums(rows, "timings_s")
    whole = sum(seconds.values()) or 1.0
    return {"stack": "highway", "seed": seed, "entries": rows,
            "hits": sum(r["hit"] for r in rows), "total": len(rows),
            "agreement": agreement_summary(rows),
            "time_breakdown": {k: round(v / whole, 4) for k, v in seconds.items()},
            "time_total_s": round(whole, 2),
            "time_per_phase_s": {k: round(v, 2) for k, v in seconds.items()},
            "simulations_per_phase": {k: int(v) for k, v in _sums(rows, "simulations").items()},
            "search_space_reduction_mean": None, "scope_comparison": [], "instances": []}


def bench(ids: Sequence[str] | None, seeds: Sequence[int], *, workers: int | None = None,
          executor: str = "local", budget: Budget | None = None,
          progress: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """The catalog (``ids``, default all) analysed and scored once per seed, its simulations
    on ``executor`` with ``workers`` (default: all cores), each search within ``budget``
    (default :class:`rocas.stacks.highway.comutation.Budget`): each seed's bench (``runs``,
    :func:`bench_seed`), the hits per seed and per entry, as
    :func:`rocas.pipeline.bench.run_bench_seeds` returns them, and the median and least
    seconds per analysis.

    Raises:
        UsageError: an unknown entry or executor, fewer than one worker, no seed, or a
            repeated seed.
    """
    if not seeds or len(set(seeds)) != len(seeds):
        raise UsageError("the bench needs distinct seeds", "e.g. --seeds 0,1,2")
    chosen = [entry(i) for i in ids] if ids else entries()
    ex = _executor(workers, executor)
    try:
        runs = [bench_seed(chosen, s, ex, budget=budget, progress=progress) for s in seeds]
    finally:
        ex.close()
    from rocas.pipeline.bench import per_seed

    seconds = [r["seconds"] for res in runs for r in res["entries"]]
    return {"stack": "highway", **per_seed(seeds, runs), "agreement_per_seed": {},
            "executor": executor, "median_seconds": statistics.median(seconds) if seconds else None,
            "min_seconds": min(seconds) if seconds else None}
