"""attach_channel: the topology on the MCAP writer a pipeline already uses, messages unchanged."""

from __future__ import annotations

import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.writer import Writer as McapWriter
from mcap_protobuf.writer import Writer as ProtobufWriter

from rocas.analysis.cmg import build_cmg, control_channel
from rocas.errors import UsageError
from rocas.recording import RecordingWriter, attach_channel, open_recording

F = descriptor_pb2.FieldDescriptorProto


def _foreign_types():
    """Two message types of a stack that is not rocas's, built at run time."""
    fd = descriptor_pb2.FileDescriptorProto(name="other/msgs.proto", package="other",
                                            syntax="proto3")
    wp = fd.message_type.add(name="Waypoint")
    wp.field.add(name="x", number=1, type=F.TYPE_DOUBLE, label=F.LABEL_OPTIONAL)
    wp.field.add(name="v", number=2, type=F.TYPE_DOUBLE, label=F.LABEL_OPTIONAL)
    path = fd.message_type.add(name="Path")
    path.field.add(name="points", number=1, type=F.TYPE_MESSAGE, label=F.LABEL_REPEATED,
                   type_name=".other.Waypoint")
    path.field.add(name="frame", number=2, type=F.TYPE_STRING, label=F.LABEL_OPTIONAL)
    pool = descriptor_pool.DescriptorPool()
    pool.Add(fd)
    return tuple(message_factory.GetMessageClass(pool.FindMessageTypeByName(f"other.{n}"))
                 for n in ("Waypoint", "Path"))


Waypoint, Path = _foreign_types()


def _path(i: int):
    return Path(points=[Waypoint(x=float(i), v=2.0)], frame=f"f{i}")


def _read(path):
    rec = open_recording(path)
    msgs = [(m.channel.topic, m.log_time_ns, m.sequence, m.message) for m in rec.decoded()]
    return rec, msgs


def test_plain_mcap_writer(tmp_path):
    out = tmp_path / "plain.mcap"
    with open(out, "wb") as f:
        w = McapWriter(f)
        w.start()
        plan = attach_channel(w, "/plan", Path, writers=["planner"], readers=["ctrl"])
        ref = attach_channel(w, "/ref", Path, writers=["router"], readers=["planner"])
        cmd = attach_channel(w, "/cmd", Waypoint, writers=["ctrl"], role="control",
                             metadata={"frame": "base"})
        for i in range(3):
            w.add_message(plan, log_time=i, publish_time=i, data=_path(i).SerializeToString(),
                          sequence=i)
            w.add_message(ref, log_time=i, publish_time=i, data=_path(i).SerializeToString())
            w.add_message(cmd, log_time=i, publish_time=i,
                          data=Waypoint(v=float(i)).SerializeToString())
        w.finish()
    rec, msgs = _read(out)
    by_topic = rec.topics()
    assert by_topic["/plan"].metadata == {"rocas.writers": "planner", "rocas.readers": "ctrl"}
    assert by_topic["/cmd"].metadata == {"frame": "base", "rocas.writers": "ctrl",
                                         "rocas.role": "control"}
    # one schema record for a type shared by two channels
    assert by_topic["/plan"].schema_id == by_topic["/ref"].schema_id
    assert [m for t, _, _, m in msgs if t == "/plan"][2].points[0].x == 2.0
    graph = build_cmg(rec.channels.values())
    assert control_channel(graph) == "/cmd"
    assert graph.channels_written_by("planner") == ["/plan"]


def test_mcap_protobuf_writer_keeps_write_message(tmp_path):
    out = tmp_path / "pb.mcap"
    with open(out, "wb") as f, ProtobufWriter(f) as w:
        plan_id = attach_channel(w, "/plan", Path, writers=["planner"], readers=["ctrl"])
        attach_channel(w, "/cmd", Waypoint, writers=["ctrl"], role="control")
        for i in range(4):
            w.write_message("/plan", _path(i), log_time=10 + i, publish_time=10 + i,
                            sequence=i)
            w.write_message("/cmd", Waypoint(v=i), log_time=10 + i, publish_time=10 + i)
            w.write_message("/extra", Waypoint(x=i), log_time=10 + i, publish_time=10 + i)
    rec, msgs = _read(out)
    by_topic = rec.topics()
    assert by_topic["/plan"].id == plan_id
    assert by_topic["/plan"].metadata == {"rocas.writers": "planner", "rocas.readers": "ctrl"}
    assert by_topic["/cmd"].metadata["rocas.role"] == "control"
    assert by_topic["/extra"].metadata == {}  # channels not attached behave as before
    assert len(rec.channels) == 3  # write_message reused the pre-registered channels
    assert [(t, s) for t, _, s, _ in msgs if t == "/plan"] == [("/plan", i) for i in range(4)]
    assert [m.v for t, _, _, m in msgs if t == "/cmd"] == [0.0, 1.0, 2.0, 3.0]


def test_mcap_protobuf_writer_checks_the_type_of_attached_topics(tmp_path):
    with open(tmp_path / "t.mcap", "wb") as f, ProtobufWriter(f) as w:
        attach_channel(w, "/plan", Path)
        with pytest.raises(ValueError, match="cannot write a other.Waypoint"):
            w.write_message("/plan", Waypoint())


def test_attaching_after_the_first_message_is_refused(tmp_path):
    with open(tmp_path / "late.mcap", "wb") as f, ProtobufWriter(f) as w:
        w.write_message("/plan", _path(0), log_time=0, publish_time=0)
        with pytest.raises(UsageError, match="already registered") as info:
            attach_channel(w, "/plan", Path, writers=["planner"])
        assert "before the first write_message" in info.value.hint


def test_rocas_recording_writer_and_wrong_writer_kinds(tmp_path):
    with RecordingWriter(tmp_path / "r.mcap") as w:
        attach_channel(w, "/plan", Path, writers=["planner"])
        w.write("/plan", _path(1), log_time_ns=5)
    rec, msgs = _read(tmp_path / "r.mcap")
    assert rec.topics()["/plan"].metadata == {"rocas.writers": "planner"}
    assert msgs[0][3].frame == "f1"
    with pytest.raises(UsageError, match="needs an MCAP writer"):
        attach_channel(object(), "/plan", Path)  # type: ignore[arg-type]
