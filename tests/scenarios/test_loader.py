import dataclasses
import pickle

import pytest

from rocas.errors import ScenarioError
from rocas.scenarios import (
    example_names,
    load_example,
    load_scenario,
    scenario_from_dict,
    scenario_to_dict,
)

BASE = """
[scenario]
name = "t"
[[lanes]]
id = "a"
points = [[0, 0], [100, 0]]
successors = ["b"]
[[lanes]]
id = "b"
arc = { center = [100, 20], radius = 20, start_deg = -90, end_deg = 0 }
[ego]
route = ["a", "b"]
"""


def _write(tmp_path, text):
    p = tmp_path / "s.toml"
    p.write_text(text)
    return p


def test_examples_load_and_roundtrip():
    assert "junction_straight" in example_names()
    for name in example_names():
        s = load_example(name)
        again = scenario_from_dict(scenario_to_dict(s))
        assert again.lanes == s.lanes
        assert again.actors == s.actors
        assert again.ego == s.ego
        assert pickle.loads(pickle.dumps(s)) == s


def test_minimal_file_and_arc(tmp_path):
    s = load_scenario(_write(tmp_path, BASE))
    assert s.lanes[1].centerline[0] == pytest.approx((100.0, 0.0), abs=1e-6)
    assert s.lanes[1].centerline[-1] == pytest.approx((120.0, 20.0), abs=1e-6)
    assert dataclasses.replace(s, seed=3).seed == 3


@pytest.mark.parametrize(
    ("extra", "key", "reason"),
    [
        ("[weather]\nfog = 3\n", "weather.fog", "unknown key"),
        ("[weather]\nfog_density = 300\n", "weather.fog_density", "out of range"),
        ("[weather]\nfog_density = 'thick'\n", "weather.fog_density", "expected a number"),
        ("[[actors]]\nid = 'x'\nroute = ['b', 'a']\n", "actors[0].route[1]", "not a successor"),
        ("[[actors]]\nid = 'x'\nroute = ['a']\nmodel = 'tank'\n", "actors[0].model",
         "is not one of"),
        ("[[actors]]\nid = 'x'\nroute = ['a']\nspeed_profile = [[0, 1], [0, 2]]\n",
         "actors[0].speed_profile", "increase"),
        ("[[objects]]\nid = 'c'\nkind = 'cone'\n", "objects[0].position", "required"),
    ],
)
def test_errors_name_file_key_reason(tmp_path, extra, key, reason):
    text = BASE.replace("[ego]", extra + "\n[ego]") if not extra.startswith("[weather]") \
        else BASE + extra
    p = _write(tmp_path, text)
    with pytest.raises(ScenarioError) as err:
        load_scenario(p)
    msg = str(err.value)
    assert str(p) in msg and key in msg and reason in msg


def test_ego_param_overrides_are_validated_against_the_stack_by_the_rollout(tmp_path):
    from rocas.rollout import load_scenario as load_checked

    ok = BASE + "[ego.params.planning]\nyield_distance_m = 3.0\n"
    s = load_checked(str(_write(tmp_path, ok)))
    assert s.ego.overrides == {"planning.yield_distance_m": 3.0}
    bad = BASE + "[ego.params.planning]\nyield_distance_m = 300.0\n"
    assert load_scenario(_write(tmp_path, bad)).ego.overrides  # the format: a number
    with pytest.raises(ScenarioError, match="ego.params: planning.yield_distance_m: 300"):
        load_checked(str(_write(tmp_path, bad)))
    unknown = BASE + "[ego.params.planning]\nnope = 1\n"
    with pytest.raises(ScenarioError, match="planning.nope: unknown parameter"):
        load_checked(str(_write(tmp_path, unknown)))
    text = BASE + '[ego.params.planning]\nyield_distance_m = "x"\n'
    with pytest.raises(ScenarioError, match="ego.params.planning.yield_distance_m"):
        load_scenario(_write(tmp_path, text))


def test_bad_toml_and_missing_file(tmp_path):
    with pytest.raises(ScenarioError, match="not valid TOML"):
        load_scenario(_write(tmp_path, "[scenario"))
    with pytest.raises(ScenarioError, match="cannot read"):
        load_scenario(tmp_path / "missing.toml")


def test_roundabout_is_expressible_and_a9_depends_on_the_brake_threshold():
    from rocas.rollout import simulate_batch

    s = load_example("roundabout_red_truck")
    ring = ["ring_se", "ring_ne", "ring_nw", "ring_sw"]
    lanes = s.lane_by_id
    for a, b in zip(ring, ring[1:] + ring[:1], strict=True):
        assert b in lanes[a].successors  # a closed cycle of lanes
    res = simulate_batch(s, params=[None, {"perception.brake_threshold": 0.99}])
    assert res.outcomes[0].estop and not res.outcomes[1].estop


def test_a_derived_light_facing_survives_the_round_trip():
    # found by the property test: a light without facing_deg faces against its stop lane, and the
    # written degrees (9 decimals) must read back to the same radians
    from rocas.catalog import entry
    from rocas.scenarios.loader import scenario_from_dict, scenario_to_dict

    e = entry("A10")
    d = scenario_to_dict(e.scenario)
    for tl in d["traffic_lights"]:
        del tl["facing_deg"]
    s = scenario_from_dict(d)
    assert scenario_from_dict(scenario_to_dict(s)) == s


def test_a_catalog_file_loads_as_its_scenario():
    from importlib import resources

    from rocas.catalog import entry

    path = resources.files("rocas.catalog") / "ads" / "a10_skewed_junction_light.toml"
    assert load_scenario(path) == entry("A10").scenario


def test_check_ranges_false_reads_back_what_a_mutation_made():
    """An external stack reads the scenarios rocas simulates: a mutated actor may start past
    its track's end, which only ``check_ranges=False`` accepts (every other check stays)."""
    from rocas.catalog import entry
    from rocas.scenarios.loader import scenario_from_dict, scenario_to_dict

    doc = scenario_to_dict(entry("A9").scenario)
    doc["actors"][0]["start_s_m"] = 1e4
    with pytest.raises(ScenarioError, match="out of range"):
        scenario_from_dict(doc)
    s = scenario_from_dict(doc, check_ranges=False)
    assert s.actors[0].start_s_m == 1e4
    doc["actors"][0]["start_s_m"] = "far"
    with pytest.raises(ScenarioError, match="expected a number"):
        scenario_from_dict(doc, check_ranges=False)
