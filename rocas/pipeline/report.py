"""The report of ``rocas analyze``: one view model (:class:`Report`) built once from the
phases' results, rendered as report.json, report.md, the terminal view and the Rerun verdict."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from rocas._fs import write_text_atomic
from rocas._json import dumps as json_dumps
from rocas._text import markdown_text
from rocas.pipeline.codec import omitted
from rocas.pipeline.results import (
    AccidentInfo,
    Agreement,
    AlternativeFix,
    ConfidenceResult,
    CyberResult,
    DiffPhaseResult,
    JsonCodec,
    ModuleRevision,
    OtherFix,
    ParameterChange,
    PhysicalResult,
    PropertyChange,
    ReferenceAnswer,
    ReplayResult,
    SecondOpinionRecord,
    TriggeringEntity,
    ValidationResult,
    current_answer,
    revisions_of,
)
from rocas.pipeline.rundir import RunState
from rocas.scenarios.model import DEFAULT_STACK

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


@dataclass(frozen=True)
class ReportSettings(JsonCodec):
    """The settings that produced a report (:data:`rocas.pipeline.config.REPORT_SETTINGS`;
    units as in :class:`~rocas.pipeline.config.AnalyzeConfig`)."""

    seed: int
    budget: int
    population: int
    scope: str
    screening: bool
    delta_s: float
    validation_variants: int
    h1_limit_m2: float
    k_suspicion: float
    shrink_candidates: int
    alternate_references: int
    second_opinion: bool


@dataclass(frozen=True, kw_only=True)
class ConfidenceSummary(JsonCodec):
    """The confidence as reported: the confidence phase's result (without its revisions),
    with the level and note a second suspect's fix revised (``with_suspect``)."""

    answers: tuple[ReferenceAnswer, ...]
    triggering_entity: TriggeringEntity | None = omitted()
    agreement: Agreement
    adopted: int
    second_opinion: SecondOpinionRecord | None = omitted()
    level: str
    note: str


@dataclass(frozen=True)
class SearchSpace(JsonCodec):
    """The cyber search's parameters against every parameter of the stack (``reduction``: the
    share left out, None when nothing was searched) and its scope."""

    parameters_searched: int | None
    parameters_total: int
    reduction: float | None
    scope: str | None


@dataclass(frozen=True)
class Report(JsonCodec):
    """The report of one analysis, built once from the phases' results (:func:`build_report`)
    and rendered as report.json (:meth:`to_json`, keys documented in docs/cli.md), report.md
    (:func:`markdown`), the terminal (``rocas.cli.analyze.render``) and the Rerun verdict.

    The answer's fields (``deviating_module``, ``path``, ``walk_fallback`` and what the walk
    passed over, ``walk_named``) are the current answer: the diff's with every revision
    applied (:func:`rocas.pipeline.results.current_answer`)."""

    verdict: str
    stack: str
    explanation: str
    settings: ReportSettings
    accident: AccidentInfo | None
    replay: ReplayResult | None
    triggering_entity: TriggeringEntity | None
    deviating_module: str | None
    path: tuple[str, ...]
    walk_fallback: str | None
    entries_passed: Mapping[str, float] | None
    cleared_passed: tuple[str, ...] | None
    window_passed: str | None
    walk_named: str | None
    suspect_reads_named: bool
    confidence: ConfidenceSummary | None
    misconfiguration: tuple[ParameterChange, ...]
    alternatives: tuple[AlternativeFix, ...]
    other_fixes: tuple[OtherFix, ...]
    validation: ValidationResult | None
    search_space: SearchSpace
    first_fix_evaluation: int | None
    first_fix_batch_evaluations: int | None
    evaluations: Mapping[str, int]
    warnings: tuple[str, ...]
    complete: bool
    timings_s: Mapping[str, float]


