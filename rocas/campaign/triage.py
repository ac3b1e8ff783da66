"""``rocas triage``: analyse every accident of a campaign and group them by root cause.

Campaign directory::

    inputs.json       the accidents (name, file, kind, documented type) and the settings
    runs/<name>/      one ``rocas analyze`` run directory per accident (resumable)
    campaign.json     groups, accidents, failures, completeness and purity
    campaign.md       the same for people

Each accident is analysed by :func:`rocas.pipeline.analyze.analyze` in its own run directory,
so an interrupted campaign continues (``resume=True``) from the last finished phase, search
generation or validation slice of the accident under way, and finished accidents are read back
from their report.json (once their input and settings are checked to be the campaign's), not
resumed. One executor serves the whole campaign (a local pool or a Ray cluster is
started once). An accident whose analysis fails is listed with the error's one-line message,
never dropped; the groups then say they were made from fewer accidents than the campaign's.
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

from rocas._fs import write_text_atomic
from rocas._json import dumps as json_dumps
from rocas._json import rounded
from rocas._lock import locked_directory
from rocas._text import markdown_text
from rocas.campaign.grouping import documented_keys, group_accidents, root_cause_keys, scores
from rocas.campaign.inputs import CampaignInput
from rocas.errors import RocasError, UsageError
from rocas.pipeline.config import REPORT_SETTINGS, AnalyzeConfig
from rocas.search.executor import Executor, make_executor

#: progress(accident index, accident count, accident name, phase or "done", phase info)
CampaignProgress = Callable[[int, int, str, str, dict[str, Any]], None]


def _no_progress(i: int, n: int, name: str, phase: str, info: dict[str, Any]) -> None:
    pass


def triage(
    inputs: Sequence[CampaignInput],
    out: str | Path,
    cfg: AnalyzeConfig,
    *,
    resume: bool = False,
    progress: CampaignProgress = _no_progress,
    executor: Executor | None = None,
) -> dict[str, Any]:
    """Analyse every accident of ``inputs`` into ``out`` and group them; returns the
    ``campaign.json`` object (also written, with ``campaign.md``).

    Raises:
        UsageError: ``out`` holds a campaign and ``resume`` is False.
        KeyboardInterrupt: with ``kept`` saying what is kept (the finished accidents and the
            run directory of the one under way).
    """
    out = Path(out)
    if (out / "inputs.json").exists() and not resume:
        raise UsageError(f"campaign directory {out} already holds a campaign",
                         "continue it with --resume, or choose another --out")
    names = [i.name for i in inputs]
    if len(set(names)) != len(names):
        raise UsageError("two accidents of the campaign have the same name")
    (out / "runs").mkdir(parents=True, exist_ok=True)
    with locked_directory(out, "campaign directory"):  # a second triage into it is refused
        return _triage(inputs, out, cfg, progress, executor)


def _triage(inputs: Sequence[CampaignInput], out: Path, cfg: AnalyzeConfig,
            progress: CampaignProgress, executor: Executor | None) -> dict[str, Any]:
    settings = {k: getattr(cfg, k) for k in REPORT_SETTINGS}
    write_text_atomic(out / "inputs.json", json.dumps(
        {"settings": settings, "accidents": [_input_json(i) for i in inputs]}, indent=2) + "\n")
    own = executor is None
    ex = executor if executor is not None else make_executor(cfg.executor, cfg.workers)
    rows: list[dict[str, Any]] = []
    try:
        for k, item in enumerate(inputs):
            rows.append(_analyse_one(item, out, cfg, ex, k, len(inputs), progress))
            progress(k, len(inputs), item.name, "done", {"verdict": rows[-1].get("verdict")})
    except KeyboardInterrupt as exc:
        done = len(rows)
        exc.kept = (f"{done} of {len(inputs)} accidents are analysed in {out / 'runs'} and the "  # type: ignore[attr-defined]
                    f"one under way keeps its finished phases; continue with --resume")
        raise
    finally:
        if own:
            ex.close()
    campaign = rounded(build_campaign(rows, settings))  # what campaign.json holds, read back alike
    write_text_atomic(out / "campaign.json", json_dumps(campaign, indent=2) + "\n")
    write_text_atomic(out / "campaign.md", markdown(campaign))
    return campaign


def _input_json(i: CampaignInput) -> dict[str, Any]:
    d = asdict(i)
    d["path"] = str(i.path)
    return d


def _analyse_one(item: CampaignInput, out: Path, cfg: AnalyzeConfig, ex: Executor, k: int, n: int,
                 progress: CampaignProgress) -> dict[str, Any]:
    from rocas.pipeline.analyze import analyze

    run_dir = out / "runs" / item.name
    row: dict[str, Any] = {"name": item.name, "source": str(item.path), "kind": item.kind,
                           "run_dir": f"runs/{item.name}", "truth_type": item.truth_type,
                           "truth_title": item.truth_title}
    try:
        source: Any = item.path
        if item.kind == "scenario":
            from rocas.rollout import load_scenario

            source = load_scenario(str(item.path))
        report = _finished_report(run_dir, source, cfg)
        if report is None:
            report = analyze(source, run_dir, cfg, resume=(run_dir / "state.json").exists(),
                             progress=lambda phase, info: progress(k, n, item.name, phase, info),
                             executor=ex).to_json()  # the report.json a finished run holds
    except RocasError as exc:
        return {**row, "error": str(exc).splitlines()[0]}
    except (KeyboardInterrupt, MemoryError):
        raise
    except Exception as exc:  # a bug in one analysis must not cost the campaign the others
        return {**row, "error": f"internal error: {type(exc).__name__}: "
                                f"{str(exc).splitlines()[0] if str(exc) else ''}".rstrip(": ")}
    conf = report.get("confidence") or {}
    agreement = conf.get("agreement") or {}
    return {**row, "verdict": report["verdict"], "deviating_module": report.get("deviating_module"),
            "misconfiguration": [{k2: m[k2] for k2 in ("parameter", "original", "mutated")}
                                 for m in report.get("misconfiguration", [])],
            "triggering_entity": report.get("triggering_entity"),
            "root_causes": root_cause_keys(report),
            "documented_root_causes": _documented(item, report),
            "confidence": {"level": conf.get("level"), "same": agreement.get("same"),
                           "runs": agreement.get("runs"), "note": conf.get("note")} if conf else None,
            "complete": report.get("complete", True),
            "seconds": round(sum(report.get("timings_s", {}).values()), 2)}


def _finished_report(run_dir: Path, source: Any, cfg: AnalyzeConfig) -> dict[str, Any] | None:
    """The report of a finished analysis of ``source`` with ``cfg`` in ``run_dir``, read from
    its report.json (resuming it would re-simulate the accident and the references only to
    rebuild the same report), or None when it has not finished.

    Raises:
        UsageError: ``run_dir`` holds the analysis of another input or with other settings.
    """
    from rocas.pipeline.rundir import prepare_run_dir, source_identity

    path = run_dir / "report.json"
    if not path.is_file():
        return None
    label, digest = source_identity(source)
    prepare_run_dir(run_dir, True, label, cfg, digest)  # the same input and settings, or refused
    try:
        report = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None  # resuming says what is wrong with the run directory
    return report if isinstance(report, dict) and "verdict" in report else None


def _documented(item: CampaignInput, report: dict[str, Any]) -> list[str] | None:
    """The accident's root cause names that are its type's documented root cause
    (:func:`documented_keys`), or None when its type is not a catalog type (the documented
    module and fixes are the catalog entry's; a variant keeps its entry's)."""
    if item.truth_type is None:
        return None
    from rocas.catalog import entry

    try:
        truth = entry(item.truth_type).truth
    except UsageError:
        return None
    return documented_keys(report, truth.module, truth.fixes)


def build_campaign(rows: Sequence[dict[str, Any]], settings: dict[str, Any]) -> dict[str, Any]:
    """The campaign object from the accidents' rows (analysed and failed)."""
    analysed = [r for r in rows if "error" not in r]
    failed = [{"name": r["name"], "source": r["source"], "reason": r["error"],
               "truth_type": r["truth_type"]} for r in rows if "error" in r]
    keys = {r["name"]: r["root_causes"] for r in analysed}
    by_name = {r["name"]: r for r in analysed}
    groups = []
    for idx, g in enumerate(group_accidents([r["name"] for r in analysed], keys), start=1):
        members = [by_name[n] for n in g["accidents"]]
        levels = Counter((m["confidence"] or {}).get("level") or "none" for m in members)
        groups.append({"id": f"G{idx}", "root_cause": g["root_cause"],
                       "verdict": members[0]["verdict"], "count": len(members),
                       "accidents": g["accidents"], "by_alternative": g["by_alternative"],
                       "agreement": dict(sorted(levels.items())),
                       "types": dict(Counter(m["truth_type"] or "unknown" for m in members))})
    group_of = {n: g["id"] for g in groups for n in g["accidents"]}
    accidents = [{**r, "group": group_of.get(r["name"])} for r in rows if "error" not in r]
    documented = {r["name"]: r["documented_root_causes"] for r in analysed
                  if r.get("documented_root_causes") is not None}
    sc = scores(groups, {r["name"]: r["truth_type"] for r in analysed},
                documented if documented else None)
    for g in groups:
        g["documented"] = ((sc or {}).get("groups", {}).get(g["root_cause"]) or {}).get("documented")
    return {"settings": settings, "accidents_total": len(rows), "analysed": len(analysed),
            "failed": failed, "complete": not failed,
            "groups": groups, "accidents": accidents, "scores": sc}


