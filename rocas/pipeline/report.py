"""The report of ``rocas analyze``: one JSON object, a markdown verdict, a terminal view."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rocas._fs import write_text_atomic
from rocas._json import dumps as json_dumps
from rocas._json import rounded
from rocas._text import markdown_text

EXPLANATIONS = {
    "misconfiguration": (
        "Changing {entity_phrase} avoids the accident, and the two executions first diverge in "
        "module {module}. Changing {params} in that module avoids the accident while the ego drives "
        "as before until {horizon:.1f} s: the accident is attributed to this configuration."),
    "no_configuration_fix": (
        "Changing {entity_phrase} avoids the accident and the executions first diverge in module "
        "{module_or_none}, but no configuration of {scope} within the search budget avoids it without "
        "changing the ego's earlier trajectory. This points to a missing feature or a limit of the "
        "system rather than a misconfiguration."),
    # the fix was found in the module module substitution names (cyber_phase.second_suspect)
    "misconfiguration_second_suspect": (
        "Changing {entity_phrase} avoids the accident, and the two executions first diverge in "
        "module {walk_named}, but no configuration of it avoids the accident; with ground truth "
        "from module {module} it does not happen, and changing {params} in that module avoids it "
        "while the ego drives as before until {horizon:.1f} s: the accident is attributed to this "
        "configuration."),
    # the fix was found in the module that reads the walk's module's output
    # (cyber_phase.second_suspect: substitution named the walk's module itself)
    "misconfiguration_consumer": (
        "Changing {entity_phrase} avoids the accident, and the two executions first diverge in "
        "module {walk_named}; with ground truth from it the accident does not happen, but no "
        "configuration of it avoids the accident. Changing {params} in module {module}, which "
        "reads its output, avoids it while the ego drives as before until {horizon:.1f} s: the "
        "accident is attributed to this configuration (a margin for errors of {walk_named})."),
    "no_reference": (
        "No small change of the world within the search budget avoids the accident, so there is no "
        "accident-free reference execution to compare with; the analysis stops here. A larger "
        "--budget may find one."),
    "not_reproduced": (
        "Replaying the recording did not reproduce the accident (see the replay figures), so the "
        "later phases would analyse a different execution; the analysis stops here."),
}
#: not_reproduced when there is nothing to reproduce, by source
NO_ACCIDENT = {
    "recording": ("The recording holds no accident (collision or emergency braking), and its replay "
                  "has none either: there is nothing to analyse."),
    "scenario": ("Simulating the scenario gives no accident (collision or emergency braking): "
                 "there is nothing to analyse."),
}


def build_report(state: dict[str, Any], accident: Any, verdict: str) -> dict[str, Any]:
    """The report object (``--json``) from a run directory's state."""
    done = state["done"]
    physical = done.get("physical", {})
    diff = done.get("diff", {})
    cyber = done.get("cyber", {})
    trig = (done.get("confidence") or {}).get("triggering_entity") or physical.get("triggering_entity")
    module = diff.get("deviating_module")
    mis = cyber.get("misconfiguration", [])
    from rocas.pipeline.config import REPORT_SETTINGS, AnalyzeConfig
    from rocas.pipeline.cyber import cyber_space
    from rocas.scenarios.model import DEFAULT_STACK

    searched = cyber.get("parameters")
    stack = done.get("replay", {}).get("stack", DEFAULT_STACK)
    total = len(cyber_space(None, {}, stack).variables)  # what --scope all searches
    default = AnalyzeConfig()
    report = {
        "verdict": verdict,
        "stack": stack,
        "explanation": "",
        # what produced this report (a run directory from before a setting existed used its
        # default); not the executor or workers, which do not change it
        "settings": {k: state["config"].get(k, getattr(default, k)) for k in REPORT_SETTINGS},
        "accident": accident.to_json() if accident is not None else None,
        "replay": done.get("replay"),
        "triggering_entity": trig,
        "deviating_module": module,
        "path": diff.get("path", []),
        # why the walk did not start at the control channel's change point (it had none)
        "walk_fallback": diff.get("fallback"),
        # the departures where content entered both runs, passed over (module substitution
        # disagreed with the module Algorithm 1 named at them): topic -> time [s]
        "entries_passed": diff.get("entries_passed"),
        # modules whose departures the walk went on past: module substitution cleared them
        "cleared_passed": diff.get("cleared_passed"),
        # why the walk went on past Algorithm 1's window toward the module substitution names
        "window_passed": diff.get("window_passed"),
        # the module Algorithm 1's walk named when no configuration of it avoided the accident
        # and the fix was found in the module module substitution names, or (when substitution
        # named the walk's module itself) in the module that reads its output
        "walk_named": diff.get("walk_named"),
        "suspect_reads_named": bool(diff.get("suspect_reads_named")),
        "confidence": done.get("confidence"),
        "misconfiguration": mis,
        "alternatives": cyber.get("alternatives", []),
        # the other shrunk fixes that avoid the accident, larger than the tolerance
        "other_fixes": cyber.get("other_fixes", []),
        "validation": done.get("validation"),
        "search_space": {"parameters_searched": searched, "parameters_total": total,
                         "reduction": (1 - searched / total) if searched else None,
                         "scope": cyber.get("scope")},
        "first_fix_evaluation": cyber.get("first_fix_evaluation"),
        "first_fix_batch_evaluations": cyber.get("first_fix_batch_evaluations"),
        "evaluations": dict(state["evaluations"]),
        # a result computed from less than the whole recording says so (docs/errors.md)
        "warnings": list((done.get("replay") or {}).get("warnings", []))
        + [f"diff: {w}" for w in _texts((done.get("diff") or {}).get("warnings"))],
        "complete": bool((done.get("replay") or {}).get("complete", True))
        and not _texts((done.get("diff") or {}).get("warnings")),
        "timings_s": dict(state["timings_s"]),
    }
    entity_phrase = "the world"
    if trig:
        props = ", ".join(f"{p['name']} from {_fmt(p['original'])} to {_fmt(p['mutated'])}"
                          for p in trig["properties"])
        entity_phrase = f"{trig['entity']} ({props})"
    params = ", ".join(f"{m['parameter']} from {_fmt(m['original'])} to {_fmt(m['mutated'])}" for m in mis)
    horizon = (accident.time_s - state["config"]["delta_s"]) if accident is not None else 0.0
    replay = done.get("replay") or {}
    if verdict == "not_reproduced" and _nothing_recorded(replay, accident):
        report["explanation"] = NO_ACCIDENT[replay.get("source", "recording")]
        return report
    suspect = cyber.get("second_suspect", {}).get("module")
    scope = f"module {module}" if cyber.get("scope") == "module" and module else "the whole ADS"
    if suspect:
        scope += f" nor of module {suspect} (the module module substitution names)"
    template = verdict
    if verdict == "misconfiguration" and diff.get("walk_named"):
        template = ("misconfiguration_consumer" if diff.get("suspect_reads_named")
                    else "misconfiguration_second_suspect")
    report["explanation"] = EXPLANATIONS[template].format(
        entity_phrase=entity_phrase, module=module, module_or_none=module or "(none found)",
        params=params or "-", horizon=max(horizon, 0.0), scope=scope,
        walk_named=diff.get("walk_named"))
    nearest = cyber.get("nearest_fix")
    if verdict == "no_configuration_fix" and nearest:
        changes = ", ".join(f"{k} to {_fmt(v)}" for k, v in nearest["mutation"].items())
        report["explanation"] += (
            f" The nearest one, {changes}, avoids the accident but changes the ego's trajectory "
            f"before {max(horizon, 0.0):.1f} s by h1 = {_fmt(nearest['objectives'][0])} m^2, over "
            f"the limit of {_fmt(state['config']['h1_limit_m2'])} m^2.")
    return report