def build_report(state: RunState, accident: Any, verdict: str) -> Report:
    """The report from a run directory's state (the finished phases' results) and the
    accident (an :class:`~rocas.pipeline.evaluate.Accident` or None)."""
    results = state.results
    replay: ReplayResult | None = results.get("replay")
    physical: PhysicalResult | None = results.get("physical")
    cyber: CyberResult | None = results.get("cyber")
    conf: ConfidenceResult | None = results.get("confidence")
    diff: DiffPhaseResult | None = results.get("diff")
    revisions = revisions_of(results)
    answer = current_answer(diff, revisions) if diff is not None else None
    trig = (conf.triggering_entity if conf is not None else None) or (
        physical.triggering_entity if physical is not None else None)
    diff_warnings = answer.warnings if answer is not None else ()
    report = Report(
        verdict=verdict, stack=replay.stack if replay is not None else DEFAULT_STACK, explanation="",
        settings=_settings(state.config),
        accident=None if accident is None else AccidentInfo.from_json(accident.to_json()),
        replay=replay, triggering_entity=trig,
        deviating_module=answer.deviating_module if answer else None,
        path=answer.path if answer else (), walk_fallback=answer.fallback if answer else None,
        entries_passed=answer.entries_passed if answer else None,
        cleared_passed=answer.cleared_passed if answer else None,
        window_passed=answer.window_passed if answer else None,
        walk_named=answer.walk_named if answer else None,
        suspect_reads_named=bool(answer and answer.suspect_reads_named),
        confidence=None if conf is None else _confidence(conf, revisions),
        misconfiguration=(cyber.misconfiguration or ()) if cyber else (),
        alternatives=(cyber.alternatives or ()) if cyber else (),
        other_fixes=(cyber.other_fixes or ()) if cyber else (),
        validation=results.get("validation"),
        search_space=_search_space(cyber, replay.stack if replay is not None else DEFAULT_STACK),
        first_fix_evaluation=cyber.first_fix_evaluation if cyber else None,
        first_fix_batch_evaluations=cyber.first_fix_batch_evaluations if cyber else None,
        evaluations=dict(state.evaluations),
        warnings=tuple((replay.warnings or ()) if replay else ())
        + tuple(f"diff: {w}" for w in diff_warnings),
        complete=bool(replay is None or replay.complete is None or replay.complete) and not diff_warnings,
        timings_s=dict(state.timings_s))
    return replace(report, explanation=_explanation(report, cyber, state.config, accident))


def _settings(config: Mapping[str, Any]) -> ReportSettings:
    """The report's settings from a run's (a setting the run lacks had its default)."""
    from rocas.pipeline.config import REPORT_SETTINGS, AnalyzeConfig

    default = AnalyzeConfig()
    return ReportSettings(**{k: config.get(k, getattr(default, k)) for k in REPORT_SETTINGS})


def _confidence(conf: ConfidenceResult, revisions: list[ModuleRevision]) -> ConfidenceSummary:
    """The confidence as reported: the phase's, with a second suspect's revision applied."""
    from rocas.pipeline.confidence import with_suspect

    level, note = conf.level, conf.note
    for revision in revisions:
        if revision.reason == "second_suspect":
            level, note = with_suspect(level, note, revision)
    return ConfidenceSummary(answers=conf.answers, triggering_entity=conf.triggering_entity,
                             agreement=conf.agreement, adopted=conf.adopted,
                             second_opinion=conf.second_opinion, level=level, note=note)


def _search_space(cyber: CyberResult | None, stack: str) -> SearchSpace:
    """The parameters the cyber search searched against all the stack's (--scope all)."""
    from rocas.pipeline.cyber import cyber_space

    searched = cyber.parameters if cyber is not None else None
    total = len(cyber_space(None, {}, stack).variables)
    return SearchSpace(parameters_searched=searched, parameters_total=total,
                       reduction=(1 - searched / total) if searched else None,
                       scope=cyber.scope if cyber is not None else None)


