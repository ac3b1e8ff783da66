"""tests/artefacts.py: each logging artefact does what it says, on a small file."""

from __future__ import annotations

import artefacts as A
import numpy as np
import pytest
from google.protobuf import descriptor_pb2
from mcap.reader import make_reader
from mcap.writer import Writer

from rocas.msgs import control_pb2, localization_pb2

NS = A.NS
ROS_MSG = "float64 x\nfloat32[] ranges\nint32 count\nstring label\n"


def _fds(descriptor) -> bytes:
    fds = descriptor_pb2.FileDescriptorSet()
    seen: set[str] = set()

    def add(fd) -> None:
        if fd.name in seen:
            return
        seen.add(fd.name)
        for dep in fd.dependencies:
            add(dep)
        fd.CopyToProto(fds.file.add())

    add(descriptor.file)
    return fds.SerializeToString()


@pytest.fixture
def pb_file(tmp_path):
    """5 s: /control at 20 Hz (ControlCommand), /pose at 10 Hz (LocalizationEstimate), from 100 s,
    with channel metadata, an attachment and a metadata record."""
    path = tmp_path / "pb.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="", library="test")
        s1 = w.register_schema(control_pb2.ControlCommand.DESCRIPTOR.full_name, "protobuf",
                               _fds(control_pb2.ControlCommand.DESCRIPTOR))
        s2 = w.register_schema(localization_pb2.LocalizationEstimate.DESCRIPTOR.full_name, "protobuf",
                               _fds(localization_pb2.LocalizationEstimate.DESCRIPTOR))
        c1 = w.register_channel("/control", "protobuf", s1,
                                {"rocas.writers": "control", "rocas.role": "control"})
        c2 = w.register_channel("/pose", "protobuf", s2, {"rocas.writers": "localization"})
        t0 = 100 * NS
        for k in range(100):
            t = t0 + k * NS // 20
            msg = control_pb2.ControlCommand(throttle=k * 0.5, brake=1.0, steering_target=-k * 0.1)
            w.add_message(c1, t, msg.SerializeToString(), t, k)
            if k % 2 == 0:
                pose = localization_pb2.LocalizationEstimate(lane_s=k * 1.0)
                pose.header.timestamp_sec = t / NS
                pose.header.sequence_num = k
                w.add_message(c2, t + 1000, pose.SerializeToString(), t + 1000, k)
        w.add_attachment(1, 2, "world.json", "application/json", b"{}")
        w.add_metadata("run", {"seed": "7"})
        w.finish()
    return path