def entries_passed_text(report: dict[str, Any]) -> str:
    """Why the walk passed over departures where content entered both runs (one clause)."""
    from rocas.analysis.entries import entries_text

    return (entries_text(report["entries_passed"], report["deviating_module"])
            + "; module substitution disagrees with the module named at those departures")


def walk_named_text(report: dict[str, Any]) -> str:
    """Why the deviating module is not the one Algorithm 1's walk named (one clause)."""
    if report.get("suspect_reads_named"):
        return (f"Algorithm 1's walk and module substitution named {report['walk_named']}, but no "
                f"configuration of it avoids the accident; {report['deviating_module']} reads its "
                "output, and its parameters hold the fix")
    return (f"Algorithm 1's walk named {report['walk_named']}, but no configuration of it avoids "
            f"the accident; module substitution names {report['deviating_module']}, whose "
            "parameters hold the fix")


def cleared_passed_text(report: dict[str, Any]) -> str:
    """Why the walk went on past modules module substitution cleared (one clause)."""
    cleared = " and ".join(report["cleared_passed"])
    return (f"the walk went on past {cleared}: with its ground truth the accident still "
            f"happens, while another module's ground truth avoids it; past it, the walk names "
            f"{report.get('walk_named') or report['deviating_module'] or 'no module'}")


def _nothing_recorded(replay: dict[str, Any], accident: Any) -> bool:
    """Whether the input holds no accident at all (rather than one replay missed)."""
    if replay.get("source") == "scenario":
        return replay.get("accident") is None
    if "recorded_accident" in replay:
        return replay["recorded_accident"] is None
    # a run directory from before the replay figures were kept: a replay is "reproduced"
    # without an accident only when the recording is accident-free too
    return bool(replay.get("reproduced")) and accident is None


