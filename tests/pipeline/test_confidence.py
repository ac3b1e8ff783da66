"""The confidence phase's rules: which references it adds, the majority, the level, the note."""

from __future__ import annotations

import json

import pytest

from rocas.pipeline.confidence import agreement, alternate_references, level, note


def _c(**values):
    return {"mutation": values}


def test_alternates_change_other_properties_than_the_chosen_one_and_each_other():
    chosen = _c(**{"actor.a.color": "brown"})
    front = [_c(**{"actor.a.color": "blue"}), _c(**{"actor.b.model": "truck"}),
             _c(**{"actor.b.model": "bus"}), _c(**{"actor.a.color": "red", "actor.b.model": "suv"}),
             _c(**{"weather.fog_density": 40.0})]
    alts = alternate_references(front, chosen, 2)
    assert alts == [front[1], front[3]]
    assert alternate_references(front, chosen, 0) == []
    assert len(alternate_references(front, chosen, 9)) == 3


def test_agreement_counts_the_reported_module_and_names_the_majority():
    assert agreement(["planning", "perception", "perception"]) == {
        "module": "planning", "runs": 3, "same": 1, "majority": "perception",
        "runner_up": {"module": "perception", "runs": 2}}
    assert agreement(["planning", "perception", "perception"], 1) == {
        "module": "perception", "runs": 3, "same": 2, "majority": "perception",
        "runner_up": {"module": "planning", "runs": 1}}
    assert agreement(["planning", "perception"])["majority"] == "planning"  # a tie: the best-ranked
    assert agreement(["prediction"]) == {"module": "prediction", "runs": 1, "same": 1,
                                         "majority": "prediction", "runner_up": None}
    assert agreement([None, None, "planning"])["majority"] is None


def test_level():
    assert level({"runs": 3, "same": 3}, "agrees") == "stable"
    assert level({"runs": 3, "same": 2}, "consistent") == "stable"
    assert level({"runs": 3, "same": 2}, None) == "stable"
    assert level({"runs": 3, "same": 2}, "disagrees") == "contested"
    assert level({"runs": 3, "same": 1}, "consistent") == "contested"
    assert level({"runs": 2, "same": 1}, "disagrees") == "unstable"
    assert level({"runs": 3, "same": 1}, None) == "unstable"
    # an answer from Algorithm 1's fallback (no change point on the control channel)
    assert level({"runs": 3, "same": 3}, "agrees", fallback=True) == "contested"
    assert level({"runs": 3, "same": 1}, None, fallback=True) == "unstable"


def test_the_note_says_when_the_answer_came_from_the_fallback():
    answers = [{"reference": "reference.mcap", "module": "perception",
                "fallback": "/control has no change point (...)"}]
    result = {"agreement": agreement(["perception"]), "answers": answers, "adopted": 0,
              "level": "contested"}
    assert "without a change point on the control channel" in note(result)
    answers[0]["fallback"] = None
    assert "without a change point" not in note(result)


def test_the_note_says_what_was_adopted_and_what_substitution_says():
    answers = [{"reference": "reference.mcap", "module": "planning"},
               {"reference": "reference_1.mcap", "module": "perception"},
               {"reference": "reference_2.mcap", "module": "perception"}]
    adopted = {"agreement": agreement([a["module"] for a in answers], 1), "answers": answers,
               "adopted": 1, "level": "stable",
               "second_opinion": {"stance": "agrees", "module": "perception"}}
    text = note(adopted)
    assert text.startswith("2 of 3 references name perception (1 names planning)")
    assert "reference_1.mcap" in text and "module substitution names the same module" in text
    kept = {"agreement": agreement([a["module"] for a in answers]), "answers": answers, "adopted": 0,
            "level": "contested", "second_opinion": {"stance": "consistent", "module": None}}
    text = note(kept)
    assert text.startswith("1 of 3 references name planning (2 name perception)")
    assert "the chosen reference's answer stands" in text
    assert "Unstable" in note(kept | {"level": "unstable"})


