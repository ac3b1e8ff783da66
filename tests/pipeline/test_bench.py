"""rocas bench end to end on one catalog entry (small budgets: the machinery, not accuracy)."""

import json
from pathlib import Path

import pytest

from rocas.pipeline import AnalyzeConfig
from rocas.pipeline.bench import run_bench

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"


@pytest.mark.slow  # four analyses, two of them screening all 129 parameters (about 40 s)
def test_bench_scores_an_entry_and_compares_scopes_and_searches(tmp_path):
    cfg = AnalyzeConfig(seed=1, budget=16, population=8, validation_variants=2)
    res = run_bench(["A9"], tmp_path, cfg, recordings=RECORDINGS, compare_scope=1)
    (row,) = res["entries"]
    assert row["id"] == "a09" and row["expected"]["deviating_module"] == "perception"
    marks = row["marks"]
    assert row["hit"] == (marks["verdict"] and marks["module"] and marks["parameter"])
    (cmp,) = res["scope_comparison"]
    runs = {"module": cmp["module"], "all": cmp["all"], "plain module": cmp["plain"]["module"],
            "plain all": cmp["plain"]["all"]}
    assert runs["all"]["parameters"] == runs["plain all"]["parameters"] > runs["module"]["parameters"]
    assert runs["plain module"]["parameters"] == runs["module"]["parameters"]
    assert all(isinstance(r["parameter_hit"], bool) for r in runs.values())
    # the module run is the scored entry itself; the other three have their own run directories,
    # and only the screening searches start with the two-ends-of-every-parameter generation 0
    assert runs["module"]["found"] == row["found"]["parameters"]
    assert runs["module"]["parameter_hit"] == marks["parameter"]
    for name, screened in (("a09_red_truck_roundabout.all", True),
                           ("a09_red_truck_roundabout.module.plain", False),
                           ("a09_red_truck_roundabout.all.plain", False)):
        cyber = json.loads((tmp_path / name / "cyber.json").read_text())
        first = cyber["generations"][0]["generation"]
        assert (first == 0) == screened, name
        assert cyber["scope"] == ("all" if ".all" in name else "module")
        # the comparison is about the cyber search: its runs skip the validation
        state = json.loads((tmp_path / name / "state.json").read_text())
        assert state["evaluations"].get("validation", 0) == 0


@pytest.mark.slow  # two small analyses (about 15 s)
def test_bench_instances_are_variants_the_documented_fix_repairs(tmp_path):
    import io

    from rocas.cli.bench import render
    from rocas.cli.console import Env

    cfg = AnalyzeConfig(seed=1, budget=16, population=8, validation_variants=0)
    res = run_bench(["A9"], tmp_path, cfg, recordings=RECORDINGS, compare_scope=0, instances=1)
    (inst,) = res["instances"]
    assert inst["type"] == "A9" and inst["fixable"] and inst["analyzed"] == 1
    assert inst["tried"] >= inst["crashed"] >= inst["fix_holds"] >= 1
    assert 0 <= inst["hits"] <= 1 and inst["accuracy"] == inst["hits"]
    assert len(list((tmp_path / "instances").iterdir())) == 1
    out = io.StringIO()
    render(res, Env(stdout=out, stderr=io.StringIO()))
    assert (f"A9: {inst['crashed']} of {inst['tried']} variants crash, the documented fix repairs "
            f"{inst['fix_holds']}; {inst['hits']} of 1 analysed correctly") in out.getvalue()


def test_bench_over_seeds_tables_the_hits_per_entry_and_seed(tmp_path, monkeypatch):
    """Each seed's bench runs in its own directory with that seed; the table joins them."""
    import rocas.pipeline.bench as bench
    from rocas.errors import UsageError

    seen = []

    def fake(ids, out, cfg, **kwargs):
        seen.append((out, cfg.seed))
        hit_a2 = cfg.seed != 3

        def row(i, hit, module):
            return {"id": i, "type": i.upper(), "hit": hit, "seconds": 10.0 + cfg.seed,
                    "found": {"deviating_module": module, "parameters": [], "trigger_entity": None}}
        return {"entries": [row("a01", True, "prediction"), row("a02", hit_a2, "planning")],
                "hits": 1 + hit_a2, "total": 2}

    monkeypatch.setattr(bench, "run_bench", fake)
    res = bench.run_bench_seeds(None, tmp_path, AnalyzeConfig(), [0, 3, 4])
    assert seen == [(tmp_path / "seed-0", 0), (tmp_path / "seed-3", 3), (tmp_path / "seed-4", 4)]
    assert res["hits_per_seed"] == {"0": 2, "3": 1, "4": 2}
    assert res["every_seed"] == 1
    a02 = next(r for r in res["entries"] if r["id"] == "a02")
    assert a02["hits"] == {"0": True, "3": False, "4": True}
    assert a02["found"]["3"]["module"] == "planning"
    assert res["median_seconds"] == 13.0
    with pytest.raises(UsageError, match="repeats"):
        bench.run_bench_seeds(None, tmp_path, AnalyzeConfig(), [1, 1])


