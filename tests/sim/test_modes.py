"""Recording mode and batch mode share one semantics."""

import dataclasses
import json

import numpy as np
import pytest

from rocas.recording.formats import open_recording
from rocas.rollout import simulate, simulate_batch
from rocas.scenarios import load_example, scenario_from_dict
from rocas.stacks.ads.topics import CHANNELS, EGO_METADATA, WORLD_ATTACHMENT


@pytest.fixture(scope="module")
def short():
    return dataclasses.replace(load_example("left_turn_oncoming"), duration_s=10.0)


@pytest.fixture(scope="module")
def recorded(short, tmp_path_factory):
    path = tmp_path_factory.mktemp("rec") / "run.mcap"
    return simulate(short, output=path), path


def test_batch_equals_recording_mode(short, recorded):
    run, _ = recorded
    variants = [dataclasses.replace(short, seed=99), short,
                dataclasses.replace(short, weather=dataclasses.replace(short.weather,
                                                                       precipitation=80.0)),
                short]
    params = [None, None, {"planning.yield_distance_m": 1.0}, None]
    batch = simulate_batch(variants, params=params)
    for i in (1, 3):
        assert np.array_equal(batch.ego[i], run.ego)
        assert np.array_equal(batch.actors[i], run.actors)
        assert np.array_equal(batch.min_gap[i], run.min_gap)
        assert batch.outcomes[i] == run.outcome
    assert not np.array_equal(batch.ego[0], run.ego)  # another seed differs


def test_same_seed_same_result_whatever_the_batch_size():
    s = dataclasses.replace(load_example("junction_straight"), duration_s=8.0)
    one = simulate_batch(s, seeds=[5])
    many = simulate_batch(s, seeds=[1, 2, 5, 3, 4])
    assert np.array_equal(one.ego[0], many.ego[2])
    assert one.outcomes[0] == many.outcomes[2]


def test_recording_carries_topology_world_and_ego(short, recorded):
    run, path = recorded
    rec = open_recording(path)
    counts: dict[str, int] = {}
    last_ns: dict[str, int] = {}
    for m in rec.decoded():
        topic = m.channel.topic
        counts[topic] = counts.get(topic, 0) + 1
        assert m.log_time_ns >= last_ns.get(topic, -1)
        last_ns[topic] = m.log_time_ns
        assert abs(m.message.header.timestamp_sec * 1e9 - m.log_time_ns) < 1e3
    ticks = short.num_ticks
    for ch in CHANNELS:
        assert counts[ch.topic] == round(ticks * short.dt_s / ch.period_s)
    assert sum(counts.values()) == run.messages
    topics = rec.topics()
    control = topics["/control"]
    assert control.metadata["rocas.role"] == "control"
    assert control.metadata["rocas.writers"] == "control"
    assert control.metadata["rocas.readers"] == "canbus"
    assert set(topics["/planning"].metadata["rocas.readers"].split(",")) == {"control"}
    assert "planning" in topics["/perception/brake_signal"].metadata["rocas.readers"]
    world = json.loads(rec.attachment(WORLD_ATTACHMENT))
    assert {ln["id"] for ln in world["lanes"]} == {ln.id for ln in short.lanes}
    md = rec.metadata() if callable(rec.metadata) else rec.metadata
    meta = dict(md)[EGO_METADATA]
    assert meta["route"] == ",".join(short.ego.route)
    # the world plus the ego record is enough to rebuild the static scenario
    rebuilt = scenario_from_dict({**world, "ego": json.loads(meta["ego"])})
    assert rebuilt.lanes == short.lanes and rebuilt.ego == short.ego


def test_recording_is_atomic_on_failure(tmp_path, short):
    bad = dataclasses.replace(short, ego=dataclasses.replace(short.ego, params=(
        ("planning.nope", 1.0),)))
    with pytest.raises(Exception):  # noqa: B017 - any failure must leave no file behind
        simulate(bad, output=tmp_path / "x.mcap")
    assert not (tmp_path / "x.mcap").exists()


def test_each_variant_starts_with_its_own_ego_speed_and_offset(short, recorded):
    """The ego's start speed and lateral offset are per variant, not variant 0's."""
    run, _ = recorded
    slow = dataclasses.replace(short, ego=dataclasses.replace(short.ego, start_speed_mps=3.0,
                                                              start_lateral_m=0.4))
    batch = simulate_batch([slow, short])
    alone = simulate_batch([slow])
    assert batch.ego[0, 0, 3] == 3.0 and batch.ego[1, 0, 3] == short.ego.start_speed_mps
    assert np.array_equal(batch.ego[1], run.ego)
    assert np.array_equal(batch.ego[0], alone.ego[0])


def test_a_variant_is_the_same_beside_variants_whose_paths_are_longer_or_shorter():
    """Actor paths are sampled per variant: a lateral offset or a start moved makes a path
    longer or shorter, and a batch-wide sample count used to move the other variants' actors
    by up to 1e-7 m (catalog A4, an offset of 0.9 m: every output digest of its row changed)."""
    from rocas.catalog import entry
    from rocas.pipeline.physical import apply_physical
    from rocas.search.space import Mutation

    scn = entry("A4").scenario
    a = scn.actors[0]
    variants = [apply_physical(scn, Mutation(m)) for m in (
        {}, {f"actor.{a.id}.lateral_offset_m": a.lateral_offset_m + 0.9},
        {f"actor.{a.id}.lateral_offset_m": a.lateral_offset_m - 1.7},
        {f"actor.{a.id}.start_s_m": a.start_s_m + 7.3})]
    together = simulate_batch(variants, track_outputs=True)
    for i, v in enumerate(variants):
        alone = simulate_batch([v], track_outputs=True)
        assert np.array_equal(together.ego[i], alone.ego[0])
        assert np.array_equal(together.actors[i], alone.actors[0])
        assert np.array_equal(together.digests[i], alone.digests[0])


def test_rows_recorded_inside_a_batch_are_the_files_of_their_runs_alone(short, recorded, tmp_path):
    """Recordings merged into one batch (simulate_batch's ``outputs``) cost one rollout's fixed
    per-tick cost instead of one each, and change no bit of any file or row."""
    _, alone = recorded  # short, recorded on its own with its own seed
    other = tmp_path / "alone_other.mcap"
    simulate(short, {"planning.yield_distance_m": 1.0}, seed=7, output=other)
    variants = [dataclasses.replace(short, seed=99), short, short, short]
    params = [None, {"planning.yield_distance_m": 1.0}, None, {"planning.yield_distance_m": 2.0}]
    seeds = [99, 7, short.seed, 3]
    outputs = {1: tmp_path / "row1.mcap", 2: tmp_path / "row2.mcap"}
    batch = simulate_batch(variants, params=params, seeds=seeds, outputs=outputs)
    assert outputs[1].read_bytes() == other.read_bytes()
    assert outputs[2].read_bytes() == alone.read_bytes()
    plain = simulate_batch(variants, params=params, seeds=seeds)  # recording moves nothing
    assert np.array_equal(batch.ego, plain.ego) and np.array_equal(batch.actors, plain.actors)
    assert batch.outcomes == plain.outcomes