class _Opinion:
    """A stand-in for SubstitutionOpinion: a stance per module, the module whose ground truth
    avoids the accident (if any) and whether all ground truth together does."""

    def __init__(self, module=None, jointly_avoided=False, cleared=(), **stances):
        self.stances = stances
        self.module = module
        self.jointly_avoided = jointly_avoided
        self.cleared = tuple(cleared)
        self.accident = True

    def stance(self, module):
        return self.stances.get(module, "disagrees")


def test_the_walk_past_entries_is_taken_only_when_substitution_prefers_it():
    from rocas.pipeline.confidence import _answer

    found = {"deviating_module": "perception", "path": ["/control", "control", "perception"],
             "fallback": None,
             "entries": {"deviating_module": "planning", "path": ["/control", "control", "planning"],
                         "fallback": None, "named_at_entry": True,
                         "channels": {"/perception/obstacles": 3.5}}}
    # ground truth in perception leaves the accident, and planning has none to try (A5-like)
    taken = _answer(found, _Opinion(planning="consistent"))
    assert taken["module"] == "planning" and taken["entries_passed"] == {"/perception/obstacles": 3.5}
    # the diff phase's summary once resolved (as a resumed run reads it) stays resolved
    summary = {**found, "deviating_module": "planning", "path": taken["path"],
               "entries_passed": taken["entries_passed"]}
    assert _answer(summary, None)["module"] == "planning"
    # substitution names prediction, which is neither (an A11 variant of seed 131), or avoids
    # the accident only with perception and prediction together: it points upstream, not at
    # the walk past the entry, and Algorithm 1's answer stands
    for opinion in (_Opinion(module="prediction", prediction="agrees"), _Opinion(jointly_avoided=True)):
        assert _answer(found, opinion)["module"] == "perception"
    # substitution clears both (a car from behind that nothing avoids: A7-like): Algorithm 1's
    for opinion in (_Opinion(), _Opinion(perception="agrees", planning="consistent"), None):
        kept = _answer(found, opinion)
        assert kept["module"] == "perception" and "entries_passed" not in kept
    assert _answer({**found, "entries": None}, _Opinion(planning="consistent"))["module"] == "perception"
    # Algorithm 1 named its module at another departure than an entry (an A2 variant)
    other = {**found, "entries": {**found["entries"], "named_at_entry": False}}
    assert _answer(other, _Opinion(planning="consistent"))["module"] == "perception"


class _Walks:
    """A stand-in for DiffResult: the module Algorithm 1 names with the given modules'
    channels counted as not departed."""

    def __init__(self, **past):
        self.past = past
        self.calls = []

    def walk_without(self, modules, past_entries=False):
        from types import SimpleNamespace

        self.calls.append((tuple(modules), past_entries))
        module = self.past.get("+".join(modules))
        path = ("/control", "control", "/planning", "planning") if module == "planning" else ()
        return SimpleNamespace(deviating_module=module, path=path, fallback=None)

    delta_s = 3.0

    def walk_past_window(self, written_by, reach_s=None):
        from types import SimpleNamespace

        return SimpleNamespace(deviating_module=None, path=(), fallback=None)


