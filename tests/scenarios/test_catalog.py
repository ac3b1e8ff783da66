"""The accident catalog: every entry crashes with the ADS defaults as documented, its fix (or
the physical mutation of its trigger) avoids the accident, the unfixable ones resist every
single-parameter change of their module, and the shipped recordings match the catalog."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rocas.catalog import (
    PRE_ACCIDENT_MARGIN_S,
    PRE_ACCIDENT_RMSE_M,
    _jittered,
    accident_matches,
    accident_time,
    entries,
    entry,
    fix_holds,
    generate_instances,
    mutate,
    scenario_toml,
    trajectory_rmse,
)
from rocas.recording.formats import open_recording
from rocas.rollout import simulate_batch
from rocas.scenarios.loader import scenario_from_dict
from rocas.stacks.ads.params import PARAMETERS

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"
ENTRIES = entries()
IDS = [e.id for e in ENTRIES]


def _clean(o) -> bool:  # noqa: ANN001
    return not o.collided and not o.emergency


@pytest.fixture(scope="module")
def runs():
    """Per entry, one batch: defaults, the reference, then each documented fix (the main one
    and its alternatives)."""
    out = {}
    for e in ENTRIES:
        scs = [e.scenario, e.reference_scenario] + [e.scenario] * len(e.truth.fixes)
        params = [None, None] + [dict(f) for f in e.truth.fixes]
        out[e.id] = simulate_batch(scs, params=params)
    return out


def test_the_catalog_has_unique_ordered_ids():
    assert IDS == sorted(IDS, key=lambda i: int(i[1:]))
    assert len(set(IDS)) == len(IDS)
    assert all(e.key.startswith(f"a{int(e.id[1:]):02d}_") for e in ENTRIES)
    assert entry("a9").id == entry("A09").id == "A9"


@pytest.mark.parametrize("type_id", IDS)
def test_crashes_with_the_default_configuration(runs, type_id):
    e = entry(type_id)
    o = runs[type_id].outcomes[0]
    assert accident_matches(e.truth, o), o.summary()
    assert accident_time(o) is not None and accident_time(o) <= e.scenario.duration_s
    if e.truth.consequence == "collision":
        assert o.collision_with == e.truth.collision_with


@pytest.mark.parametrize("type_id", IDS)
def test_mutating_the_trigger_avoids_the_accident(runs, type_id):
    o = runs[type_id].outcomes[1]
    assert _clean(o), o.summary()


FIXES = [(e.id, i) for e in ENTRIES for i in range(len(e.truth.fixes))]


@pytest.mark.parametrize(("type_id", "which"), FIXES)
def test_the_documented_fix_avoids_the_accident_and_keeps_the_trajectory(runs, type_id, which):
    res = runs[type_id]
    o = res.outcomes[2 + which]
    assert _clean(o), (entry(type_id).truth.fixes[which], o.summary())
    t_acc = accident_time(res.outcomes[0])
    rmse = trajectory_rmse(res.ego[0], res.ego[2 + which], res.times,
                           t_acc - PRE_ACCIDENT_MARGIN_S)
    assert rmse < PRE_ACCIDENT_RMSE_M
    assert fix_holds(res.outcomes[0], res.ego[0], o, res.ego[2 + which], res.times)


def _grid(name: str, points: int) -> list[float]:
    p = PARAMETERS[name]
    grid = np.linspace(p.low, p.high, points)
    return sorted({float(round(v)) if p.is_integer else float(v) for v in grid})


@pytest.mark.slow
@pytest.mark.parametrize("type_id", [e.id for e in ENTRIES if not e.truth.fixable])
def test_no_single_parameter_of_the_module_avoids_an_unfixable_accident(type_id):
    e = entry(type_id)
    names = [n for n in PARAMETERS if n.startswith(e.truth.module + ".")]
    params = [{n: v} for n in names for v in _grid(n, 3)]
    res = simulate_batch([e.scenario] * len(params), params=params)
    avoided = [p for p, o in zip(params, res.outcomes, strict=True) if _clean(o)]
    assert not avoided, f"{type_id} is avoided by {avoided}"


@pytest.mark.parametrize("type_id", IDS)
def test_the_shipped_recording_is_in_sync(type_id):
    e = entry(type_id)
    path = RECORDINGS / f"{e.key}.mcap"
    assert path.is_file(), f"missing {path}; run: rocas catalog record recordings/"
    assert path.stat().st_size < 5_000_000
    rec = open_recording(path).scan()
    meta = dict(rec.metadata)
    run, ego = meta["rocas.run"], meta["rocas.ego"]
    assert ego["scenario"] == e.scenario.name
    assert float(ego["duration_s"]) == e.scenario.duration_s <= 30.0
    assert run["collided"] == ("true" if e.truth.consequence == "collision" else "false")
    assert run["emergency"] == "true" or e.truth.consequence == "collision"
    assert run["collision_with"] == (e.truth.collision_with or "")


def test_mutate_validates_and_names_the_entity():
    e = entry("A9")
    s = mutate(e.document, {"actor": e.truth.trigger_entity, "color": "white"}, "x")
    assert next(a for a in s.actors if a.id == e.truth.trigger_entity).color == "white"
    with pytest.raises(Exception, match="no actor"):
        mutate(e.document, {"actor": "nobody", "color": "white"}, "x")


def test_instances_are_seeded_crashing_variants_that_round_trip_as_toml():
    import tomllib

    e = entry("A9")
    a = generate_instances(e, 2, seed=3, max_tries=4)
    b = generate_instances(e, 2, seed=3, max_tries=4)
    assert a.tried == 4 and 0 < a.fix_holds <= a.crashed <= 4 and len(a.instances) == 2
    assert [s for _, s in a.instances] == [s for _, s in b.instances]
    assert a.instances[0][1] != e.scenario
    back = scenario_from_dict(tomllib.loads(scenario_toml(a.instances[0][1])))
    assert back == a.instances[0][1]


def test_instances_the_documented_fix_does_not_repair_are_not_kept():
    """A4's variants 0 and 1 (seed 0) crash, but yield_distance_m 0.5 brakes hard on them; the
    first variant it repairs is 5. An instance is scored against the documented fix, so only
    variants that fix repairs are kept."""
    e = entry("A4")
    rep = generate_instances(e, 1, seed=0, max_tries=6, batch=6)
    assert [k for k, _ in rep.instances] == [5] and rep.crashed > rep.fix_holds >= 1
    first = _jittered(e, np.random.default_rng([0, 0]))
    res = simulate_batch([first, first], params=[None, dict(e.truth.fix)])
    assert accident_matches(e.truth, res.outcomes[0])
    assert not fix_holds(res.outcomes[0], res.ego[0], res.outcomes[1], res.ego[1], res.times)


def _truth_doc(**changes):  # noqa: ANN003, ANN202
    import tomllib
    from importlib import resources

    text = resources.files("rocas.catalog").joinpath("ads", f"{entry('A5').key}.toml")
    return {**tomllib.loads(text.read_text())["ground_truth"], **changes}


@pytest.mark.parametrize(("changes", "message"), [
    ({"alternatives": [{"planning.yield_distance_m": 1.0}]}, "not listed in parameters"),
    ({"alternatives": [{}]}, "non-empty tables"),
    ({"alternatives": {"planning.min_overtake_distance_m": 0.5}}, "list of non-empty tables"),
    ({"fix": {}, "fixable": False}, "unfixable entry has no alternative"),
])
def test_alternative_fixes_are_validated(changes, message):
    from rocas.catalog import _truth
    from rocas.errors import ScenarioError

    with pytest.raises(ScenarioError, match=message):
        _truth(_truth_doc(**changes), "a05.toml")


def test_alternatives_name_documented_parameters_and_follow_the_fix():
    t = entry("A5").truth
    assert t.fixes[0] == t.fix and len(t.fixes) == 1 + len(t.alternatives)
    assert all(set(a) <= set(t.parameters) for a in t.alternatives)
    assert entry("A7").truth.fixes == ()
