"""Phase IV's second suspect: when no configuration of Algorithm 1's module avoids the
accident, the module module substitution names is searched, or, when substitution names that
module itself, the module that reads its output (rocas.pipeline.cyber_phase)."""

import json
from types import SimpleNamespace

import pytest

from rocas.pipeline import cyber_phase


WALK_TO_PLANNING = ("/control", "control", "/planning", "planning")
WALK_TO_PREDICTION = (*WALK_TO_PLANNING, "/prediction", "prediction")


class _Run:
    """The parts of a run directory phase IV reads and writes."""

    def __init__(self, tmp_path, opinion, scope="module", path=WALK_TO_PLANNING):
        self.out = tmp_path
        self.cfg = SimpleNamespace(scope=scope)
        self.state = {"done": {
            "diff": {"deviating_module": path[-1] if path else None, "path": list(path)},
            "confidence": {"level": "contested", "note": "2 of 2 references name planning.",
                           "second_opinion": opinion}},
            "timings_s": {}, "evaluations": {}}

    def done(self, phase):
        return phase in self.state["done"]

    def finish(self, phase, result, seconds, evaluations=0):
        self.state["done"][phase] = result
        self.state["evaluations"][phase] = evaluations


def _searches(fixed):
    """A stand-in for _search_fix: a fix only in the modules of ``fixed``."""
    calls = []

    def search(run, module, checkpoint):
        calls.append((module, checkpoint.name))
        out = {"module": module, "parameters": 10, "evaluations": 50, "feasible": 0}
        if module in fixed:
            out |= {"feasible": 3, "fix": {f"{module}.x": 1.0},
                    "misconfiguration": [{"module": module, "parameter": f"{module}.x",
                                          "original": 0.5, "mutated": 1.0}]}
        return out, 50
    return search, calls


PREDICTION = {"accident": True, "module": "prediction"}


def test_no_fix_in_the_walks_module_sends_the_search_to_substitutions_module(tmp_path, monkeypatch):
    search, calls = _searches({"prediction"})
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, PREDICTION)
    result = cyber_phase.phase_cyber(run, "planning")
    assert calls == [("planning", "cyber.ckpt"), ("prediction", "cyber_suspect.ckpt")]
    assert result["fix"] == {"prediction.x": 1.0} and result["named_module"] == "planning"
    assert result["named_module_search"]["module"] == "planning"
    assert run.state["evaluations"]["cyber"] == 100
    diff = run.state["done"]["diff"]
    assert diff["deviating_module"] == "prediction" and diff["walk_named"] == "planning"
    conf = run.state["done"]["confidence"]
    assert conf["level"] == "contested" and "no configuration of planning" in conf["note"]
    assert json.loads((tmp_path / "cyber.json").read_text())["named_module"] == "planning"


@pytest.mark.parametrize("opinion, scope, fixed", [
    (PREDICTION, "module", {"planning", "prediction"}),  # the walk's module has a fix
    ({"accident": True, "module": None}, "module", {"prediction"}),  # nothing alone avoids it (A7)
    ({"accident": False, "module": None}, "module", {"prediction"}),
    (PREDICTION, "all", {"prediction"}),  # --scope all searched every module already
])
def test_the_walks_module_stands_otherwise(tmp_path, monkeypatch, opinion, scope, fixed):
    search, calls = _searches(fixed)
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, opinion, scope)
    result = cyber_phase.phase_cyber(run, "planning")
    assert calls[0] == ("planning", "cyber.ckpt") and len(calls) == 1
    assert "named_module" not in result
    assert run.state["done"]["diff"]["deviating_module"] == "planning"


def test_a_second_suspect_without_a_fix_leaves_no_fix_and_says_it_was_searched(tmp_path, monkeypatch):
    search, calls = _searches(set())
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, PREDICTION)
    result = cyber_phase.phase_cyber(run, "planning")
    assert "fix" not in result and result["second_suspect"]["module"] == "prediction"
    assert run.state["done"]["diff"]["deviating_module"] == "planning"
    assert run.state["evaluations"]["cyber"] == 100


def test_substitution_naming_the_walks_module_sends_the_search_to_the_module_reading_it(
        tmp_path, monkeypatch):
    """Ground-truth prediction avoids the accident but no prediction parameter does (a layout
    variant of A11): planning, which reads the forecast, is searched for a margin."""
    search, calls = _searches({"planning"})
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, PREDICTION, path=WALK_TO_PREDICTION)
    result = cyber_phase.phase_cyber(run, "prediction")
    assert calls == [("prediction", "cyber.ckpt"), ("planning", "cyber_suspect.ckpt")]
    assert result["fix"] == {"planning.x": 1.0} and result["named_module"] == "prediction"
    diff = run.state["done"]["diff"]
    assert diff["deviating_module"] == "planning" and diff["walk_named"] == "prediction"
    assert diff["suspect_reads_named"] is True
    conf = run.state["done"]["confidence"]
    assert conf["level"] == "contested" and "planning, which reads its output" in conf["note"]


@pytest.mark.parametrize("path", [(), ("/prediction", "prediction")])
def test_no_module_reads_the_walks_module_on_its_path_no_second_search(tmp_path, monkeypatch, path):
    search, calls = _searches({"planning"})
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, PREDICTION, path=path)
    result = cyber_phase.phase_cyber(run, "prediction")
    assert calls == [("prediction", "cyber.ckpt")] and "fix" not in result
