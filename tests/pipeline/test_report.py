"""The report's words for what the phases' results say."""

from dataclasses import replace

from rocas.pipeline.evaluate import Accident
from rocas.pipeline.report import build_report, markdown, replay_text
from rocas.pipeline.results import (
    CyberResult,
    DiffPhaseResult,
    ModuleRevision,
    ReplayResult,
    SearchSummary,
)
from rocas.pipeline.rundir import RunState


def _state(replay, **results):
    """A run state whose replay finished with ``replay`` (report.json's replay object, the
    stack defaulted) and whose other ``results`` are given as phase=result."""
    return RunState("x", {"delta_s": 3.0, "seed": 4},
                    results={"replay": ReplayResult.from_json({"stack": "ads", **replay}), **results},
                    timings_s={"replay": 0.5}, evaluations={"replay": 1})


def _diff(module, path=("/control", "control")):
    return DiffPhaseResult(deviating_module=module, path=tuple(path), control_channel="/control",
                           fallback=None, entries=None, warnings=())


def _cyber(**fields):
    base = {"module": "planning", "scope": "module", "parameters": 42, "generations": [],
            "evaluations": 10, "feasible": 0, "first_fix_evaluation": None,
            "first_fix_batch_evaluations": None}
    return CyberResult.from_json(base | fields)


SCENARIO = {"source": "scenario", "reproduced": True, "recorded_accident": None, "accident": None,
            "ego_rmse_m": 0.0}


def test_a_recording_without_an_accident_is_said_to_hold_none():
    clean = {"source": "recording", "reproduced": True, "recorded_accident": None,
             "accident": None, "ego_rmse_m": 0.0123, "compared_until_s": 20.0}
    report = build_report(_state(clean), None, "not_reproduced")
    assert "holds no accident" in report.explanation
    assert "did not reproduce" not in report.explanation
    assert replay_text(report) == ("the recording holds no accident, nor does its replay, "
                                   "ego RMSE over the whole run 0.012 m")
    assert "- **Replay**: the recording holds no accident" in markdown(report)


def test_an_accident_the_replay_missed_is_not_reproduced():
    recorded = {"kind": "collision", "time_s": 5.0, "other": "obstacle_2"}
    missed = {"source": "recording", "reproduced": False, "recorded_accident": recorded,
              "accident": None, "ego_rmse_m": 1.5, "compared_until_s": 5.0}
    report = build_report(_state(missed), None, "not_reproduced")
    assert "did not reproduce the accident" in report.explanation
    assert replay_text(report) == ("not reproduced (recorded collision with obstacle_2 at 5.00 s, "
                                   "replay no accident), ego RMSE before the accident 1.500 m")


def test_the_replay_line_of_a_reproduced_accident():
    acc = {"kind": "emergency", "time_s": 10.15, "other": None}
    rep = {"source": "recording", "reproduced": True, "recorded_accident": acc, "accident": acc,
           "ego_rmse_m": 0.0351, "compared_until_s": 10.2}
    report = build_report(_state(rep), Accident("emergency", 10.15, None), "no_reference")
    assert replay_text(report) == \
        "reproduced (emergency at 10.15 s), ego RMSE before the accident 0.035 m"
    # a setting the run's config lacks is reported at its default
    assert report.settings.seed == 4 and report.settings.budget == 240


def test_a_fix_that_changes_the_earlier_trajectory_is_named_as_the_nearest_not_as_a_fix():
    acc = {"kind": "collision", "time_s": 9.0, "other": "obstacle_1"}
    rep = {"source": "recording", "reproduced": True, "recorded_accident": acc, "accident": acc,
           "ego_rmse_m": 0.02, "compared_until_s": 9.0}
    state = _state(rep, diff=_diff("planning"), cyber=_cyber(nearest_fix={
        "mutation": {"planning.max_accel_mps2": 0.4}, "objectives": [3.5, 1.2], "constraint": -0.2,
        "generation": 2}))
    state.config["h1_limit_m2"] = 1.0
    report = build_report(state, Accident("collision", 9.0, "obstacle_1"), "no_configuration_fix")
    assert report.misconfiguration == ()
    assert ("The nearest one, planning.max_accel_mps2 to 0.4, avoids the accident but changes the "
            "ego's trajectory before 6.0 s by h1 = 3.5 m^2, over the limit of 1 m^2."
            ) in report.explanation


def test_a_replay_from_less_than_the_whole_recording_says_so_everywhere():
    acc = {"kind": "emergency", "time_s": 10.15, "other": None}
    rep = {"source": "recording", "reproduced": True, "recorded_accident": acc, "accident": acc,
           "ego_rmse_m": 0.03, "compared_until_s": 10.2, "complete": False,
           "warnings": ["a.mcap: skipped a corrupted chunk at byte 4096 (312 messages)"]}
    report = build_report(_state(rep), Accident("emergency", 10.15, None), "no_reference")
    assert report.complete is False and list(report.warnings) == rep["warnings"]
    md = markdown(report)
    assert "less than the whole recording" in md and "skipped a corrupted chunk" in md
    whole = build_report(_state(rep | {"complete": True, "warnings": []}), None, "no_reference")
    assert whole.complete is True and "less than the whole" not in markdown(whole)


