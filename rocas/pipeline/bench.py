"""``rocas bench``: `rocas analyze` over the accident catalog, scored against its ground truth.

Prints the paper's Table 4 for our ADS (a hit/miss mark per column), the time breakdown per
phase, the search-space reduction (parameters searched against all, as in Table 2) and the
comparison of ``--scope module`` with ``--scope all`` (the paper's brute-force baseline):
simulations and time to the first fix, and whether the fix found is the documented one, each
with our screening search and with a plain genetic search without it, as the paper's
(``--no-screening``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from rocas.errors import UsageError
from rocas.pipeline.analyze import analyze
from rocas.pipeline.config import AnalyzeConfig
from rocas.pipeline.physical import PROPERTY_WORDS
from rocas.scenarios.model import DEFAULT_STACK


def _expected(truth: Any, replayed: bool = True) -> dict[str, Any]:
    """What the ground truth expects of an analysis; ``replayed``: the analysis replays a
    recording, whose actors are known by the ids a replay gives them (``truth.replayed_id``),
    rather than simulating the scenario, whose actors keep their own ids."""
    return {"verdict": "misconfiguration" if truth.fixable else "no_configuration_fix",
            "deviating_module": truth.module, "parameters": list(truth.parameters),
            "fixes": [dict(f) for f in truth.fixes],
            "trigger_entity": truth.trigger_entity, "trigger_property": truth.trigger_property,
            "trigger_replayed": truth.replayed_id if replayed else truth.trigger_entity}


def _found(report: dict[str, Any]) -> dict[str, Any]:
    trig = report.get("triggering_entity") or {}
    props = [p["name"].rsplit(".", 1)[-1] for p in trig.get("properties", [])]
    return {"verdict": report["verdict"], "deviating_module": report["deviating_module"],
            "parameters": [m["parameter"] for m in report["misconfiguration"]],
            "changes": [{"parameter": m["parameter"], "original": m["original"],
                         "mutated": m["mutated"]} for m in report["misconfiguration"]],
            "trigger_entity": trig.get("entity"), "trigger_property": props[0] if props else None,
            "robust": ((report.get("validation") or {}).get("robust_fix") or {}).get("fix")}


def _same_way(expected_fixes: list[dict[str, float]], changes: list[dict[str, Any]]) -> bool:
    """Whether some found change moves a documented fix's parameter the way that fix does
    (up or down from the original value)."""
    for ch in changes:
        delta = float(ch["mutated"]) - float(ch["original"])
        for fix in expected_fixes:
            if ch["parameter"] in fix and delta * (fix[ch["parameter"]] - float(ch["original"])) > 0:
                return True
    return False


def same_property(found: str | None, documented: str) -> bool:
    """Whether the physical variable part ``found`` (``speed_delta_mps``) is the property the
    catalog documents in words (``speed``; what follows the words in parentheses explains them)
    or by that part's own name, through rocas.pipeline.physical.PROPERTY_WORDS."""
    if found is None:
        return False
    words = documented.split("(", 1)[0].strip().lower()
    return words == found.lower() or words in PROPERTY_WORDS.get(found, ())


def score(expected: dict[str, Any], found: dict[str, Any]) -> dict[str, bool | None]:
    """Hit marks per column: verdict, module, parameter, trigger, and the overall hit (verdict
    and module, parameter when a fix exists, and trigger when it can be scored).

    The trigger is scored (entity and property) when the ground truth knows the id a replay
    gives the trigger entity (``trigger_replayed``); otherwise its mark is None. The property
    found is a physical variable's name part, the documented one words (same_property).

    The parameter counts when a found change moves a documented fix's parameter in the same
    direction as that fix: a "fix" that lowers an overtake margin so the ego races ahead of the
    truck avoids the replayed accident but is not the misconfiguration whose fix raises it."""
    verdict = expected["verdict"] == found["verdict"]
    module = expected["deviating_module"] == found["deviating_module"]
    param = _same_way(expected["fixes"], found["changes"]) \
        if expected["verdict"] == "misconfiguration" else not found["parameters"]
    trigger = None
    if expected.get("trigger_replayed"):
        trigger = (found["trigger_entity"] == expected["trigger_replayed"]
                   and same_property(found["trigger_property"], expected["trigger_property"]))
    return {"verdict": verdict, "module": module, "parameter": param, "trigger": trigger,
            "hit": verdict and module and param and trigger is not False}


#: the cyber searches ``--compare-scope`` sets side by side: (scope, screening)
_COMPARED = (("module", True), ("all", True), ("module", False), ("all", False))


def _scope_run(report: dict[str, Any], found: dict[str, Any], marks: dict[str, bool]) -> dict[str, Any]:
    """What one cyber search cost and found, for the scope comparison."""
    return {"first_fix_evaluation": report.get("first_fix_evaluation"),
            "first_fix_batch_evaluations": report.get("first_fix_batch_evaluations"),
            "cyber_evaluations": report["evaluations"].get("cyber"),
            "cyber_seconds": report["timings_s"].get("cyber"),
            "parameters": report["search_space"]["parameters_searched"],
            "found": found["parameters"],
            "changes": found["changes"],
            # the scope and the search decide the parameter, not the module (that is the diff's)
            "parameter_hit": marks["parameter"],
            "seconds": round(sum(report["timings_s"].values()), 2)}