def test_the_walk_goes_on_past_a_module_substitution_cleared():
    from rocas.pipeline.confidence import _answer

    found = {"deviating_module": "perception",
             "path": ["/control", "control", "/planning", "planning", "/perception/brake_signal",
                      "perception"], "fallback": None, "entries": None}
    # a drifting truck set aside changes the brake classifier's probabilities long before
    # planning departs; ground-truth perception leaves the accident, ground-truth prediction
    # avoids it (an A6 variant)
    cleared = _Opinion(module="prediction", cleared=["perception"], prediction="agrees")
    walks = _Walks(perception="planning")
    taken = _answer(found, cleared, lambda: walks)
    assert taken["module"] == "planning" and taken["cleared_passed"] == ["perception"]
    assert taken["path"] == ["/control", "control", "/planning", "planning"]
    # past two cleared modules in turn
    walks = _Walks(perception="prediction", **{"perception+prediction": "planning"})
    both = _Opinion(module="perception", cleared=["perception", "prediction"])
    both.module = "perception"  # informative: some module's ground truth avoids it
    assert _answer(found, both, lambda: walks)["cleared_passed"] == ["perception", "prediction"]
    # clearing says nothing when no module's ground truth alone avoids the accident (a car
    # from behind: A7), and a module substitution did not clear stands; the diff is not read
    unread = _Walks(perception="planning")
    for opinion in (_Opinion(cleared=["perception", "prediction"]),
                    _Opinion(jointly_avoided=True, cleared=["perception", "prediction"]),
                    _Opinion(module="perception", perception="agrees", cleared=["prediction"]),
                    None):
        kept = _answer(found, opinion, lambda: unread)
        assert kept["module"] == "perception" and "cleared_passed" not in kept
    assert unread.calls == []
    # a walk past that names no module leaves Algorithm 1's answer
    assert _answer(found, cleared, lambda: _Walks())["module"] == "perception"
    # a summary this phase resolved stays resolved (a resumed run)
    summary = {**found, **{k: taken[k] for k in ("path", "cleared_passed")},
               "deviating_module": "planning"}
    assert _answer(summary, cleared, lambda: unread)["cleared_passed"] == ["perception"]


def test_an_abstaining_chosen_reference_gives_way_to_one_that_names_a_module():
    from rocas.pipeline.confidence import adopted_answer

    def answers(*modules):
        return [{"reference": f"reference_{i}.mcap", "module": m} for i, m in enumerate(modules)]

    # a light switched off: the ego drives from the first tick, the diff names no module
    sub = _Opinion(module="prediction", prediction="agrees")
    assert adopted_answer(answers(None, None, "prediction"), sub) == 2
    assert adopted_answer(answers(None, "planning", "prediction"), sub) == 2  # disagrees
    assert adopted_answer(answers(None, "planning", "prediction"), None) == 1
    assert adopted_answer(answers(None, None), sub) == 0
    # an answer stands when it names a module (majority rule aside)
    assert adopted_answer(answers("planning", None, None), sub) == 0
    # the majority rule as before
    two = _Opinion(perception="agrees", planning="disagrees")
    assert adopted_answer(answers("planning", "perception", "perception"), two) == 1


class _Window:
    """A stand-in for DiffResult whose walk past the window names ``module``."""

    delta_s = 3.0

    def __init__(self, module):
        self.module = module
        self.asked = []

    def walk_past_window(self, written_by, reach_s=None):
        from types import SimpleNamespace

        self.asked.append((tuple(written_by), reach_s))
        return SimpleNamespace(deviating_module=self.module,
                               path=("/control", "control", "/planning", "planning",
                                     "/perception/brake_signal", "perception"),
                               fallback="no input of planning departed within 3 s before planning "
                                        "departed (10.6 s), but /perception/brake_signal departed "
                                        "earlier (7.4 s), so the walk goes on from it")


def test_the_walk_goes_on_past_the_window_only_to_the_module_substitution_names():
    from rocas.pipeline.confidence import _answer

    found = {"deviating_module": "planning", "path": ["/control", "control", "/planning", "planning"],
             "fallback": None, "entries": None}
    # the red truck met at a lower speed: its brake signal departs 3.2 s before planning
    sub = _Opinion(module="perception", perception="agrees")
    window = _Window("perception")
    taken = _answer(found, sub, lambda: window)
    assert taken["module"] == "perception" and window.asked == [(("perception",), 6.0)]
    assert taken["window_passed"].endswith("so the walk goes on from it; module substitution "
                                           "names perception")
    # the walk past the window reaches another module than substitution's: unchanged
    assert _answer(found, sub, lambda: _Window("prediction"))["module"] == "planning"
    # substitution names none, or the same module, or the answer came from the fallback or past
    # a cleared module: the window stays, and the diff is not read
    unread = _Window("perception")
    for opinion, answer in ((_Opinion(planning="consistent"), found),
                            (_Opinion(module="planning", planning="agrees"), found),
                            (sub, {**found, "fallback": "no change point"}),
                            (None, found)):
        assert _answer(answer, opinion, lambda: unread)["module"] == answer["deviating_module"]
    assert unread.asked == []