@pytest.fixture
def cdr_file(tmp_path):
    """3 s of a ROS 2 topic /scan at 10 Hz (float64, float32[], int32, string fields)."""
    from mcap_ros2.writer import Writer as Ros2Writer

    path = tmp_path / "cdr.mcap"
    with open(path, "wb") as f:
        w = Ros2Writer(f)
        schema = w.register_msgdef("test_msgs/msg/Scan", ROS_MSG)
        for k in range(30):
            w.write_message("/scan", schema, {"x": k * 1.0, "ranges": [1.0, 2.0, 3.0], "count": k,
                                              "label": "s"}, log_time=k * NS // 10, publish_time=k * NS // 10)
        w.finish()
    return path


def _times(path, topic=None):
    with open(path, "rb") as f:
        return [m.log_time for _, ch, m in make_reader(f).iter_messages(log_time_order=False)
                if topic is None or ch.topic == topic]


def _records(path):
    with open(path, "rb") as f:
        return [(ch.topic, m.log_time, bytes(m.data))
                for _, ch, m in make_reader(f).iter_messages(log_time_order=False)]


def test_rewrite_without_transform_keeps_everything(pb_file, tmp_path):
    out = tmp_path / "out.mcap"
    A.rewrite(pb_file, out)
    a, b = A.read(pb_file), A.read(out)
    assert _records(pb_file) == _records(out)
    assert [(c.topic, c.message_encoding, dict(c.metadata)) for c in a.channels.values()] == \
        [(c.topic, c.message_encoding, dict(c.metadata)) for c in b.channels.values()]
    assert sorted((s.name, s.encoding, s.data) for s in a.schemas.values()) == \
        sorted((s.name, s.encoding, s.data) for s in b.schemas.values())
    assert [(x.name, x.data, x.log_time) for x in b.attachments] == [("world.json", b"{}", 2)]
    assert b.metadata == [("run", {"seed": "7"})]


def test_truncate_end_and_late_start(pb_file, tmp_path):
    t = _times(pb_file)
    A.rewrite(pb_file, tmp_path / "end.mcap", A.truncate_end(1.0))
    assert max(_times(tmp_path / "end.mcap")) <= max(t) - NS
    assert len(_times(tmp_path / "end.mcap")) == sum(x <= max(t) - NS for x in t)
    A.rewrite(pb_file, tmp_path / "start.mcap", A.late_start(0.5))
    assert min(_times(tmp_path / "start.mcap")) >= min(t) + NS // 2
    assert len(_times(tmp_path / "start.mcap")) == sum(x >= min(t) + NS // 2 for x in t)


def test_latched_message_logged_a_second_before_the_rest(pb_file, tmp_path):
    out = tmp_path / "l.mcap"
    A.rewrite(pb_file, out, A.latched_early("/pose", 1.0))
    before, after = _records(pb_file), _records(out)
    assert len(after) == len(before)
    assert after[0][0] == "/pose" and after[0][1] == min(_times(pb_file)) - NS
    assert after[0][2] == next(r for r in before if r[0] == "/pose")[2]
    # default: the channel with the fewest messages (/pose)
    A.rewrite(pb_file, tmp_path / "d.mcap", A.latched_early())
    assert _records(tmp_path / "d.mcap") == after


def test_duplicate_and_lose(pb_file, tmp_path):
    before = _records(pb_file)
    A.rewrite(pb_file, tmp_path / "d.mcap", A.duplicate(seed=3))
    after = _records(tmp_path / "d.mcap")
    assert len(after) == len(before) + 1
    i = next(i for i in range(len(before)) if after[i] != before[i]) if after[:-1] != before else len(before)
    assert after[i] == after[i - 1]
    A.rewrite(pb_file, tmp_path / "l0.mcap", A.lose(0.01, seed=0))
    A.rewrite(pb_file, tmp_path / "l0b.mcap", A.lose(0.01, seed=0))
    A.rewrite(pb_file, tmp_path / "l1.mcap", A.lose(0.05, seed=1))
    lost0 = _records(tmp_path / "l0.mcap")
    assert len(lost0) == len(before) - round(0.01 * len(before))
    assert lost0 == _records(tmp_path / "l0b.mcap")  # seeded
    assert len(_records(tmp_path / "l1.mcap")) == len(before) - round(0.05 * len(before))
    assert all(r in before for r in lost0)


def test_half_rate_clock_and_flush(pb_file, tmp_path):
    ctl = _times(pb_file, "/control")
    A.rewrite(pb_file, tmp_path / "h.mcap", A.half_rate("/control"))
    assert _times(tmp_path / "h.mcap", "/control") == ctl[0::2]
    assert _times(tmp_path / "h.mcap", "/pose") == _times(pb_file, "/pose")

    A.rewrite(pb_file, tmp_path / "c.mcap", A.clock_offset("/pose", 0.5))
    assert _times(tmp_path / "c.mcap", "/pose") == [t + NS // 2 for t in _times(pb_file, "/pose")]
    assert _times(tmp_path / "c.mcap", "/control") == ctl
    # file order kept: the records are in the same sequence, only /pose's times changed
    assert [r[2] for r in _records(tmp_path / "c.mcap")] == [r[2] for r in _records(pb_file)]

    A.rewrite(pb_file, tmp_path / "f.mcap", A.flush_stamps("/control", 1.0))
    flushed = _times(tmp_path / "f.mcap", "/control")
    assert all(f % NS == 0 and t <= f < t + NS for f, t in zip(flushed, ctl, strict=True))
    assert [r[2] for r in _records(tmp_path / "f.mcap")] == [r[2] for r in _records(pb_file)]


def test_jitter_is_bounded_uniform_and_seeded(pb_file, tmp_path):
    t = np.array(_times(pb_file))
    A.rewrite(pb_file, tmp_path / "j.mcap", A.jitter(20.0, seed=5))
    A.rewrite(pb_file, tmp_path / "j2.mcap", A.jitter(20.0, seed=6))
    d = (np.array(_times(tmp_path / "j.mcap")) - t) / 1e6
    assert np.all(np.abs(d) <= 20.0) and d.std() > 5.0 and abs(d.mean()) < 4.0
    assert not np.array_equal(d, (np.array(_times(tmp_path / "j2.mcap")) - t) / 1e6)


def _decoded(path, topic, cls):
    with open(path, "rb") as f:
        return [cls.FromString(m.data) for _, ch, m in make_reader(f).iter_messages(log_time_order=False)
                if ch.topic == topic]


def test_noise_on_protobuf_floats(pb_file, tmp_path):
    A.rewrite(pb_file, tmp_path / "n.mcap", A.noise(0.03, seed=1))
    A.rewrite(pb_file, tmp_path / "n2.mcap", A.noise(0.03, seed=2))
    a = _decoded(pb_file, "/control", control_pb2.ControlCommand)
    b = _decoded(tmp_path / "n.mcap", "/control", control_pb2.ControlCommand)
    d = np.array([[y.throttle - x.throttle, y.brake - x.brake, y.station_error - x.station_error]
                  for x, y in zip(a, b, strict=True)])
    assert 0.02 < d.std() < 0.04 and abs(d.mean()) < 0.01 and np.all(d != 0)
    p0 = _decoded(pb_file, "/pose", localization_pb2.LocalizationEstimate)
    p1 = _decoded(tmp_path / "n.mcap", "/pose", localization_pb2.LocalizationEstimate)
    # nested floats change, integers do not
    assert all(abs(y.header.timestamp_sec - x.header.timestamp_sec) > 0 for x, y in zip(p0, p1, strict=True))
    assert [y.header.sequence_num for y in p1] == [x.header.sequence_num for x in p0]
    assert _records(tmp_path / "n.mcap") != _records(tmp_path / "n2.mcap")  # seeded apart
    assert [r[:2] for r in _records(tmp_path / "n.mcap")] == [r[:2] for r in _records(pb_file)]


def test_step_from_a_known_time(pb_file, tmp_path):
    A.rewrite(pb_file, tmp_path / "s.mcap", A.step("/control", at_s=2.0, amount=1.0))
    before, after = _records(pb_file), _records(tmp_path / "s.mcap")
    t0 = min(_times(pb_file)) + 2 * NS
    for (topic, t, x), (_, _, y) in zip(before, after, strict=True):
        if topic != "/control" or t < t0:
            assert x == y
        else:
            a, b = control_pb2.ControlCommand.FromString(x), control_pb2.ControlCommand.FromString(y)
            assert b.throttle == pytest.approx(a.throttle + 1) and b.brake == pytest.approx(a.brake + 1)


def test_noise_and_step_on_ros2_cdr(cdr_file, tmp_path):
    from mcap_ros2.decoder import DecoderFactory

    A.rewrite(cdr_file, tmp_path / "n.mcap", A.noise(0.05, seed=0), A.step("/scan", at_s=1.0, amount=1.0))

    def decoded(path):
        out = []
        with open(path, "rb") as f:
            for _, _, _, m in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
                out.append((m.x, list(m.ranges), m.count, m.label))
        return out

    a, b = decoded(cdr_file), decoded(tmp_path / "n.mcap")
    assert [r[2:] for r in a] == [r[2:] for r in b]  # int and string fields kept
    dx = np.array([y[0] - x[0] - (1.0 if k >= 10 else 0.0)
                   for k, (x, y) in enumerate(zip(a, b, strict=True))])
    dr = np.array([np.subtract(y[1], x[1]) - (1.0 if k >= 10 else 0.0)
                   for k, (x, y) in enumerate(zip(a, b, strict=True))])
    assert np.all(np.abs(dx) < 0.25) and 0.02 < dx.std() < 0.09
    assert np.all(np.abs(dr) < 0.25) and 0.02 < dr.std() < 0.09


def test_logging_artefacts_keep_the_deviation_inside():
    arts = A.logging_artefacts(deviating_topic="/planning", other_topic="/pose", span_s=12.0, deviation_s=9.0)
    names = [a.name for a in arts]
    assert "truncate_end[0.5s]" in names and "truncate_end[2s]" in names  # 12 - 9 - 1 = 2 s of room
    assert "late_start[0.1s]" in names and "late_start[2s]" in names
    assert {"half_rate[/planning]", "half_rate[/pose]", "clock+0.5s[/planning]", "flush_1s[/pose]",
            "jitter_20ms#0", "jitter_20ms#1", "lose_1%#1", "duplicate#0", "latched_early[1s]"} <= set(names)
