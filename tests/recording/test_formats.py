"""Recordings in other formats, read directly: ROS 1 bags, rosbag2 (.db3, directories) and
Apollo Cyber RT records, on the real recordings in recordings/real (README there)."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from rocas.analysis.diff import diff
from rocas.errors import InputError, RecordingError
from rocas.recording import open_recording
from rocas.recording.annotate import annotate_recording, read_channels
from rocas.recording.cyber import descriptor_set

REAL = Path(__file__).resolve().parents[2] / "recordings" / "real"
BAG = REAL / "turtlesim_example.bag"
RECORD = REAL / "apollo_sim.record.00000"
TALKER = REAL / "talker.db3"
SERVICES_MCAP = REAL / "service_events_mcap"
SERVICES_SQLITE = REAL / "service_events_sqlite3"


def _counts(rec):
    rec.scan()
    return {t: st.messages for t, st in rec.report.channel_stats.items()}


def _first(rec):
    first = {}
    for m in rec.decoded():
        first.setdefault(m.channel.topic, m.message)
    return first


def test_a_ros1_bag_is_read_with_its_writers_and_decoded_fields():
    rec = open_recording(BAG)
    assert rec.format == "ros1" and rec.profile == "ros1"
    first = _first(rec)
    assert rec.report.complete and rec.report.intact
    counts = {t: st.messages for t, st in rec.report.channel_stats.items()}
    assert sum(counts.values()) == 8647
    assert counts["/tf"] == 2688 and counts["/turtle1/pose"] == 1344 and counts["/rosout"] == 10
    assert all(st.decoded == st.messages for st in rec.report.channel_stats.values())
    pose = first["/turtle1/pose"]
    assert pose.__msgtype__ == "turtlesim/msg/Pose"
    assert pose.x == pytest.approx(5.544444561004639)
    assert first["/turtle1/cmd_vel"].linear.x == 2.0
    log = first["/rosout"]
    assert log.header.seq == 3 and log.msg == "Subscribing to /rosout"  # ROS 1 Header has seq
    # callerid is the writer; /tf has two publishers, /rosout three
    writers: dict[str, set[str]] = {}
    for ch in rec.channels.values():
        writers.setdefault(ch.topic, set()).add(ch.metadata["callerid"])
        assert ch.message_encoding == "ros1" and ch.schema_encoding == "ros1msg"
    assert writers["/tf"] == {"/turtle1_tf_broadcaster", "/turtle2_tf_broadcaster"}
    assert writers["/turtle1/cmd_vel"] == {"/teleop"} and len(writers["/rosout"]) == 3
    assert rec.topics()["/turtle1/pose"].schema_name == "turtlesim/Pose"


def test_the_bag_reader_yields_what_rosbags_reads():
    """rocas walks a bag's chunks in file order; rosbags merges its index in time order: the
    same messages, channels and message definitions either way."""
    from collections import Counter

    from rosbags.rosbag1 import Reader

    ours = open_recording(BAG)
    mine = Counter((m.channel.topic, m.log_time_ns, m.data) for m in ours.messages())
    with Reader(BAG) as r:
        theirs = Counter((c.topic, t, bytes(raw)) for c, t, raw in r.messages())
        conns = {c.id: c for c in r.connections}
    assert mine == theirs and sum(mine.values()) == 8647
    for cid, ch in ours.channels.items():
        assert ch.topic == conns[cid].topic
        assert ch.schema_data.decode() == conns[cid].msgdef.data
        assert ch.metadata["callerid"] == conns[cid].ext.callerid


def test_a_rosbag2_db3_file_is_read_and_a_bad_stored_definition_is_reported():
    rec = open_recording(TALKER)
    assert rec.format == "rosbag2"
    first = _first(rec)
    assert first["/topic"].data == "Hello, world! 0"
    st = rec.report.channel_stats
    assert st["/topic"].decoded == 10 and st["/parameter_events"].messages == 0
    # the file's stored definition of rcl_interfaces/msg/Log is one line: said, not hidden
    assert st["/rosout"].messages == 10 and st["/rosout"].undecodable == 10
    assert any("/rosout could not be decoded" in w for w in rec.warnings("talker.db3"))


def test_service_events_decode_from_the_srv_text():
    rec = open_recording(SERVICES_MCAP)
    assert rec.format == "rosbag2"
    events = [m for m in rec.decoded() if m.channel.topic == "/test_service1/_service_event"]
    assert len(events) == 4 and rec.report.intact
    # the client's side of two calls: request sent (0), response received (3)
    assert [m.message.info.event_type for m in events] == [0, 3, 0, 3]
    assert [m.message.info.sequence_number for m in events] == [1, 1, 2, 2]
    sent, received = events[0].message, events[1].message
    assert sent.__msgtype__ == "test_msgs/srv/BasicTypes_Event"
    assert len(sent.request) == 1 and len(sent.response) == 0
    assert len(received.request) == 0 and len(received.response) == 1
    assert sent.request[0].__msgtype__ == "test_msgs/srv/BasicTypes_Request"
    assert received.response[0].__msgtype__ == "test_msgs/srv/BasicTypes_Response"
    ev = sent
    assert isinstance(ev.info.client_gid, np.ndarray) and ev.info.client_gid.shape == (16,)
    # the .mcap file alone (rocas's own MCAP reader) decodes them the same way
    mcap = next(SERVICES_MCAP.glob("*.mcap"))
    direct = open_recording(mcap)
    assert direct.format == "mcap"
    got = [m.message for m in direct.decoded() if m.channel.topic == "/test_service1/_service_event"]
    assert [g.info.sequence_number for g in got] == [e.message.info.sequence_number for e in events]


def test_service_events_without_a_stored_definition_are_counted_with_the_reason():
    rec = open_recording(SERVICES_SQLITE)
    counts = _counts(rec)
    assert counts == {"/events/write_split": 0, "/test_service1/_service_event": 4,
                      "/test_service2/_service_event": 4, "/test_topic1": 1, "/test_topic2": 1}
    sum(1 for _ in rec.decoded())
    st = rec.report.channel_stats["/test_service1/_service_event"]
    assert st.undecodable == 4 and "stores no definition" in st.first_error


def test_an_apollo_record_is_read_with_its_protobuf_schemas():
    rec = open_recording(RECORD)
    assert rec.format == "cyber"
    first = _first(rec)
    assert rec.report.complete and rec.report.intact
    counts = {t: st.messages for t, st in rec.report.channel_stats.items()}
    assert sum(counts.values()) == 34 and len(counts) == 8
    assert counts["/apollo/localization/pose"] == 15 and counts["/apollo/canbus/chassis"] == 15
    assert counts["/apollo/planning"] == 1 and counts["/apollo/monitor"] == 0
    chassis = first["/apollo/canbus/chassis"]
    assert type(chassis).DESCRIPTOR.full_name == "apollo.canbus.Chassis"
    assert chassis.engine_started and chassis.header.module_name
    pose = first["/apollo/localization/pose"]
    assert pose.header.module_name == "SimControl" and pose.pose.position.x > 3e5
    ch = rec.topics()["/apollo/planning"]
    assert ch.message_encoding == "protobuf" and ch.schema_name == "apollo.planning.ADCTrajectory"


def test_a_protodesc_flattens_dependencies_first_and_once():
    from google.protobuf import descriptor_pb2

    from rocas.recording.cyber import _record_classes

    desc = _record_classes()["ProtoDesc"]

    def fdp(name, *deps):
        return descriptor_pb2.FileDescriptorProto(name=name, dependency=list(deps)).SerializeToString()

    common = desc(desc=fdp("common.proto"))
    header = desc(desc=fdp("header.proto", "common.proto"), dependencies=[common])
    root = desc(desc=fdp("root.proto", "header.proto", "common.proto"),
                dependencies=[header, common])
    fds = descriptor_pb2.FileDescriptorSet.FromString(descriptor_set(root.SerializeToString()))
    assert [f.name for f in fds.file] == ["common.proto", "header.proto", "root.proto"]
    with pytest.raises(ValueError, match="no file"):
        descriptor_set(b"")


def test_the_format_is_sniffed_from_the_bytes_not_the_name(tmp_path):
    for src, kind in ((BAG, "ros1"), (RECORD, "cyber"), (TALKER, "rosbag2")):
        for suffix in (".mcap", ".bag", ""):
            odd = tmp_path / f"{kind}{suffix}"
            shutil.copyfile(src, odd)
            rec = open_recording(odd)
            assert rec.format == kind and sum(_counts(rec).values()) > 0


def _cmg(path, control, topics):
    path.write_text(json.dumps({
        "modules": {"stack": {"reads": [], "writes": sorted(topics)}},
        "control_channel": control,
    }))
    return path


@pytest.mark.parametrize(("source", "control"), [
    (BAG, "/turtle1/cmd_vel"), (RECORD, "/apollo/canbus/chassis"), (SERVICES_MCAP, "/test_topic1"),
])
def test_a_recording_and_its_mcap_copy_compare_as_equal(tmp_path, source, control):
    copy = tmp_path / "copy.mcap"
    report = annotate_recording(source, copy, {}, control_channel=control)
    assert report.messages == sum(_counts(open_recording(source)).values())
    assert report.profile == open_recording(source).profile
    infos, counts = read_channels(copy)
    assert counts == {t: n for t, n in _counts(open_recording(source)).items()}
    topics = {c.topic for c in infos}
    cmg = _cmg(tmp_path / "cmg.json", control, topics)
    for a, b in ((source, copy), (copy, source)):  # a pair may mix formats, either way round
        res = diff(a, b, cmg=cmg)
        assert res.messages_read[0] == res.messages_read[1] == report.messages - sum(
            st.undecodable for st in open_recording(source).scan().report.channel_stats.values())
        for row in res.channels:
            assert float(np.max(row.series.mdr, initial=0.0)) == 0.0, row.topic
        assert res.pinpoint.deviating_module is None


def test_a_changed_channel_is_found_across_formats(tmp_path):
    """A bag against an MCAP copy of it in which one channel's messages differ from 10 s on."""
    from mcap.writer import Writer

    copy = tmp_path / "copy.mcap"
    annotate_recording(BAG, copy, {})
    rec = open_recording(copy)
    changed = tmp_path / "changed.mcap"
    start = None
    with open(changed, "wb") as f:
        w = Writer(f)
        w.start(profile="ros1", library="test")
        ids: dict[int, int] = {}
        for m in rec.messages():
            ch = m.channel
            if ch.id not in ids:
                sid = w.register_schema(ch.schema_name, ch.schema_encoding, ch.schema_data)
                ids[ch.id] = w.register_channel(ch.topic, ch.message_encoding, sid, ch.metadata)
            start = m.log_time_ns if start is None else start
            data = m.data
            if ch.topic == "/turtle1/pose" and m.log_time_ns - start > 10e9:
                data = bytes([data[0] ^ 0x40]) + data[1:]  # x changes
            w.add_message(ids[ch.id], m.log_time_ns, data, m.publish_time_ns, m.sequence)
        w.finish()
    cmg = tmp_path / "cmg.json"
    cmg.write_text(json.dumps({"modules": {
        "sim": {"reads": ["/turtle1/cmd_vel"], "writes": ["/turtle1/pose"]},
        "teleop": {"reads": ["/turtle1/pose"], "writes": ["/turtle1/cmd_vel"]},
    }, "control_channel": "/turtle1/cmd_vel"}))
    res = diff(changed, BAG, cmg=cmg)
    rows = {r.topic: r for r in res.channels}
    pose = rows["/turtle1/pose"].series
    assert np.max(pose.mdr) > 0 and float(pose.times_s[np.flatnonzero(pose.mdr)[0]]) >= 9.9
    assert float(np.max(rows["/turtle2/pose"].series.mdr)) == 0.0