def _confidence(report: dict[str, Any]) -> dict[str, Any] | None:
    """An analysis's confidence in short: level, agreement of the references, whether another
    reference was adopted, and module substitution's stance and module."""
    c = report.get("confidence")
    if not c:
        return None
    second = c.get("second_opinion") or {}
    return {"level": c["level"], "same": c["agreement"]["same"], "runs": c["agreement"]["runs"],
            "adopted": bool(c.get("adopted")), "stance": second.get("stance"),
            "substitution": second.get("module")}


def agreement_summary(rows: Sequence[dict[str, Any]]) -> dict[str, int]:
    """How many analyses ended stable, contested or unstable, how many adopted another
    reference, and how many the second opinion agreed with (or was consistent with)."""
    conf = [r["confidence"] for r in rows if r.get("confidence")]
    return {"analyses": len(conf),
            **{lvl: sum(c["level"] == lvl for c in conf) for lvl in ("stable", "contested", "unstable")},
            "adopted": sum(c["adopted"] for c in conf),
            "unanimous": sum(0 < c["runs"] == c["same"] for c in conf),
            "second_opinion_agrees": sum(c["stance"] in ("agrees", "consistent") for c in conf)}


def recording_for(key: str, directory: Path) -> Path | None:
    hits = sorted(directory.glob(f"{key.split('_', 1)[0]}*.mcap"))
    return hits[0] if hits else None


def _analyze(source: Any, out: Path, cfg: AnalyzeConfig) -> dict[str, Any]:
    """An analysis (resumed when ``out`` holds one) as its report.json object, which the
    bench scores."""
    return analyze(source, out, cfg, resume=(out / "state.json").exists()).to_json()


def run_bench(
    ids: Sequence[str] | None,
    out: Path,
    cfg: AnalyzeConfig,
    *,
    recordings: Path = Path("recordings"),
    compare_scope: int = 3,
    instances: int = 0,
    progress: Callable[[str], None] = lambda _: None,
    stack: str = DEFAULT_STACK,
) -> dict[str, Any]:
    """Analyze catalog entries of ``stack``'s catalog and score them; returns the ``--json``
    object."""
    from rocas.catalog import entries, entry

    chosen = [entry(i, stack) for i in ids] if ids else list(entries(stack))
    if not chosen:
        raise UsageError("the catalog is empty")
    out.mkdir(parents=True, exist_ok=True)
    rows, reports = _score_entries(chosen, out, cfg, recordings, progress)
    totals: dict[str, float] = {}
    for r in rows:
        for k, v in r["timings_s"].items():
            totals[k] = totals.get(k, 0.0) + v
    whole = sum(totals.values()) or 1.0
    reductions = [r["search_space"]["reduction"] for r in rows if r["search_space"]["reduction"] is not None]
    return {
        "stack": stack,
        "entries": rows,
        "hits": sum(r["hit"] for r in rows),
        "total": len(rows),
        "agreement": agreement_summary(rows),
        "time_breakdown": {k: round(v / whole, 4) for k, v in totals.items()},
        "time_total_s": round(whole, 2),
        "search_space_reduction_mean": sum(reductions) / len(reductions) if reductions else None,
        "scope_comparison": _compare_scopes(chosen, rows, reports, out, cfg, recordings,
                                            compare_scope, progress),
        "instances": _instances(chosen, out, cfg, instances, progress) if instances else [],
    }


def _score_entries(chosen: Sequence[Any], out: Path, cfg: AnalyzeConfig, recordings: Path,
                   progress: Callable[[str], None]
                   ) -> tuple[list[dict[str, Any]], dict[str, dict[str, Any]]]:
    """Analyze each entry (its recording, or its scenario simulated) and score it against its
    ground truth: the rows of the table, and each entry's report (by key)."""
    rows: list[dict[str, Any]] = []
    reports: dict[str, dict[str, Any]] = {}
    for e in chosen:
        rec = recording_for(e.key, recordings)
        progress(f"{e.id}: analyze {rec or e.key + ' (simulated)'}")
        report = _analyze(rec if rec is not None else e.scenario, out / e.key, cfg)
        # the phases' own times, which a resumed run keeps (its wall time would be the resume's)
        seconds = sum(report["timings_s"].values())
        reports[e.key] = report
        exp, fnd = _expected(e.truth, replayed=rec is not None), _found(report)
        marks = score(exp, fnd)
        rows.append({"id": e.key.split("_", 1)[0], "type": e.id, "title": e.truth.title,
                     "expected": exp, "found": fnd, "marks": marks, "hit": marks["hit"],
                     "seconds": round(seconds, 2), "timings_s": report["timings_s"],
                     "evaluations": report["evaluations"], "search_space": report["search_space"],
                     "first_fix_evaluation": report.get("first_fix_evaluation"),
                     "first_fix_batch_evaluations": report.get("first_fix_batch_evaluations"),
                     "confidence": _confidence(report)})
    return rows, reports