def test_the_agreement_summary_counts_levels_adoptions_and_the_second_opinion():
    def row(level, same, runs, adopted, stance):
        return {"confidence": {"level": level, "same": same, "runs": runs, "adopted": adopted,
                               "stance": stance, "substitution": None}}

    rows = [row("stable", 3, 3, False, "agrees"), row("contested", 2, 3, True, "disagrees"),
            row("unstable", 1, 3, False, "consistent"), {"confidence": None}]
    from rocas.pipeline import bench

    assert bench.agreement_summary(rows) == {
        "analyses": 3, "stable": 1, "contested": 1, "unstable": 1, "adopted": 1, "unanimous": 1,
        "second_opinion_agrees": 2}


def test_the_trigger_is_scored_when_the_replayed_id_is_known():
    from rocas.pipeline.bench import score

    exp = {"verdict": "misconfiguration", "deviating_module": "brake",
           "parameters": ["brake.brake_threshold"], "fixes": [{"brake.brake_threshold": 0.8}],
           "trigger_entity": "red_truck", "trigger_property": "color",
           "trigger_replayed": "obstacle_1"}
    found = {"verdict": "misconfiguration", "deviating_module": "brake",
             "parameters": ["brake.brake_threshold"],
             "changes": [{"parameter": "brake.brake_threshold", "original": 0.1, "mutated": 0.5}],
             "trigger_entity": "obstacle_1", "trigger_property": "color"}
    assert score(exp, found) == {"verdict": True, "module": True, "parameter": True,
                                 "trigger": True, "hit": True}
    other = score(exp, {**found, "trigger_property": "speed"})
    assert other["trigger"] is False and not other["hit"]
    unknown = score({**exp, "trigger_replayed": None}, {**found, "trigger_entity": "obstacle_2"})
    assert unknown["trigger"] is None and unknown["hit"]


def test_a_simulated_entry_expects_the_scenarios_own_trigger_id():
    """Without its recording an entry is simulated from its scenario, whose actors keep their
    ids: the lav catalog's red truck is `red_truck` there and `obstacle_1` in a replay."""
    from types import SimpleNamespace

    from rocas.pipeline.bench import _expected

    truth = SimpleNamespace(fixable=True, module="brake", parameters=("brake.brake_threshold",),
                            fixes=({"brake.brake_threshold": 0.8},), trigger_entity="red_truck",
                            trigger_property="color", replayed_id="obstacle_1")
    assert _expected(truth)["trigger_replayed"] == "obstacle_1"
    assert _expected(truth, replayed=False)["trigger_replayed"] == "red_truck"


def test_a_simulated_trigger_is_scored_against_the_documented_words():
    """A simulated entry's trigger property is a physical variable's name part
    (``speed_delta_mps``) and the catalog documents it in Table 1's words (``speed``, with an
    explanation in parentheses) or by that name part (the lav catalog's ``lateral_offset_m``)."""
    from rocas.pipeline.bench import same_property, score

    exp = {"verdict": "misconfiguration", "deviating_module": "planning",
           "parameters": ["planning.x"], "fixes": [{"planning.x": 2.0}],
           "trigger_entity": "truck", "trigger_property": "speed", "trigger_replayed": "truck"}
    found = {"verdict": "misconfiguration", "deviating_module": "planning",
             "parameters": ["planning.x"],
             "changes": [{"parameter": "planning.x", "original": 1.0, "mutated": 2.0}],
             "trigger_entity": "truck", "trigger_property": "speed_delta_mps"}
    assert score(exp, found)["trigger"] is True and score(exp, found)["hit"]
    wrong = score(exp, {**found, "trigger_property": "lateral_offset_m"})
    assert wrong["trigger"] is False and not wrong["hit"]
    assert same_property("enabled", "enabled (vegetation grown over the lane)")
    assert same_property("policy", "policy (yellow, then red while the ego's own light is green)")
    assert same_property("lateral_offset_m", "lateral position")
    assert same_property("start_s_m", "location") and same_property("lateral_offset_m", "location")
    assert same_property("lateral_offset_m", "lateral_offset_m")
    assert not same_property("start_s_m", "lateral position")
    assert not same_property("speed_delta_mps", "reactive (the driver brakes for what is ahead)")
    assert not same_property(None, "speed")


def test_every_documented_trigger_property_is_searched_but_two():
    """Each catalog entry's documented trigger property names a physical variable of its
    trigger entity, except A7's (the hitter's reactivity) and A11's (the truck's path angle),
    which no physical variable varies: a simulated bench cannot find them."""
    from rocas.catalog import entries
    from rocas.pipeline.bench import same_property
    from rocas.pipeline.physical import physical_space

    unsearched = []
    for stack in ("ads", "lav"):
        for e in entries(stack):
            t = e.truth
            if not any(v.entity == t.trigger_entity
                       and same_property(v.name.rsplit(".", 1)[-1], t.trigger_property)
                       for v in physical_space(e.scenario).variables):
                unsearched.append(e.id)
    assert unsearched == ["A7", "A11"]
