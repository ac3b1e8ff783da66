"""The confidence phase's rules: which references it adds, the majority, the level, the note."""

from __future__ import annotations

import json

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

    def __init__(self, module=None, jointly_avoided=False, **stances):
        self.stances = stances
        self.module = module
        self.jointly_avoided = jointly_avoided

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


def test_substitution_starts_before_phase_ii_and_runs_once_and_the_alternates_share_a_batch(
        tmp_path, monkeypatch):
    """Module substitution needs only the accident, so it is started (on a worker, here in
    this process) before phase II and the confidence phase takes its result; the alternate
    references are recorded in one batch, each the file its run alone writes."""
    import rocas.pipeline.substitution as substitution
    from rocas.pipeline import AnalyzeConfig, analyze
    from rocas.pipeline.physical import apply_physical
    from rocas.scenarios import load_example
    from rocas.search import SerialExecutor
    from rocas.search.space import Mutation
    from rocas.stacks.rollout import simulate

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
                     progress=lambda phase, info: events.append(phase))
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
