"""Phase IV's second suspect: when no configuration of Algorithm 1's module avoids the
accident, the module module substitution names is searched, or, when substitution names that
module itself, the module that reads its output (rocas.pipeline.cyber_phase)."""

import json
from dataclasses import replace
from types import SimpleNamespace

import pytest

from rocas.pipeline import cyber_phase
from rocas.pipeline.results import (
    Agreement,
    ConfidenceResult,
    CyberResult,
    DiffPhaseResult,
    ModuleRevision,
    ParameterChange,
    SecondOpinionRecord,
)
from rocas.pipeline.rundir import Run, RunState, noop

WALK_TO_PLANNING = ("/control", "control", "/planning", "planning")
WALK_TO_PREDICTION = (*WALK_TO_PLANNING, "/prediction", "prediction")


def _opinion(accident, module):
    return SecondOpinionRecord(module=module, reason="", accident=accident, cleared=(), baseline="",
                               runs=(), stance="agrees")


def _Run(tmp_path, opinion, scope="module", path=WALK_TO_PLANNING):
    """A run whose diff and confidence phases finished (the parts phase IV reads and writes)."""
    diff = DiffPhaseResult(deviating_module=path[-1] if path else None, path=tuple(path),
                           control_channel="/control", fallback=None, entries=None, warnings=())
    conf = ConfidenceResult(answers=(), agreement=Agreement("planning", 2, 2, "planning", None),
                            adopted=0, second_opinion=_opinion(*opinion), level="contested",
                            note="2 of 2 references name planning.")
    state = RunState("x", {}, results={"diff": diff, "confidence": conf})
    run = Run(tmp_path, SimpleNamespace(scope=scope), None, noop, state)
    run.save = lambda: None
    return run


def _searches(fixed):
    """A stand-in for _search_fix: a fix only in the modules of ``fixed``."""
    calls = []

    def search(run, module, checkpoint):
        calls.append((module, checkpoint.name))
        out = CyberResult(module=module, scope="module", parameters=10, generations=(),
                          evaluations=50, feasible=0, first_fix_evaluation=None,
                          first_fix_batch_evaluations=None)
        if module in fixed:
            out = replace(out, feasible=3, fix={f"{module}.x": 1.0}, misconfiguration=(
                ParameterChange(module=module, parameter=f"{module}.x", original=0.5, mutated=1.0),))
        return out, 50
    return search, calls


PREDICTION = (True, "prediction")


def _report(run):
    """The report the run's results give (the current answer and the revised confidence)."""
    from rocas.pipeline.report import build_report

    return build_report(run.state, None, "misconfiguration")


def test_no_fix_in_the_walks_module_sends_the_search_to_substitutions_module(tmp_path, monkeypatch):
    search, calls = _searches({"prediction"})
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, PREDICTION)
    result = cyber_phase.phase_cyber(run, "planning")
    assert calls == [("planning", "cyber.ckpt"), ("prediction", "cyber_suspect.ckpt")]
    assert result.fix == {"prediction.x": 1.0} and result.named_module == "planning"
    assert result.named_module_search.module == "planning"
    assert run.state.evaluations["cyber"] == 100
    assert result.revision == ModuleRevision(by="cyber", reason="second_suspect", before="planning",
                                             after="prediction", path=(), reads_named=False)
    answer = run.answer()
    assert answer.deviating_module == "prediction" and answer.walk_named == "planning"
    assert run.result(DiffPhaseResult).deviating_module == "planning"  # never rewritten
    conf = _report(run).confidence
    assert conf.level == "contested" and "no configuration of planning" in conf.note
    assert run.result(ConfidenceResult).note == "2 of 2 references name planning."
    assert json.loads((tmp_path / "cyber.json").read_text())["named_module"] == "planning"


@pytest.mark.parametrize("opinion, scope, fixed", [
    (PREDICTION, "module", {"planning", "prediction"}),  # the walk's module has a fix
    ((True, None), "module", {"prediction"}),  # nothing alone avoids it (A7)
    ((False, None), "module", {"prediction"}),
    (PREDICTION, "all", {"prediction"}),  # --scope all searched every module already
])
def test_the_walks_module_stands_otherwise(tmp_path, monkeypatch, opinion, scope, fixed):
    search, calls = _searches(fixed)
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, opinion, scope)
    result = cyber_phase.phase_cyber(run, "planning")
    assert calls[0] == ("planning", "cyber.ckpt") and len(calls) == 1
    assert result.named_module is None and result.revision is None
    assert run.answer().deviating_module == "planning"


def test_a_second_suspect_without_a_fix_leaves_no_fix_and_says_it_was_searched(tmp_path, monkeypatch):
    search, calls = _searches(set())
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, PREDICTION)
    result = cyber_phase.phase_cyber(run, "planning")
    assert result.fix is None and result.second_suspect.module == "prediction"
    assert run.answer().deviating_module == "planning"
    assert run.state.evaluations["cyber"] == 100