def _explanation(report: Report, cyber: CyberResult | None, config: Mapping[str, Any],
                 accident: Any) -> str:
    """The verdict in words (EXPLANATIONS, NO_ACCIDENT)."""
    trig = report.triggering_entity
    entity_phrase = "the world"
    if trig:
        props = ", ".join(f"{p.name} from {_fmt(p.original)} to {_fmt(p.mutated)}"
                          for p in trig.properties)
        entity_phrase = f"{trig.entity} ({props})"
    params = ", ".join(f"{m.parameter} from {_fmt(m.original)} to {_fmt(m.mutated)}"
                       for m in report.misconfiguration)
    horizon = max((accident.time_s - config["delta_s"]) if accident is not None else 0.0, 0.0)
    replay = report.replay
    if report.verdict == "not_reproduced" and replay is not None and _nothing_recorded(replay):
        return NO_ACCIDENT[replay.source]
    module = report.deviating_module
    suspect = cyber.second_suspect.module if cyber and cyber.second_suspect else None
    scope = f"module {module}" if cyber and cyber.scope == "module" and module else "the whole ADS"
    if suspect:
        scope += f" nor of module {suspect} (the module module substitution names)"
    template = report.verdict
    if report.verdict == "misconfiguration" and report.walk_named:
        template = ("misconfiguration_consumer" if report.suspect_reads_named
                    else "misconfiguration_second_suspect")
    text = EXPLANATIONS[template].format(
        entity_phrase=entity_phrase, module=module, module_or_none=module or "(none found)",
        params=params or "-", horizon=horizon, scope=scope, walk_named=report.walk_named)
    nearest = cyber.nearest_fix if cyber else None
    if report.verdict == "no_configuration_fix" and nearest:
        changes = ", ".join(f"{k} to {_fmt(v)}" for k, v in nearest.mutation.items())
        text += (f" The nearest one, {changes}, avoids the accident but changes the ego's "
                 f"trajectory before {horizon:.1f} s by h1 = {_fmt(nearest.objectives[0])} m^2, "
                 f"over the limit of {_fmt(config['h1_limit_m2'])} m^2.")
    return text


def entries_passed_text(report: Report) -> str:
    """Why the walk passed over departures where content entered both runs (one clause)."""
    from rocas.analysis.entries import entries_text

    return (entries_text(dict(report.entries_passed or {}), report.deviating_module)
            + "; module substitution disagrees with the module named at those departures")


def walk_named_text(report: Report) -> str:
    """Why the deviating module is not the one Algorithm 1's walk named (one clause)."""
    if report.suspect_reads_named:
        return (f"Algorithm 1's walk and module substitution named {report.walk_named}, but no "
                f"configuration of it avoids the accident; {report.deviating_module} reads its "
                "output, and its parameters hold the fix")
    return (f"Algorithm 1's walk named {report.walk_named}, but no configuration of it avoids "
            f"the accident; module substitution names {report.deviating_module}, whose "
            "parameters hold the fix")


def cleared_passed_text(report: Report) -> str:
    """Why the walk went on past modules module substitution cleared (one clause)."""
    cleared = " and ".join(report.cleared_passed or ())
    return (f"the walk went on past {cleared}: with its ground truth the accident still "
            f"happens, while another module's ground truth avoids it; past it, the walk names "
            f"{report.walk_named or report.deviating_module or 'no module'}")


def _nothing_recorded(replay: ReplayResult) -> bool:
    """Whether the input holds no accident at all (rather than one replay missed)."""
    if replay.source == "scenario":
        return replay.accident is None
    return replay.recorded_accident is None


def accident_text(acc: AccidentInfo | None) -> str:
    """An accident as the report words it: "collision with obstacle_1 at 8.10 s"."""
    if not acc:
        return "no accident"
    other = f" with {acc.other}" if acc.other else ""
    at = f" at {acc.time_s:.2f} s" if acc.time_s is not None else ""
    return f"{acc.kind}{other}{at}"


def replay_text(report: Report) -> str:
    """Phase I in one line: whether the accident was reproduced, and the ego's position error
    against the recording (the terminal's and report.md's replay line)."""
    rep = report.replay
    assert rep is not None
    if rep.source == "scenario":
        return f"simulated scenario ({accident_text(rep.accident)})"
    rmse = rep.ego_rmse_m
    recorded, replayed = rep.recorded_accident, rep.accident
    if recorded is None:
        text = "the recording holds no accident" + \
            (", nor does its replay" if replayed is None else f"; the replay has {accident_text(replayed)}")
        return text + f", ego RMSE over the whole run {rmse:.3f} m"
    if rep.only_emergency:
        text = (f"the emergency before the recorded {accident_text(recorded)} reproduced "
                f"({accident_text(replayed)}), not the collision: the analysis explains the "
                "emergency")
    elif rep.reproduced:
        text = f"reproduced ({accident_text(replayed)})"
    else:
        text = f"not reproduced (recorded {accident_text(recorded)}, replay {accident_text(replayed)})"
    return text + f", ego RMSE before the accident {rmse:.3f} m"