@pytest.mark.slow  # a whole analysis on a worker pool, about 45 s
def test_substitution_starts_before_phase_ii_and_runs_once_and_the_alternates_share_a_batch(
        tmp_path, monkeypatch):
    """Module substitution needs only the accident, so it is started (on a worker, here in
    this process) before phase II and the confidence phase takes its result; the alternate
    references are recorded in one batch, each the file its run alone writes."""
    import rocas.pipeline.substitution as substitution
    from rocas.pipeline import AnalyzeConfig, analyze
    from rocas.pipeline.physical import apply_physical
    from rocas.rollout import simulate
    from rocas.scenarios import load_example
    from rocas.search import SerialExecutor
    from rocas.search.space import Mutation

    events = []
    real = substitution.second_opinion

    def counted(*args, **kwargs):
        events.append("substitution")
        return real(*args, **kwargs)

    monkeypatch.setattr(substitution, "second_opinion", counted)
    red_truck = load_example("roundabout_red_truck")
    cfg = AnalyzeConfig(seed=1, budget=16, population=8, validation_variants=0, batch_size=8)
    out = tmp_path / "run"
    report = analyze(red_truck, out, cfg, executor=SerialExecutor(),
                     progress=lambda phase, info: events.append(phase)).to_json()
    assert events.count("substitution") == 1
    assert events.index("substitution") < events.index("physical")
    confidence = json.loads((out / "state.json").read_text())["done"]["confidence"]
    assert confidence["second_opinion"]["stance"] == report["confidence"]["second_opinion"]["stance"]
    alternates = confidence["answers"][1:]
    assert alternates  # the red truck's accident has other references
    for answer in alternates:
        scn = apply_physical(red_truck, Mutation(dict(answer["mutation"])))
        simulate(scn, output=tmp_path / "alone.mcap")
        assert (out / answer["reference"]).read_bytes() == (tmp_path / "alone.mcap").read_bytes()


def test_the_phase_revises_the_diffs_answer_instead_of_rewriting_it(tmp_path):
    """The chosen reference's walk taken on past a cleared module, then another reference's
    answer adopted: two revisions, in that order; the adopted reference's recording and diff
    become reference.mcap and diff.json."""
    from types import SimpleNamespace

    from rocas.pipeline.confidence import _revisions
    from rocas.pipeline.results import DiffPhaseResult, current_answer

    diff = DiffPhaseResult(deviating_module="perception", path=("/control", "control", "/p", "perception"),
                           control_channel="/control", fallback=None, entries=None, warnings=())
    answers = [{"reference": "reference.mcap", "mutation": {"a": 1.0}, "module": "planning",
                "path": ["/control", "control"], "fallback": None, "cleared_passed": ["perception"]},
               {"reference": "reference_1.mcap", "mutation": {"b": 2.0}, "module": "prediction",
                "path": ["/control", "control", "/pr", "prediction"], "fallback": None}]
    data = {"control_channel": "/cmd", "entries": None, "warnings": [], "deviating_module": "prediction"}
    (tmp_path / "reference_1.mcap").write_bytes(b"alternate")
    (tmp_path / "reference.mcap").write_bytes(b"chosen")
    revisions = _revisions(SimpleNamespace(out=tmp_path), diff, answers, 1, data)
    assert [(r.reason, r.before, r.after) for r in revisions] == [
        ("walk_passed", "perception", "planning"), ("adopted_reference", "planning", "prediction")]
    answer = current_answer(diff, revisions)
    assert (answer.deviating_module, answer.control_channel, answer.adopted_from) == (
        "prediction", "/cmd", "reference_1.mcap")
    assert answer.cleared_passed is None  # the adopted reference's walk passed nothing
    assert (tmp_path / "reference.mcap").read_bytes() == b"alternate"
    assert json.loads((tmp_path / "diff.json").read_text()) == data
    assert _revisions(SimpleNamespace(out=tmp_path), diff, answers[:1], 0, None)[0].after == "planning"
