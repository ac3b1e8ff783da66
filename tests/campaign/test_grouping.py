"""Root-cause keys, groups and scores from report objects (no simulation)."""

from rocas.campaign.grouping import documented_keys, group_accidents, root_cause_keys, scores
from rocas.campaign.triage import markdown


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
    assert root_cause_keys(nofix) == ["perception: no configuration fix; trigger vegetation"]
    # the property the reference changed is the search's choice, not part of the cause
    moved = {**nofix, "triggering_entity": {"kind": "vegetation",
                                            "properties": [{"name": "area.hedge.height_m"}]}}
    assert root_cause_keys(moved) == root_cause_keys(nofix)
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


def test_documented_keys_need_the_module_and_a_fix_parameter_moved_its_way():
    fixes = [{"planning.gap_m": 5.0}, {"planning.buffer_s": 2.0}]
    r = _mis("planning", ("planning.gap_m", 3.0, 4.0),
             alternatives=[[("planning.buffer_s", 1.0, 1.5)], [("planning.other", 1.0, 2.0)]])
    assert documented_keys(r, "planning", fixes) == ["planning: planning.gap_m up",
                                                     "planning: planning.buffer_s up"]
    # the documented parameter moved the other way, the wrong module, another parameter
    assert documented_keys(_mis("planning", ("planning.gap_m", 3.0, 1.0)), "planning", fixes) == []
    assert documented_keys(_mis("control", ("planning.gap_m", 3.0, 4.0)), "planning", fixes) == []
    assert documented_keys(_mis("planning", ("planning.other", 1.0, 2.0)), "planning", fixes) == []
    nofix = {"verdict": "no_configuration_fix", "deviating_module": "perception",
             "triggering_entity": {"kind": "vegetation", "properties": [{"name": "area.h.enabled"}]}}
    assert documented_keys(nofix, "perception", []) == root_cause_keys(nofix)
    assert documented_keys(nofix, "planning", []) == []
    # a type with a fix answered "no configuration fix" is not its documented root cause
    assert documented_keys(nofix, "perception", fixes) == []


def test_campaign_counts_groups_and_accidents_whose_root_cause_is_the_documented_one():
    from rocas.campaign import build_campaign

    def row(name, t, keys, documented):
        return {"name": name, "source": f"{name}.toml", "kind": "scenario", "run_dir": "",
                "truth_type": t, "truth_title": "", "verdict": "misconfiguration",
                "deviating_module": "p", "misconfiguration": [], "triggering_entity": None,
                "root_causes": keys, "documented_root_causes": documented, "confidence": None,
                "complete": True, "seconds": 1.0}

    rows = [row("a", "A3", ["p: x up"], ["p: x up"]), row("b", "A3", ["p: x up"], ["p: x up"]),
            row("c", "A5", ["p: x up"], []),  # in A3's group, not A5's documented cause
            row("d", "A5", ["p: z down"], []), row("e", "A5", ["p: z down"], [])]
    c = build_campaign(rows, {})
    sc = c["scores"]
    # purity says 4 of 5 accidents are in a group of their type; only 2 have the right cause
    assert sc["purity"] == 4 / 5
    assert (sc["groups_documented"], sc["groups_with_truth"]) == (1, 2)
    assert (sc["accidents_documented"], sc["documented_share"]) == (2, 2 / 5)
    assert [(g["root_cause"], g["documented"]) for g in c["groups"]] == [("p: x up", True),
                                                                          ("p: z down", False)]
    assert "1 of 2 groups, 2 of 5 accidents" in markdown(c)
    import io
    from pathlib import Path

    from rocas.cli.console import Env
    from rocas.cli.triage import render

    out = io.StringIO()
    render(c, Path("c"), Env(stdout=out, stderr=io.StringIO()))
    assert ("root cause the documented one (module, parameter, direction): 1 of 2 groups, "
            "2 of 5 accidents (40.0 %)") in out.getvalue()