def settings_text(report: Report) -> str:
    """The settings that produced the report, in one line."""
    s = report.settings
    return (f"seed {s.seed}, budget {s.budget}, population {s.population}, "
            f"scope {s.scope}, screening {'on' if s.screening else 'off'}, "
            f"delta {_fmt(s.delta_s)} s, validation {s.validation_variants} variants, "
            f"h1 limit {_fmt(s.h1_limit_m2)} m^2, K {_fmt(s.k_suspicion)} m, "
            f"{s.shrink_candidates} fixes shrunk, "
            f"{s.alternate_references} alternate references, "
            f"second opinion {'on' if s.second_opinion else 'off'}")


def confidence_text(report: Report) -> str:
    """The deviating module's confidence in one line: its level, the agreement of the
    references, the runner-up and the second opinion (rocas.pipeline.confidence)."""
    c = report.confidence
    if c is None:
        return ""
    return f"{c.level}: {c.note}"


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def change_text(name: str, original: Any, mutated: Any, arrow: str = "→") -> str:
    """"name original → mutated"."""
    return f"{name} {_fmt(original)} {arrow} {_fmt(mutated)}"


def change(item: PropertyChange | ParameterChange | Mapping[str, Any], arrow: str = "→") -> str:
    """"name original → mutated" for a triggering property or a misconfigured parameter (or
    one as report.json gives it: ``rocas bench`` prints its rows)."""
    if isinstance(item, Mapping):
        return change_text(item.get("parameter", item.get("name")), item["original"], item["mutated"],
                           arrow)
    name = item.parameter if isinstance(item, ParameterChange) else item.name
    return change_text(name, item.original, item.mutated, arrow)


def other_fix_text(fix: OtherFix, arrow: str = "→") -> str:
    """One of the report's ``other_fixes``: its changes, size and the gap it kept."""
    notes = [f"h2 {fix.h2:.4g}"]
    if fix.min_separation_m is not None:
        notes.append(f"smallest gap {fix.min_separation_m:.2f} m")
    if fix.stalled:
        notes.append("the ego stays where the accident left it")
    return ", ".join(change(m, arrow) for m in fix.misconfiguration) + f" ({', '.join(notes)})"


def robust_text(report: Report, arrow: str = "→") -> str:
    """The validation's robust value in words: the fix moved further the same way until it
    avoids clearly more of the perturbed variants (or why there is none)."""
    v = report.validation
    rob = v.robust_fix if v is not None else None
    if rob is None:
        return ("none: no stronger value avoids clearly more variants than the minimal fix"
                if v is not None and v.stronger else "not tried")
    originals = {m.parameter: m.original for m in report.misconfiguration}
    values = ", ".join(change_text(k, originals.get(k, "?"), x, arrow) for k, x in rob.fix.items())
    return f"{values}: accident-free in {100 * rob.success_rate:.0f} % of the variants"


def sweep_text(validation: ValidationResult) -> str:
    """How far phase V's sweep of stronger values ran, when it stopped before its end ('' when
    it ran every value)."""
    done, whole = validation.simulations, validation.simulations_without_stopping
    if done >= whole:
        return ""
    return (f"the sweep stopped once the robust value was settled ({done} of {whole} simulations; "
            "the values left out could not change it)")


def regression_text(validation: ValidationResult) -> str:
    """Where the regression test's sequential stop ended the original's runs, in words ('' when
    the original ran on every variant)."""
    test = validation.regression_test
    if test is None or not test.stopped_early:
        return ""
    better = test.decision == "fix_better"
    return (f"the original stopped after {test.variants} of {validation.variants} variants: "
            f"the fix {'avoids' if better else 'causes'} the accident in "
            f"{test.fix_only if better else test.original_only} of them where the original "
            f"{'does not' if better else 'avoids it'}, and the reverse in "
            f"{test.original_only if better else test.fix_only} (sign test p = "
            f"{test.p_value:.2g}, level {test.alpha_per_look:.2g} per look)")


