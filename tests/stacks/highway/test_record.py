"""Recording highway-env runs and diffing them: channels read back, the planted module named."""

import pytest

pytest.importorskip("highway_env")

from rocas.analysis.diff import diff  # noqa: E402
from rocas.recording.formats import open_recording  # noqa: E402
from rocas.stacks.highway.record import (  # noqa: E402
    TOPIC_COMMAND,
    TOPIC_DECISION,
    TOPIC_NEIGHBOURS,
    record,
)

from .scenes import LAZY_LANE_CHANGE, PLANTED, WEAK_BRAKES  # noqa: E402


def test_a_recording_reads_back_with_its_topology_and_the_run(tmp_path):
    run = record(PLANTED, tmp_path / "a.mcap", WEAK_BRAKES, 0)
    rec = open_recording(tmp_path / "a.mcap")
    commands, neighbours = [], []
    for m in rec.decoded():
        if m.channel.topic == TOPIC_COMMAND:
            commands.append(m.message.acceleration_mps2)
        elif m.channel.topic == TOPIC_NEIGHBOURS:
            neighbours.append(m.message.front.id)
    assert commands == list(run.ego[:, 4])
    assert len(neighbours) == len(run.times) and neighbours[0] == 1
    topics = rec.topics()
    assert topics[TOPIC_COMMAND].metadata["rocas.role"] == "control"
    assert topics[TOPIC_DECISION].metadata["rocas.writers"] == "planning"
    meta = dict(rec.metadata)
    assert meta["rocas.stack"]["name"] == "highway"
    assert meta["rocas.run"]["collided"] == "true"


def test_diff_names_control_for_weak_brakes(tmp_path):
    record(PLANTED, tmp_path / "acc.mcap", WEAK_BRAKES, 0)
    record(PLANTED, tmp_path / "ref.mcap", {}, 0)
    assert diff(tmp_path / "acc.mcap", tmp_path / "ref.mcap").deviating_module == "control"


def test_diff_names_planning_for_a_lazy_lane_change(tmp_path):
    record(PLANTED, tmp_path / "acc.mcap", LAZY_LANE_CHANGE, 0)
    record(PLANTED, tmp_path / "ref.mcap", {}, 0)
    assert diff(tmp_path / "acc.mcap", tmp_path / "ref.mcap").deviating_module == "planning"
