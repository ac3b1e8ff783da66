"""The stack protocol, the registry, the LAV-like stack and the rollout that joins a world and
a stack."""

import dataclasses

import numpy as np
import pytest

from rocas.catalog import entry
from rocas.errors import ScenarioError, UsageError
from rocas.rollout import rollout, rollout_batch
from rocas.stacks import registry
from rocas.stacks.base import Stack, StackParams


def _short(scenario, duration=4.0):
    return dataclasses.replace(scenario, duration_s=duration)


def test_registry_knows_both_built_in_stacks_and_refuses_a_taken_name():
    assert {"ads", "lav"} <= set(registry.names())
    lav = registry.get_stack("lav")
    assert isinstance(lav, Stack)
    with pytest.raises(UsageError, match="already registered"):
        registry.register(lav)
    with pytest.raises(UsageError, match="unknown stack 'nope'"):
        registry.get_stack("nope")


def test_lav_declares_its_own_parameters_and_channels():
    lav, ads = registry.get_stack("lav"), registry.get_stack("ads")
    names = {p.full_name for p in lav.parameters}
    assert "brake.brake_threshold" in names and "planner.dist_threshold_moving_m" in names
    assert not names & {p.full_name for p in ads.parameters}
    assert not {c.topic for c in lav.channels} & {c.topic for c in ads.channels}
    assert [c.topic for c in lav.channels if c.role == "control"] == ["/lav/control/command"]
    modules = set(lav.modules)
    for c in lav.channels:
        assert c.writer in modules and set(c.readers) <= modules


def test_stack_params_validate_against_the_inventory():
    lav = registry.get_stack("lav")
    p = StackParams(lav.parameters, {"brake.brake_threshold": 0.5})
    assert p["brake.brake_threshold"] == 0.5 and p.overrides() == {"brake.brake_threshold": 0.5}
    with pytest.raises(ScenarioError, match="out of range"):
        StackParams(lav.parameters, {"brake.brake_threshold": 2.0})
    with pytest.raises(ScenarioError, match="unknown parameter"):
        StackParams(lav.parameters, {"perception.brake_threshold": 0.5})


def test_a_lav_variant_is_the_same_whatever_the_batch():
    lav = registry.get_stack("lav")
    s = _short(entry("A9").scenario)
    params = [None, {"planner.max_speed_kmh": 20.0}, {"brake.brake_threshold": 0.9}]
    batch = rollout_batch(lav, [s] * 3, params, [1, 2, 3])
    for i in range(3):
        one = rollout(lav, s, params[i], [1, 2, 3][i])
        np.testing.assert_array_equal(one.ego, batch.ego[i])
    tracked = rollout_batch(lav, [s] * 3, params, [1, 2, 3], track_outputs=True)
    alone = rollout_batch(lav, [s], [params[1]], [2], track_outputs=True)
    np.testing.assert_array_equal(tracked.digests[1], alone.digests[0])
    # a parameter the planner reads changes the planner's output and the ego's course
    planner = lav.modules.index("planner")
    assert tracked.digests[1, planner] != tracked.digests[0, planner]


def test_the_built_in_ads_through_the_protocol_drives_as_the_engine_does():
    from rocas.rollout import simulate_batch

    s = _short(entry("A1").scenario, 3.0)
    ours = rollout_batch(registry.get_stack("ads"), [s], None, [0])
    engine = simulate_batch([s], None, [0])
    np.testing.assert_array_equal(ours.ego, engine.ego)
    assert ours.outcomes == engine.outcomes


def test_a_lav_recording_carries_its_topology_world_and_stack_name(tmp_path):
    from rocas.recording.formats import open_recording

    lav = registry.get_stack("lav")
    out = tmp_path / "run.mcap"
    res = rollout(lav, _short(entry("A9").scenario, 1.0), output=out)
    rec = open_recording(str(out)).scan()
    topics = {c.topic: c for c in rec.channels.values()} if isinstance(rec.channels, dict) \
        else {c.topic: c for c in rec.channels}
    assert set(topics) == {c.topic for c in lav.channels}
    assert topics["/lav/control/command"].metadata["rocas.role"] == "control"
    meta = dict(rec.metadata)
    assert meta["rocas.stack"] == {"name": "lav"}
    assert meta["rocas.run"]["outcome"] == res.outcome.summary()
    assert rec.attachment("rocas/world.json") is not None