def test_the_replay_line_says_when_only_the_emergency_before_the_collision_came_back():
    recorded = {"kind": "collision", "time_s": 7.55, "other": "obstacle_1"}
    replayed = {"kind": "emergency", "time_s": 6.75, "other": None}
    rep = {"source": "recording", "reproduced": True, "only_emergency": True,
           "recorded_accident": recorded, "accident": replayed, "ego_rmse_m": 0.1,
           "compared_until_s": 7.55}
    report = build_report(_state(rep), Accident("emergency", 6.75, None), "no_reference")
    assert replay_text(report).startswith(
        "the emergency before the recorded collision with obstacle_1 at 7.55 s reproduced "
        "(emergency at 6.75 s), not the collision: the analysis explains the emergency")


def _suspect(named, suspect, reads_named):
    return ModuleRevision(by="cyber", reason="second_suspect", before=named, after=suspect, path=(),
                          reads_named=reads_named)


def test_a_fix_in_the_second_suspect_says_which_module_the_walk_named():
    mis = [{"module": "prediction", "parameter": "prediction.still_obstacle_speed_mps",
            "original": 0.5, "mutated": 0.2}]
    cyber = _cyber(module="prediction", parameters=18, named_module="planning",
                   fix={"prediction.still_obstacle_speed_mps": 0.2}, misconfiguration=mis)
    state = _state(SCENARIO, diff=_diff("planning"),
                   cyber=replace(cyber, revision=_suspect("planning", "prediction", False)))
    report = build_report(state, None, "misconfiguration")
    assert report.deviating_module == "prediction" and report.walk_named == "planning"
    assert report.path == ()
    assert "first diverge in module planning, but no configuration of it" in report.explanation
    assert "Algorithm 1's walk named planning" in markdown(report)
    # searched and not found either: the explanation names both modules
    state = _state(SCENARIO, diff=_diff("planning"),
                   cyber=_cyber(second_suspect=SearchSummary("prediction", 18, 10, 0).to_json()))
    report = build_report(state, None, "no_configuration_fix")
    assert "module planning nor of module prediction" in report.explanation


def test_a_fix_in_the_module_reading_the_walks_module_says_so():
    mis = [{"module": "planning", "parameter": "planning.collision_check_moving_m",
            "original": 0.5, "mutated": 1.3}]
    cyber = _cyber(named_module="prediction", fix={"planning.collision_check_moving_m": 1.3},
                   misconfiguration=mis,
                   revision=_suspect("prediction", "planning", True).to_json())
    report = build_report(_state(SCENARIO, diff=_diff("prediction"), cyber=cyber), None,
                          "misconfiguration")
    assert report.deviating_module == "planning" and report.suspect_reads_named is True
    assert "with ground truth from it the accident does not happen" in report.explanation
    assert "in module planning, which reads its output" in report.explanation
    assert "walk and module substitution named prediction" in markdown(report)


def test_larger_fixes_that_also_avoid_the_accident_are_listed_after_the_chosen_one():
    """A rotated A11 (variant set s1613): the lateral buffer is the smaller fix, the
    moving-obstacle check (the catalog's documented parameter) a larger one; both are shown."""
    mis = {"module": "planning", "parameter": "planning.lateral_safety_buffer_m",
           "original": 0.3, "mutated": 1.692}
    other = {"h2": 1.651042, "misconfiguration": [{"module": "planning",
                                                   "parameter": "planning.collision_check_moving_m",
                                                   "original": 0.5, "mutated": 2.453}],
             "min_separation_m": 6.841, "stalled": False}
    cyber = _cyber(misconfiguration=[mis], fix={mis["parameter"]: mis["mutated"]},
                   other_fixes=[other])
    report = build_report(_state(SCENARIO, diff=_diff("planning"), cyber=cyber), None,
                          "misconfiguration")
    assert report.to_json()["misconfiguration"] == [mis]
    assert report.to_json()["other_fixes"] == [other]
    assert ("- **Larger fixes that also avoid it**: planning.collision_check_moving_m 0.5 → "
            "2.453 (h2 1.651, smallest gap 6.84 m)") in markdown(report)


def test_names_in_report_md_are_never_html_or_markdown():
    from hostile import MARKUP, SPOOF

    state = _state(SCENARIO, diff=_diff("<img src=x onerror=alert(1)>", ["/control", SPOOF, MARKUP]),
                   cyber=_cyber(parameters=1, misconfiguration=[]))
    md = markdown(build_report(state, None, "no_configuration_fix"))
    assert "<img" not in md and "&lt;img src=x onerror=alert(1)&gt;" in md
    assert "\x1b" not in md and "\r" not in md and "fore\\[/\\]caster\\[bold\\]" in md