def groups_signature(campaign: dict[str, Any]) -> list[tuple[str, tuple[str, ...]]]:
    """The campaign's grouping alone (root cause and members of each group): what two runs
    of one campaign on other executors must agree on."""
    return [(g["root_cause"], tuple(g["accidents"])) for g in campaign["groups"]]


def _pct(x: float | None) -> str:
    return "n/a" if x is None else f"{100 * x:.1f} %"


def markdown(c: dict[str, Any]) -> str:
    """campaign.md: the groups, the failures and the scores (every name from data escaped:
    :func:`rocas._text.markdown_text`)."""
    md = markdown_text
    lines = ["# rocas triage", "",
             f"{c['analysed']} of {c['accidents_total']} accidents analysed in "
             f"{len(c['groups'])} groups"
             + ("." if c["complete"] else f"; {len(c['failed'])} failed to analyse "
                "(the groups are made from the others)."), ""]
    lines += ["| group | root cause | accidents | agreement | documented types | documented root cause |",
              "|---|---|---|---|---|---|"]
    for g in c["groups"]:
        agree = ", ".join(f"{k} {v}" for k, v in g["agreement"].items())
        types = ", ".join(f"{k} {v}" for k, v in g["types"].items())
        doc = {True: "yes", False: "no"}.get(g.get("documented"), "")
        lines.append(f"| {md(g['id'])} | {md(g['root_cause'])} | {g['count']} | {md(agree)} | "
                     f"{md(types)} | {doc} |")
    lines.append("")
    if c["failed"]:
        lines += ["## Failed to analyse", ""]
        lines += [f"- {md(f['name'])} ({md(f['source'])}): {md(f['reason'])}" for f in c["failed"]]
        lines.append("")
    sc = c.get("scores")
    if sc:
        lines += ["## Against the documented answers", "",
                  f"Completeness {_pct(sc['completeness'])} (worst type {_pct(sc['worst_completeness'])}), "
                  f"purity {_pct(sc['purity'])} (worst group {_pct(sc['worst_purity'])}), over "
                  f"{sc['accidents_with_truth']} accidents with a documented type."
                  + (f" Root cause the documented one (module, parameter, direction): "
                     f"{sc['groups_documented']} of {sc['groups_with_truth']} groups, "
                     f"{sc['accidents_documented']} of {sc['accidents_with_truth']} accidents "
                     f"({_pct(sc['documented_share'])})." if "groups_documented" in sc else ""),
                  "",
                  "| type | accidents | in its largest group | groups |", "|---|---|---|---|"]
        for t, v in sc["types"].items():
            lines.append(f"| {md(t)} | {v['accidents']} | {v['in_largest']} ({_pct(v['completeness'])}) "
                         f"| {v['groups']} |")
        lines.append("")
    lines += ["## Accidents", "", "| accident | group | verdict | module | agreement | type |",
              "|---|---|---|---|---|---|"]
    for a in c["accidents"]:
        conf = a.get("confidence") or {}
        agree = f"{conf.get('level')} ({conf.get('same')}/{conf.get('runs')})" if conf else "n/a"
        lines.append(f"| {md(a['name'])} | {md(a['group'])} | {md(a['verdict'])} | "
                     f"{md(a['deviating_module'])} | {md(agree)} | {md(a['truth_type'] or '')} |")
    return "\n".join(lines) + "\n"