# -- damage ----------------------------------------------------------------------------------
def test_a_truncated_bag_keeps_what_was_read_and_warns(tmp_path, rocas):
    cut = tmp_path / "cut.bag"
    cut.write_bytes(BAG.read_bytes()[: BAG.stat().st_size // 2])  # inside its one chunk
    rec = open_recording(cut)
    assert sum(1 for _ in rec.decoded()) == 4899
    assert rec.report.truncated and not rec.report.intact
    warnings = rec.warnings("cut.bag")
    assert any("recording is truncated (the file ends inside the record" in w for w in warnings)
    assert any("index cannot be used" in w for w in warnings)
    full = open_recording(BAG).scan()
    assert {c.topic: (c.metadata, c.schema_data) for c in rec.channels.values()} == {
        c.topic: (c.metadata, c.schema_data) for c in full.channels.values()}
    with pytest.raises(RecordingError, match="annotate copies complete recordings only"):
        annotate_recording(cut, tmp_path / "out.mcap", {})
    # a bag cut before any complete connection: one line
    tiny = tmp_path / "tiny.bag"
    tiny.write_bytes(BAG.read_bytes()[:5000])
    with pytest.raises(RecordingError, match="ROS 1 bag that cannot be read") as info:
        open_recording(tiny)
    assert "rosbag reindex" in info.value.hint
    res = rocas("diff", tiny, BAG)
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("rocas: error:")]
    assert res.code == 3 and len(lines) == 1 and "Traceback" not in res.stderr


def test_an_unindexed_bag_is_read_chunk_by_chunk(tmp_path):
    import struct

    data = bytearray(BAG.read_bytes())
    at = data.index(b"index_pos=") + len("index_pos=")
    data[at : at + 8] = struct.pack("<Q", 0)  # what a recorder stopped early leaves
    bag = tmp_path / "active.bag"
    bag.write_bytes(bytes(data))
    rec = open_recording(bag)
    assert rec.index_problem is not None and "not indexed" in rec.index_problem
    first = _first(rec)
    assert rec.report.complete and not rec.report.truncated
    assert sum(st.decoded for st in rec.report.channel_stats.values()) == 8647
    assert first["/turtle1/pose"].x == pytest.approx(5.544444561004639)


def test_a_truncated_record_keeps_what_was_read_and_warns(tmp_path):
    data = RECORD.read_bytes()
    cut = tmp_path / "cut.record"
    cut.write_bytes(data[:240_000])  # inside the chunk body
    rec = open_recording(cut)
    assert sum(1 for _ in rec.decoded()) == 0
    assert rec.report.truncated and not rec.report.intact
    assert any("truncated" in w for w in rec.warnings("cut.record"))
    assert len(rec.channels) == 8  # the channel sections before the cut were read
    with pytest.raises(RecordingError, match="annotate copies complete recordings only"):
        annotate_recording(cut, tmp_path / "out.mcap", {})
    assert not (tmp_path / "out.mcap").exists()


def test_a_damaged_record_chunk_is_skipped_with_a_warning(tmp_path):
    data = bytearray(RECORD.read_bytes())
    body = 232002 + 16  # the chunk body section's payload
    data[body : body + 64] = b"\xff" * 64
    bad = tmp_path / "bad.record"
    bad.write_bytes(bytes(data))
    rec = open_recording(bad)
    assert sum(1 for _ in rec.decoded()) == 0
    assert rec.report.skipped_chunks and rec.report.complete
    assert any("skipped a corrupted chunk" in w for w in rec.warnings("bad.record"))


def test_a_damaged_record_header_and_db3_are_refused_in_one_line(tmp_path, rocas):
    data = bytearray(RECORD.read_bytes())
    data[16:40] = b"\xff" * 24
    bad = tmp_path / "bad.record"
    bad.write_bytes(bytes(data))
    cut = tmp_path / "cut.db3"
    cut.write_bytes(TALKER.read_bytes()[:5000])
    for path in (bad, cut):
        res = rocas("cmg", path)
        lines = [ln for ln in res.stderr.splitlines() if ln.startswith("rocas: error:")]
        assert res.code == 3 and len(lines) == 1 and "Traceback" not in res.stderr, res.stderr


def test_unknown_formats_get_one_line_naming_them(tmp_path):
    gz = tmp_path / "log.bag"
    gz.write_bytes(b"\x1f\x8b\x08\x00" + b"\x00" * 60)
    with pytest.raises(RecordingError, match="gzip-compressed") as info:
        open_recording(gz)
    assert "decompress it first" in info.value.hint
    old = tmp_path / "old.bag"
    old.write_bytes(b"#ROSBAG V1.2\n" + b"\x00" * 60)
    with pytest.raises(RecordingError, match="old format version"):
        open_recording(old)
    with pytest.raises(InputError, match="no metadata.yaml"):
        open_recording(tmp_path)


def test_view_and_cmg_take_other_formats(tmp_path, rocas):
    out = tmp_path / "bag.rrd"
    res = rocas("view", BAG, "--rrd", out, "--no-viewer")
    assert res.code == 0, res.stderr
    assert "9 channels through Rerun's MCAP importer" in res.stdout and out.stat().st_size > 1e5
    res = rocas("view", SERVICES_MCAP, "--rrd", tmp_path / "dir.rrd", "--no-viewer")
    assert res.code == 0, res.stderr  # a rosbag2 directory is a recording, not a run directory
    res = rocas("cmg", RECORD, "--format", "json")
    assert res.code == 0, res.stderr
    chans = {c["topic"]: c for c in json.loads(res.stdout)["channels"]}
    assert chans["/apollo/planning"]["schema"] == "apollo.planning.ADCTrajectory"
    assert chans["/apollo/localization/pose"]["messages"] == 15


def test_the_cli_diffs_a_mixed_pair_and_annotates_a_bag(tmp_path, rocas):
    cmg = tmp_path / "cmg.json"
    cmg.write_text(json.dumps({"modules": {
        "turtlesim": {"reads": ["/turtle1/cmd_vel"], "writes": ["/turtle1/pose"]},
        "teleop": {"reads": ["/turtle1/pose"], "writes": ["/turtle1/cmd_vel"]},
    }, "control_channel": "/turtle1/cmd_vel"}))
    out = tmp_path / "annotated.mcap"
    res = rocas("annotate", BAG, "--cmg", cmg, "-o", out)
    assert res.code == 0, res.stderr
    assert "8647 messages" in res.stdout and "profile ros1" in res.stdout
    infos, _ = read_channels(out)
    pose = [c for c in infos if c.topic == "/turtle1/pose"]
    assert pose and all(c.metadata["rocas.writers"] == "turtlesim" for c in pose)
    assert all(c.metadata["callerid"] == "/sim" for c in pose)  # kept as it was
    res = rocas("diff", out, BAG, "--json")  # the annotated copy against the bag itself
    assert res.code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["deviating_module"] is None and doc["control_channel"] == "/turtle1/cmd_vel"
    assert all(c["mdr_before"] == 0.0 for c in doc["channels"])


@pytest.mark.parametrize("source", [BAG, RECORD, TALKER], ids=["bag", "record", "db3"])
def test_damaged_copies_give_warnings_or_one_line_never_a_traceback(tmp_path, rocas, source):
    import random

    rng = random.Random(7)
    data = source.read_bytes()
    topics = sorted({c.topic for c in open_recording(source).scan().channels.values()})
    cmg = _cmg(tmp_path / "cmg.json", topics[0], topics)
    for k in range(9):
        d = bytearray(data)
        if k % 3 == 0:  # flipped bytes
            for _ in range(30):
                d[rng.randrange(len(d))] = rng.randrange(256)
        elif k % 3 == 1:  # cut short
            d = d[: rng.randrange(len(d))]
        else:  # a zeroed stretch
            at, n = rng.randrange(len(d)), rng.randrange(1, 5000)
            d[at : at + n] = bytes(len(d[at : at + n]))
        bad = tmp_path / f"bad{source.suffix}"
        bad.write_bytes(bytes(d))
        res = rocas("diff", bad, source, "--cmg", cmg, "--json")
        assert res.code in (0, 3) and "Traceback" not in res.stderr, (k, res.stderr)
        if res.code == 3:
            assert len([ln for ln in res.stderr.splitlines() if ln.startswith("rocas: error:")]) == 1