def accident_text(acc: dict[str, Any] | None) -> str:
    """An accident as the report words it: "collision with obstacle_1 at 8.10 s"."""
    if not acc:
        return "no accident"
    other = f" with {acc['other']}" if acc.get("other") else ""
    at = f" at {acc['time_s']:.2f} s" if acc.get("time_s") is not None else ""
    return f"{acc['kind']}{other}{at}"


def replay_text(report: dict[str, Any]) -> str:
    """Phase I in one line: whether the accident was reproduced, and the ego's position error
    against the recording (the terminal's and report.md's replay line)."""
    rep = report.get("replay") or {}
    if rep.get("source") == "scenario":
        return f"simulated scenario ({accident_text(rep.get('accident'))})"
    rmse = rep.get("ego_rmse_m")
    if "recorded_accident" not in rep:  # a run directory from before these figures were kept
        acc = report.get("accident")
        text = ("reproduced" if rep.get("reproduced") else "not reproduced") + \
            (f" ({accident_text(acc)})" if acc else "")
        return text + (f", ego RMSE {rmse:.3f} m" if rmse is not None else "")
    recorded, replayed = rep["recorded_accident"], rep.get("accident")
    if recorded is None:
        text = "the recording holds no accident" + \
            (", nor does its replay" if replayed is None else f"; the replay has {accident_text(replayed)}")
        return text + f", ego RMSE over the whole run {rmse:.3f} m"
    if rep.get("only_emergency"):
        text = (f"the emergency before the recorded {accident_text(recorded)} reproduced "
                f"({accident_text(replayed)}), not the collision: the analysis explains the "
                "emergency")
    elif rep.get("reproduced"):
        text = f"reproduced ({accident_text(replayed)})"
    else:
        text = f"not reproduced (recorded {accident_text(recorded)}, replay {accident_text(replayed)})"
    return text + f", ego RMSE before the accident {rmse:.3f} m"


def settings_text(report: dict[str, Any]) -> str:
    """The settings that produced the report, in one line."""
    s = report.get("settings") or {}
    if not s:
        return ""
    return (f"seed {s['seed']}, budget {s['budget']}, population {s['population']}, "
            f"scope {s['scope']}, screening {'on' if s['screening'] else 'off'}, "
            f"delta {_fmt(s['delta_s'])} s, validation {s['validation_variants']} variants, "
            f"h1 limit {_fmt(s['h1_limit_m2'])} m^2, K {_fmt(s['k_suspicion'])} m, "
            f"{s['shrink_candidates']} fixes shrunk, "
            f"{s.get('alternate_references', 0)} alternate references, "
            f"second opinion {'on' if s.get('second_opinion') else 'off'}")


def confidence_text(report: dict[str, Any]) -> str:
    """The deviating module's confidence in one line: its level, the agreement of the
    references, the runner-up and the second opinion (rocas.pipeline.confidence)."""
    c = report.get("confidence") or {}
    if not c:
        return ""
    return f"{c['level']}: {c['note']}"


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def change(item: dict[str, Any], arrow: str = "→") -> str:
    """"name original → mutated" for a triggering property or a misconfigured parameter."""
    name = item.get("parameter", item.get("name"))
    return f"{name} {_fmt(item['original'])} {arrow} {_fmt(item['mutated'])}"


def other_fix_text(fix: dict[str, Any], arrow: str = "→") -> str:
    """One of the report's ``other_fixes``: its changes, size and the gap it kept."""
    notes = [f"h2 {fix['h2']:.4g}"]
    if fix.get("min_separation_m") is not None:
        notes.append(f"smallest gap {fix['min_separation_m']:.2f} m")
    if fix.get("stalled"):
        notes.append("the ego stays where the accident left it")
    return ", ".join(change(m, arrow) for m in fix["misconfiguration"]) + f" ({', '.join(notes)})"


def robust_text(report: dict[str, Any], arrow: str = "→") -> str:
    """The validation's robust value in words: the fix moved further the same way until it
    avoids clearly more of the perturbed variants (or why there is none)."""
    v = report.get("validation") or {}
    rob = v.get("robust_fix")
    if rob is None:
        return ("none: no stronger value avoids clearly more variants than the minimal fix"
                if v.get("stronger") else "not tried")
    originals = {m["parameter"]: m["original"] for m in report["misconfiguration"]}
    values = ", ".join(change({"parameter": k, "original": originals.get(k, "?"), "mutated": x}, arrow)
                       for k, x in rob["fix"].items())
    return f"{values}: accident-free in {100 * rob['success_rate']:.0f} % of the variants"


def sweep_text(validation: dict[str, Any]) -> str:
    """How far phase V's sweep of stronger values ran, when it stopped before its end ('' when
    it ran every value)."""
    done, whole = validation.get("simulations"), validation.get("simulations_without_stopping")
    if done is None or whole is None or done >= whole:
        return ""
    return (f"the sweep stopped once the robust value was settled ({done} of {whole} simulations; "
            "the values left out could not change it)")


