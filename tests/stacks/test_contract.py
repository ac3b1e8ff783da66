"""One contract, every registered stack (as ruptures runs one test over every cost): what the
rollout, the searches, the recorder and replay rely on. A stack added to the registry is
checked here without a test of its own."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rocas.catalog import entries
from rocas.recording.formats import open_recording
from rocas.rollout import rollout, rollout_batch
from rocas.stacks import registry
from rocas.stacks.base import CAPABILITIES, SelfSimulating, StackParams

NAMES = registry.names()
#: the stacks built into rocas's own world (a stack declaring another simulator's ``world`` has
#: its own rollout and its own tests: tests/stacks/highway)
OURS = [n for n in NAMES if not getattr(registry.get_stack(n), "world", None)]


def _scenario(name: str, duration_s: float = 3.0):
    """A short run of the stack's first catalog entry."""
    e = entries(name)[0]
    return dataclasses.replace(e.scenario, duration_s=duration_s)


@pytest.fixture(params=NAMES)
def stack(request):
    return registry.get_stack(request.param)


@pytest.fixture(params=OURS)
def ours(request):
    return registry.get_stack(request.param)


def test_every_built_in_stack_is_checked():
    assert {"ads", "lav"} <= set(OURS) and "highway" in NAMES


def test_the_rollout_refuses_a_stack_of_another_world(tmp_path):
    from rocas.errors import UsageError

    others = [n for n in NAMES if n not in OURS]
    assert others
    for name in others:
        with pytest.raises(UsageError, match="world, not rocas's own"):
            rollout(registry.get_stack(name), _scenario("ads"), None, 0)


def test_the_parameter_inventory_is_well_formed(stack):
    names = [p.full_name for p in stack.parameters]
    assert names and len(names) == len(set(names))
    for p in stack.parameters:
        assert p.module in stack.modules, p.full_name
        assert p.low <= p.default <= p.high and p.low < p.high, p.full_name
        assert p.description, p.full_name
        if p.is_integer:
            assert p.default == round(p.default), p.full_name
    full = StackParams(stack.parameters)
    assert full.overrides() == {} and len(full) == len(names)
    p = stack.parameters[0]
    moved = full.with_values({p.full_name: p.high})
    assert moved[p.full_name] == p.high and moved != full


def test_the_channels_name_the_stacks_modules_and_one_control_channel(stack):
    topics = [c.topic for c in stack.channels]
    assert topics and len(topics) == len(set(topics))
    for c in stack.channels:
        assert c.writer in stack.modules and set(c.readers) <= set(stack.modules), c.topic
        assert c.period_s > 0
    assert [c.role for c in stack.channels].count("control") == 1


def test_declared_capabilities_have_the_documented_shapes(stack):
    declared = {n for n in CAPABILITIES if getattr(stack, n, None) is not None}
    names = {p.full_name for p in stack.parameters}
    for limits in ("braking_limits", "sensing_limits", "pace_limits"):
        assert set(getattr(stack, limits, ())) <= names, limits
    assert set(getattr(stack, "substitutable", ())) <= set(stack.modules)
    if "tracker" in declared:
        tracker = stack.tracker({})
        assert tracker is None or 0 < tracker.position_gain <= 1
    assert not isinstance(stack, SelfSimulating)  # built into a world, not a command
    for own in ("analyze_recording", "bench"):
        # rocas's pipeline analyses a stack of its own world: only another world's brings its own
        assert own not in declared or ("world" in declared and callable(getattr(stack, own))), own


def test_a_run_is_deterministic(ours):
    stack = ours
    s = _scenario(stack.name)
    a, b = rollout(stack, s, None, 3), rollout(stack, s, None, 3)
    np.testing.assert_array_equal(a.ego, b.ego)
    np.testing.assert_array_equal(a.actors, b.actors)
    assert a.outcome == b.outcome


def test_a_variant_does_not_depend_on_its_batch(ours):
    stack = ours
    s = _scenario(stack.name)
    p = stack.parameters[-1]
    params = [None, {p.full_name: p.low}, None]
    batch = rollout_batch(stack, [s] * 3, params, [1, 2, 3], track_outputs=True)
    for i in range(3):
        alone = rollout_batch(stack, [s], [params[i]], [[1, 2, 3][i]], track_outputs=True)
        np.testing.assert_array_equal(batch.ego[i], alone.ego[0])
        np.testing.assert_array_equal(batch.digests[i], alone.digests[0])
        assert batch.outcomes[i] == alone.outcomes[0]
    assert batch.digests.shape == (3, len(stack.modules))


def test_a_recording_round_trips_and_replay_reads_it(ours, tmp_path):
    stack = ours
    from rocas.replay import reconstruct, replay

    s = _scenario(stack.name, 4.0)
    out = tmp_path / "run.mcap"
    res = rollout(stack, s, None, 0, output=out)
    rec = open_recording(str(out)).scan()
    meta = dict(rec.metadata)
    assert meta["rocas.stack"] == {"name": stack.name}
    assert meta["rocas.run"]["outcome"] == res.outcome.summary()
    written = {c.topic for c in rec.channels.values()}
    assert written == {c.topic for c in stack.channels}
    assert res.messages == sum(1 for _ in open_recording(str(out)).messages())
    back = reconstruct(out)
    assert back.scenario.ego.stack == stack.name
    assert len(back.times) > 10 and np.all(np.isfinite(back.ego_track))
    again = replay(back)  # closed loop from the recording alone: the ego drives as recorded
    assert again.ego_rmse_m < 0.5, again.ego_rmse_m
