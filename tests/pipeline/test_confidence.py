"""The confidence phase's rules: which references it adds, the majority, the level, the note."""

from __future__ import annotations

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


def test_the_majority_wins_and_ties_go_to_the_best_ranked_reference():
    assert agreement(["planning", "perception", "perception"]) == {
        "module": "perception", "runs": 3, "same": 2,
        "runner_up": {"module": "planning", "runs": 1}}
    assert agreement(["planning", "perception"])["module"] == "planning"
    assert agreement(["prediction"]) == {"module": "prediction", "runs": 1, "same": 1,
                                         "runner_up": None}
    assert agreement([None, None, "planning"])["module"] is None


def test_level():
    assert level({"runs": 3, "same": 3}, "agrees") == "stable"
    assert level({"runs": 3, "same": 2}, "consistent") == "stable"
    assert level({"runs": 3, "same": 2}, None) == "stable"
    assert level({"runs": 3, "same": 2}, "disagrees") == "contested"
    assert level({"runs": 2, "same": 1}, "agrees") == "unstable"
    assert level({"runs": 3, "same": 1}, "agrees") == "unstable"


def test_the_note_says_what_was_adopted_and_what_substitution_says():
    result = {"agreement": agreement(["planning", "perception", "perception"]),
              "answers": [{"reference": "reference.mcap", "module": "planning"},
                          {"reference": "reference_1.mcap", "module": "perception"},
                          {"reference": "reference_2.mcap", "module": "perception"}],
              "adopted": 1, "level": "contested",
              "second_opinion": {"stance": "disagrees", "module": "prediction"}}
    text = note(result)
    assert text.startswith("2 of 3 references name perception (1 names planning)")
    assert "reference_1.mcap" in text and "(prediction)" in text
    result |= {"agreement": agreement(["planning", "perception", None]), "adopted": 0,
               "level": "unstable"}
    assert "Unstable" in note(result)