def _compare_scopes(chosen: Sequence[Any], rows: list[dict[str, Any]],
                    reports: dict[str, dict[str, Any]], out: Path, cfg: AnalyzeConfig,
                    recordings: Path, compare_scope: int, progress: Callable[[str], None]
                    ) -> list[dict[str, Any]]:
    """The first ``compare_scope`` fixable entries whose module was found, analysed again with
    each cyber search of _COMPARED (without validation: what is compared is the search)."""
    comparison = []
    fixable = [r for r in rows if r["expected"]["verdict"] == "misconfiguration"
               and r["found"]["deviating_module"]][:compare_scope]
    for r in fixable:
        e = next(x for x in chosen if x.key.startswith(r["id"]))
        rec = recording_for(e.key, recordings)
        runs = {("module", cfg.screening): _scope_run(reports[e.key], r["found"], r["marks"])}
        for scope, screening in _COMPARED:
            if (scope, screening) in runs:
                continue
            label = f"--scope {scope}" + ("" if screening else " --no-screening")
            progress(f"{e.id}: {label}")
            sub = out / f"{e.key}.{scope}{'' if screening else '.plain'}"
            rep = _analyze(rec if rec is not None else e.scenario, sub,
                           replace(cfg, scope=scope, screening=screening, validation_variants=0))
            fnd = _found(rep)
            runs[(scope, screening)] = _scope_run(rep, fnd, score(r["expected"], fnd))
        comparison.append({"id": r["id"], "module": runs[("module", True)], "all": runs[("all", True)],
                           "plain": {"module": runs[("module", False)], "all": runs[("all", False)]}})
    return comparison


def _instances(chosen: Sequence[Any], out: Path, cfg: AnalyzeConfig, instances: int,
               progress: Callable[[str], None]) -> list[dict[str, Any]]:
    """Per entry, ``instances`` generated variants analysed and scored (accuracy per type)."""
    from rocas.catalog import generate_instances

    per_type = []
    for e in chosen:
        inst = generate_instances(e, instances, seed=cfg.seed)
        hits = 0
        for k, (seed, scenario) in enumerate(inst.instances):
            progress(f"{e.id}: instance {k + 1}/{len(inst.instances)}")
            rep = _analyze(scenario, out / "instances" / f"{e.key}_{seed}", cfg)
            hits += score(_expected(e.truth, replayed=False), _found(rep))["hit"]
        per_type.append({"type": e.id, "tried": inst.tried, "crashed": inst.crashed,
                         "fixable": e.truth.fixable, "fix_holds": inst.fix_holds,
                         "analyzed": len(inst.instances), "hits": hits,
                         "accuracy": hits / len(inst.instances) if inst.instances else None})
    return per_type


def run_bench_seeds(
    ids: Sequence[str] | None,
    out: Path,
    cfg: AnalyzeConfig,
    seeds: Sequence[int],
    **kwargs: Any,
) -> dict[str, Any]:
    """:func:`run_bench` once per seed in ``seeds`` (run directories under ``out/seed-S``);
    returns the ``--json`` object: each seed's bench (``runs``), the hits per seed, and per
    entry the seeds it hit at (an answer that changes with the seed is not an answer)."""
    if not seeds:
        raise UsageError("--seeds needs at least one seed", "e.g. --seeds 0,1,2")
    if len(set(seeds)) != len(seeds):
        raise UsageError(f"--seeds repeats a seed: {','.join(map(str, seeds))}", "name each seed once")
    runs = [run_bench(ids, out / f"seed-{s}", replace(cfg, seed=s), **kwargs) for s in seeds]
    seconds = sorted(r["seconds"] for res in runs for r in res["entries"])
    return {"stack": kwargs.get("stack", DEFAULT_STACK), **per_seed(seeds, runs),
            "agreement_per_seed": {str(s): agreement_summary(res["entries"])
                                   for s, res in zip(seeds, runs, strict=True)},
            "median_seconds": seconds[len(seconds) // 2] if seconds else None}


def per_seed(seeds: Sequence[int], runs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The part of the ``--seeds`` object every stack's bench shares: the seeds, each seed's
    bench (``runs``), the hits per seed, and per entry the seeds it hit at and what it found."""
    per_entry: dict[str, dict[str, Any]] = {}
    for s, res in zip(seeds, runs, strict=True):
        for r in res["entries"]:
            row = per_entry.setdefault(r["id"], {"id": r["id"], "type": r["type"], "hits": {},
                                                 "found": {}})
            row["hits"][str(s)] = r["hit"]
            row["found"][str(s)] = {"module": r["found"]["deviating_module"],
                                    "parameters": r["found"]["parameters"],
                                    "trigger": r["found"]["trigger_entity"]}
    return {"seeds": list(seeds), "runs": list(runs),
            "hits_per_seed": {str(s): res["hits"] for s, res in zip(seeds, runs, strict=True)},
            "total": runs[0]["total"], "entries": list(per_entry.values()),
            "every_seed": sum(all(row["hits"].values()) for row in per_entry.values())}
