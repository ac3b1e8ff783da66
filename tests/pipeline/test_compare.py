"""Two analyses' reports compared field by field (rocas.pipeline.compare)."""

import copy
import json

import pytest

from rocas.errors import InputError
from rocas.pipeline.compare import compare_reports, read_analysis_report


def _report(**changes):
    report = {
        "verdict": "misconfiguration", "stack": "ads", "explanation": "x",
        "settings": {"seed": 0, "budget": 240},
        "accident": {"kind": "emergency", "time_s": 10.15},
        "triggering_entity": {"entity": "obstacle_1", "kind": "vehicle",
                              "properties": [{"name": "actor.obstacle_1.color", "original": "red",
                                              "mutated": "black"}]},
        "deviating_module": "perception", "path": ["/control", "control", "perception"],
        "confidence": {"level": "stable", "note": "2 of 3 references name perception"},
        "misconfiguration": [{"parameter": "perception.brake_threshold", "original": 0.8,
                              "mutated": 0.854921875}],
        "validation": {"variants": 200, "success_rate_original": 0.0, "success_rate_fixed": 0.59},
        "search_space": {"parameters_searched": 36, "parameters_total": 129},
        "evaluations": {"replay": 1, "cyber": 144}, "timings_s": {"replay": 0.7, "cyber": 1.0},
    }
    report.update(changes)
    return report


def test_identical_reports_give_the_same_answer_and_no_differing_field(tmp_path):
    c = compare_reports(tmp_path / "a", _report(), tmp_path / "b", _report())
    assert c.same_answer and c.differing == ()
    total = c.costs[-1]
    assert (total.phase, total.seconds_a, total.simulations_b) == ("total", pytest.approx(1.7), 145)


def test_a_changed_parameter_and_seed_are_named_and_the_rest_is_the_same(tmp_path):
    b = _report(settings={"seed": 1, "budget": 240})
    b["misconfiguration"] = [{**b["misconfiguration"][0], "mutated": 0.8564}]
    c = compare_reports(tmp_path / "a", _report(), tmp_path / "b", b)
    assert not c.same_answer
    assert [f.name for f in c.differing] == ["misconfiguration", "setting seed"]
    mis = next(f for f in c.fields if f.name == "misconfiguration")
    assert (mis.a, mis.b) == ("perception.brake_threshold 0.8 -> 0.8549",
                              "perception.brake_threshold 0.8 -> 0.8564")
    doc = c.to_json()
    assert doc["differs"] == ["misconfiguration", "setting seed"] and doc["same_answer"] is False


def test_values_are_compared_as_report_json_writes_them(tmp_path):
    noisy = _report()
    noisy["misconfiguration"] = [{**noisy["misconfiguration"][0], "mutated": 0.8549218750000002}]
    assert compare_reports(tmp_path / "a", _report(), tmp_path / "b", noisy).same_answer


def test_a_module_found_only_by_one_run_differs(tmp_path):
    b = _report(deviating_module="planning", misconfiguration=[])
    c = compare_reports(tmp_path / "a", _report(), tmp_path / "b", b)
    assert {"deviating module", "misconfiguration"} <= {f.name for f in c.differing}


def test_what_is_not_a_finished_analysis_is_refused_in_words(tmp_path):
    with pytest.raises(InputError, match="not a directory"):
        read_analysis_report(tmp_path / "missing")
    with pytest.raises(InputError, match="no analysis here"):
        read_analysis_report(tmp_path)
    (tmp_path / "state.json").write_text("{}")
    with pytest.raises(InputError, match="has not finished"):
        read_analysis_report(tmp_path)
    for bad, why in (([1, 2], "not a JSON object"), ({"verdict": "x"}, "no 'stack'"),
                     (_report(evaluations={"cyber": "many"}), "evaluations.cyber"),
                     (_report(misconfiguration=[{"parameter": "p"}]), "lacks")):
        (tmp_path / "report.json").write_text(json.dumps(bad))
        with pytest.raises(InputError, match=why):
            read_analysis_report(tmp_path)
    (tmp_path / "report.json").write_text(json.dumps(copy.deepcopy(_report())))
    assert read_analysis_report(tmp_path)["verdict"] == "misconfiguration"