def regression_text(validation: dict[str, Any]) -> str:
    """Where the regression test's sequential stop ended the original's runs, in words ('' when
    the original ran on every variant)."""
    test = validation.get("regression_test") or {}
    if not test.get("stopped_early"):
        return ""
    better = test["decision"] == "fix_better"
    return (f"the original stopped after {test['variants']} of {validation['variants']} variants: "
            f"the fix {'avoids' if better else 'causes'} the accident in "
            f"{test['fix_only'] if better else test['original_only']} of them where the original "
            f"{'does not' if better else 'avoids it'}, and the reverse in "
            f"{test['original_only'] if better else test['fix_only']} (sign test p = "
            f"{test['p_value']:.2g}, level {test['alpha_per_look']:.2g} per look)")


def _texts(value: Any) -> list[str]:
    """A stored list of warning lines (anything else: none)."""
    return [str(v) for v in value] if isinstance(value, list) else []


def markdown(report: dict[str, Any]) -> str:
    """The verdict as a markdown document (report.md, the Rerun verdict view). Every text made
    from data (names of modules, channels, entities, files) is escaped: no HTML or Markdown in a
    name acts (:func:`rocas._text.markdown_text`)."""
    md = markdown_text
    lines = [f"# rocas analyze: {report['verdict'].replace('_', ' ')}", "", md(report["explanation"]), ""]
    if report.get("warnings"):
        lines[3:3] = ["**Computed from less than the whole recording:**", "",
                      *(f"- {md(w)}" for w in report["warnings"]), ""]
    if report.get("settings"):
        lines.append(f"- **Settings**: {md(settings_text(report))}")
    if report.get("replay"):
        lines.append(f"- **Replay**: {md(replay_text(report))}")
    if report["accident"]:
        lines.append(f"- **Accident**: {md(accident_text(report['accident']))}")
    trig = report["triggering_entity"]
    if trig:
        for p in trig["properties"]:
            lines.append(f"- **Triggering entity**: {md(trig['entity'])} ({md(trig['kind'])}): "
                         f"{md(change(p))}")
    if report["deviating_module"]:
        lines.append(f"- **Deviating module**: {md(report['deviating_module'])} "
                     f"(walk: {md(' → '.join(report['path']))})")
        if report.get("walk_fallback"):
            lines.append(f"  - {md(report['walk_fallback'])}.")
        if report.get("entries_passed"):
            lines.append(f"  - {md(entries_passed_text(report))}.")
        if report.get("cleared_passed"):
            lines.append(f"  - {md(cleared_passed_text(report))}.")
        if report.get("window_passed"):
            lines.append(f"  - {md(report['window_passed'])}.")
        if report.get("walk_named"):
            lines.append(f"  - {md(walk_named_text(report))}.")
    if report.get("confidence"):
        lines.append(f"- **Confidence**: {md(confidence_text(report))}")
    for m in report["misconfiguration"]:
        lines.append(f"- **Misconfiguration**: {md(change(m))}")
    for alt in report.get("alternatives", []):
        lines.append("- **Nearly as small a fix**: "
                     + md(", ".join(change(m) for m in alt["misconfiguration"])) + f" (h2 {alt['h2']:.4g})")
    if report.get("other_fixes"):
        lines.append("- **Larger fixes that also avoid it**: " + md("; ".join(
            other_fix_text(f) for f in report["other_fixes"])))
    v = report["validation"]
    if v and v["variants"]:
        lines.append(f"- **Validation** ({v['variants']} perturbed variants): accident-free "
                     f"{100 * v['success_rate_original']:.0f} % with the original configuration, "
                     f"{100 * v['success_rate_fixed']:.0f} % with the fix"
                     + (" — **the fix makes things worse**" if v["fix_makes_it_worse"] else "")
                     + (f"; {md(regression_text(v))}" if regression_text(v) else ""))
        lines.append(f"- **Robust value**: {md(robust_text(report))}"
                     + (f"; {md(sweep_text(v))}" if sweep_text(v) else ""))
    t = report["timings_s"]
    lines.append("- **Time**: " + ", ".join(f"{k} {s:.1f} s" for k, s in t.items()))
    lines.append("- **Simulations**: " + ", ".join(f"{k} {n}" for k, n in report["evaluations"].items()))
    return "\n".join(lines) + "\n"


def write_report(out: Path, report: dict[str, Any]) -> dict[str, Any]:
    report = rounded(report)  # what report.json holds is what the caller gets (rocas._json)
    write_text_atomic(out / "report.json", json_dumps(report, indent=2))
    write_text_atomic(out / "report.md", markdown(report))
    return report