def validation_text(v: ValidationResult) -> tuple[float, float]:
    """The validation's success rates in % (original, fixed)."""
    return 100 * (v.success_rate_original or 0.0), 100 * (v.success_rate_fixed or 0.0)


def markdown(report: Report) -> str:
    """The verdict as a markdown document (report.md, the Rerun verdict view). Every text made
    from data (names of modules, channels, entities, files) is escaped: no HTML or Markdown in a
    name acts (:func:`rocas._text.markdown_text`)."""
    md = markdown_text
    lines = [f"# rocas analyze: {report.verdict.replace('_', ' ')}", "", md(report.explanation), ""]
    if report.warnings:
        lines[3:3] = ["**Computed from less than the whole recording:**", "",
                      *(f"- {md(w)}" for w in report.warnings), ""]
    lines.append(f"- **Settings**: {md(settings_text(report))}")
    if report.replay:
        lines.append(f"- **Replay**: {md(replay_text(report))}")
    if report.accident:
        lines.append(f"- **Accident**: {md(accident_text(report.accident))}")
    lines += _markdown_answer(report)
    lines += _markdown_fixes(report)
    lines.append("- **Time**: " + ", ".join(f"{k} {s:.1f} s" for k, s in report.timings_s.items()))
    lines.append("- **Simulations**: " + ", ".join(f"{k} {n}" for k, n in report.evaluations.items()))
    return "\n".join(lines) + "\n"


def _markdown_answer(report: Report) -> list[str]:
    """report.md's triggering entity, deviating module (and why the walk went where it went)
    and confidence lines."""
    md = markdown_text
    lines = []
    trig = report.triggering_entity
    if trig:
        for p in trig.properties:
            lines.append(f"- **Triggering entity**: {md(trig.entity)} ({md(trig.kind)}): "
                         f"{md(change(p))}")
    if report.deviating_module:
        lines.append(f"- **Deviating module**: {md(report.deviating_module)} "
                     f"(walk: {md(' → '.join(report.path))})")
        lines += [f"  - {md(text)}." for text in walk_notes(report)]
    if report.confidence:
        lines.append(f"- **Confidence**: {md(confidence_text(report))}")
    return lines


def walk_notes(report: Report) -> list[str]:
    """Why the walk ended where it did, one clause each (the fallback, the departures it
    passed over, the module it named before a second suspect's fix)."""
    notes = []
    if report.walk_fallback:
        notes.append(report.walk_fallback)
    if report.entries_passed:
        notes.append(entries_passed_text(report))
    if report.cleared_passed:
        notes.append(cleared_passed_text(report))
    if report.window_passed:
        notes.append(report.window_passed)
    if report.walk_named:
        notes.append(walk_named_text(report))
    return notes


def _markdown_fixes(report: Report) -> list[str]:
    """report.md's misconfiguration, other fixes, validation and robust value lines."""
    md = markdown_text
    lines = [f"- **Misconfiguration**: {md(change(m))}" for m in report.misconfiguration]
    for alt in report.alternatives:
        lines.append("- **Nearly as small a fix**: "
                     + md(", ".join(change(m) for m in alt.misconfiguration)) + f" (h2 {alt.h2:.4g})")
    if report.other_fixes:
        lines.append("- **Larger fixes that also avoid it**: " + md("; ".join(
            other_fix_text(f) for f in report.other_fixes)))
    v = report.validation
    if v and v.variants:
        orig, fixed = validation_text(v)
        lines.append(f"- **Validation** ({v.variants} perturbed variants): accident-free "
                     f"{orig:.0f} % with the original configuration, {fixed:.0f} % with the fix"
                     + (" — **the fix makes things worse**" if v.fix_makes_it_worse else "")
                     + (f"; {md(regression_text(v))}" if regression_text(v) else ""))
        lines.append(f"- **Robust value**: {md(robust_text(report))}"
                     + (f"; {md(sweep_text(v))}" if sweep_text(v) else ""))
    return lines


def write_report(out: Path, report: Report) -> Report:
    """Write report.json (the view model's JSON) and report.md; returns ``report``."""
    # floats without accumulated rounding noise (rocas._json); the state keeps them exact
    write_text_atomic(out / "report.json", json_dumps(report.to_json(), indent=2))
    write_text_atomic(out / "report.md", markdown(report))
    return report