def test_substitution_naming_the_walks_module_sends_the_search_to_the_module_reading_it(
        tmp_path, monkeypatch):
    """Ground-truth prediction avoids the accident but no prediction parameter does (a layout
    variant of A11): planning, which reads the forecast, is searched for a margin."""
    search, calls = _searches({"planning"})
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, PREDICTION, path=WALK_TO_PREDICTION)
    result = cyber_phase.phase_cyber(run, "prediction")
    assert calls == [("prediction", "cyber.ckpt"), ("planning", "cyber_suspect.ckpt")]
    assert result.fix == {"planning.x": 1.0} and result.named_module == "prediction"
    answer = run.answer()
    assert answer.deviating_module == "planning" and answer.walk_named == "prediction"
    assert answer.suspect_reads_named is True and answer.path == ()
    conf = _report(run).confidence
    assert conf.level == "contested" and "planning, which reads its output" in conf.note


@pytest.mark.parametrize("path", [(), ("/prediction", "prediction")])
def test_no_module_reads_the_walks_module_on_its_path_no_second_search(tmp_path, monkeypatch, path):
    search, calls = _searches({"planning"})
    monkeypatch.setattr(cyber_phase, "_search_fix", search)
    run = _Run(tmp_path, PREDICTION, path=path)
    result = cyber_phase.phase_cyber(run, "prediction")
    assert calls == [("prediction", "cyber.ckpt")] and result.fix is None


class _Pool:
    """A two-worker executor that runs everything here and records what it was given:
    ``mapped`` the batch sizes of each map, ``submitted`` the batch sizes submitted."""

    name = "pool"
    workers = 2

    def __init__(self):
        self.mapped, self.submitted = [], []

    def map(self, fn, tasks):
        self.mapped.append([len(t) for t in tasks])
        return [fn(t) for t in tasks]

    def submit(self, fn, *args):
        from rocas.search.executor import done_future

        self.submitted.append(len(args[0]))
        return done_future(fn, *args)

    def close(self):
        pass


def _short_run(tmp_path, executor):
    """A run of a three-second A9 whose cyber search is small (budget 40)."""
    import dataclasses

    from rocas.catalog import entries
    from rocas.pipeline.config import AnalyzeConfig
    from rocas.pipeline.evaluate import VariantTask, run_batch
    from rocas.pipeline.rundir import Run, noop

    scn = dataclasses.replace(next(e for e in entries() if e.id == "A9").scenario, duration_s=3.0)
    run = Run(tmp_path, AnalyzeConfig(budget=40, population=8), executor, noop, RunState("x", {}))
    run.scenario = scn
    run.original = run_batch([VariantTask(scn, (), scn.seed)])[0]
    run.accident_tick = 25
    return run


def test_the_screening_started_ahead_is_the_searchs_first_batch(tmp_path):
    """start_screening runs the cyber search's screening on a worker; the search then takes
    those results instead of simulating its first batch, and finds what it finds without."""
    ahead_pool, plain_pool = _Pool(), _Pool()
    ahead = _short_run(tmp_path / "a", ahead_pool)
    (tmp_path / "a").mkdir()
    cyber_phase.start_screening(ahead, "perception")
    assert ahead_pool.submitted and "cyber_screening" in ahead.ahead
    got, n_got = cyber_phase._search_fix(ahead, "perception", tmp_path / "a" / "cyber.ckpt")
    assert "cyber_screening" not in ahead.ahead
    plain = _short_run(tmp_path / "p", plain_pool)
    (tmp_path / "p").mkdir()
    want, n_want = cyber_phase._search_fix(plain, "perception", tmp_path / "p" / "cyber.ckpt")
    assert got == want
    assert n_got == n_want
    # the plain search simulated the screening itself, as its first batch; the other did not
    assert sum(ahead_pool.submitted) == sum(plain_pool.mapped[0])
    assert plain_pool.mapped[1:] == ahead_pool.mapped


def test_a_screening_of_another_module_is_left_unused(tmp_path):
    pool = _Pool()
    run = _short_run(tmp_path, pool)
    cyber_phase.start_screening(run, "planning")
    cyber_phase._search_fix(run, "perception", tmp_path / "cyber.ckpt")
    assert "cyber_screening" not in run.ahead
    plain = _Pool()
    cyber_phase._search_fix(_short_run(tmp_path / "p", plain), "perception", tmp_path / "p.ckpt")
    assert pool.mapped == plain.mapped  # the search simulated its own screening


def test_nothing_is_started_with_one_worker_or_without_a_module(tmp_path):
    pool = _Pool()
    run = _short_run(tmp_path, pool)
    cyber_phase.start_screening(run, None)
    pool.workers = 1
    cyber_phase.start_screening(run, "perception")
    assert run.ahead == {} and pool.submitted == []
