"""Root-cause keys, groups and scores from report objects (no simulation)."""

from rocas.campaign.grouping import group_accidents, root_cause_keys, scores


def _mis(module, *changes, alternatives=()):
    return {"verdict": "misconfiguration", "deviating_module": module,
            "misconfiguration": [{"parameter": p, "original": o, "mutated": m} for p, o, m in changes],
            "alternatives": [{"misconfiguration": [{"parameter": p, "original": o, "mutated": m}
                                                   for p, o, m in alt]} for alt in alternatives]}


def test_keys_name_module_parameters_and_directions():
    r = _mis("planning", ("planning.gap_m", 3.0, 5.0),
             alternatives=[[("planning.buffer_s", 1.0, 2.0)], [("planning.gap_m", 3.0, 1.0)]])
    # the same-direction alternative is another name of the cause; the other direction is not
    assert root_cause_keys(r) == ["planning: planning.gap_m up", "planning: planning.buffer_s up"]
    nofix = {"verdict": "no_configuration_fix", "deviating_module": "perception",
             "triggering_entity": {"kind": "vegetation",
                                   "properties": [{"name": "area.hedge.enabled"}]}}
    assert root_cause_keys(nofix) == ["perception: no configuration fix; trigger vegetation enabled"]
    assert root_cause_keys({"verdict": "no_reference"}) == ["no reference"]


def test_a_cause_reached_through_two_terms_is_one_group_and_scores_count_it():
    keys = {"a": ["p: x up", "p: y up"], "b": ["p: y up"], "c": ["p: y up", "p: x up"],
            "d": ["p: x down"]}
    groups = group_accidents(list(keys), keys)
    assert [(g["root_cause"], g["accidents"]) for g in groups] == [
        ("p: y up", ["a", "b", "c"]), ("p: x down", ["d"])]
    assert groups[0]["by_alternative"] == ["a"]
    sc = scores(groups, {"a": "A3", "b": "A3", "c": "A5", "d": "A5"})
    assert sc["completeness"] == 3 / 4 and sc["worst_completeness"] == 0.5
    assert sc["purity"] == 3 / 4 and sc["groups"]["p: y up"]["purity"] == 2 / 3
    assert scores(groups, {n: None for n in keys}) is None
