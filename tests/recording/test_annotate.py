"""annotate_recording: the topology is added, everything else survives the copy exactly."""

from __future__ import annotations

import json
import struct

import pytest
from google.protobuf import descriptor_pb2, timestamp_pb2
from mcap.records import Attachment, Channel, Chunk, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter

from rocas.analysis.cmg import parse_cmg, resolve_topology
from rocas.errors import InputError, RecordingError, TopologyError, UsageError
from rocas.recording import ChannelAnnotation, annotate_recording, read_channels


def _fds(message_type) -> bytes:
    fds = descriptor_pb2.FileDescriptorSet()
    message_type.DESCRIPTOR.file.CopyToProto(fds.file.add())
    return fds.SerializeToString()


def write_foreign(path, *, compression=CompressionType.LZ4, chunked=True, profile="x-acme"):
    """A recording rocas did not write: a well-known protobuf type, JSON, ROS 1, no schema."""
    with open(path, "wb") as f:
        w = McapWriter(f, compression=compression, use_chunking=chunked, chunk_size=4096)
        w.start(profile=profile, library="acme-logger 2.1")
        ts = w.register_schema("google.protobuf.Timestamp", "protobuf",
                               _fds(timestamp_pb2.Timestamp))
        js = w.register_schema("Diag", "jsonschema", b'{"type": "object"}')
        ros = w.register_schema("sensor_msgs/Range", "ros1msg", b"float32 range")
        clock = w.register_channel("/clock", "protobuf", ts,
                                   {"frame": "utc", "rocas.readers": "old_reader"})
        diag = w.register_channel("/diag", "json", js)
        rng = w.register_channel("/range", "ros1", ros, {"callerid": "/sonar_node"})
        raw = w.register_channel("/raw", "application/octet-stream", 0, {})
        w.add_metadata("vehicle", {"vin": "ACME0001", "build": "42"})
        w.add_attachment(create_time=7, log_time=8, name="calib.yaml", media_type="text/yaml",
                         data=b"k: 1\n")
        for i in range(60):
            t = 1_000_000_000 + (i * 7919 % 60) * 10_000_000  # not in log-time order
            w.add_message(clock, log_time=t, publish_time=t - 5,
                          data=timestamp_pb2.Timestamp(seconds=i).SerializeToString(),
                          sequence=1000 + i)
            w.add_message(diag, log_time=t + 1, publish_time=t + 1,
                          data=json.dumps({"i": i}).encode(), sequence=i % 3)
            w.add_message(rng, log_time=t + 2, publish_time=0, data=bytes([i]) * 4)
            w.add_message(raw, log_time=t + 3, publish_time=t, data=b"\x00" * (i % 5))
        w.add_metadata("run", {"weather": "rain"})
        w.add_attachment(create_time=0, log_time=9, name="map.bin",
                         media_type="application/octet-stream", data=bytes(range(256)) * 8)
        w.finish()


def _records(data: bytes) -> list[tuple[int, int]]:
    """(offset, opcode) of every top-level record of a complete MCAP file."""
    out, pos = [], 8
    while pos < len(data) - 8:
        opcode, length = struct.unpack_from("<BQ", data, pos)
        out.append((pos, opcode))
        pos += 9 + length
    return out


def dump(path):
    """Every record of the data section that annotate promises to keep, in file order."""
    schemas, channels, out = {}, {}, {"messages": [], "attachments": [], "metadata": [],
                                      "compression": set(), "channels": {}}
    with open(path, "rb") as f:
        for rec in StreamReader(f, emit_chunks=True).records:
            inner = breakup_chunk(rec) if isinstance(rec, Chunk) else [rec]
            if isinstance(rec, Chunk):
                out["compression"].add(rec.compression)
            for r in inner:
                if isinstance(r, Header):
                    out["header"] = (r.profile, r.library)
                elif isinstance(r, Schema):
                    schemas[r.id] = (r.name, r.encoding, bytes(r.data))
                elif isinstance(r, Channel):
                    channels[r.id] = r
                    out["channels"][r.topic] = (
                        r.message_encoding, schemas.get(r.schema_id), dict(r.metadata))
                elif isinstance(r, Message):
                    out["messages"].append((channels[r.channel_id].topic, r.log_time,
                                            r.publish_time, r.sequence, bytes(r.data)))
                elif isinstance(r, Attachment):
                    out["attachments"].append((r.name, r.media_type, r.create_time,
                                               r.log_time, bytes(r.data)))
                elif isinstance(r, Metadata):
                    out["metadata"].append((r.name, dict(r.metadata)))
    return out


CMG = parse_cmg({
    "modules": {
        "clock_driver": {"writes": ["/clock"]},
        "monitor": {"reads": ["/clock", "/range"], "writes": ["/diag"]},
    },
    "control_channel": "/diag",
})


@pytest.mark.parametrize(
    ("compression", "chunked", "expected"),
    [(CompressionType.LZ4, True, {"lz4"}), (CompressionType.ZSTD, True, {"zstd"}),
     (CompressionType.NONE, True, {""}), (CompressionType.NONE, False, set())],
)
def test_round_trip_is_lossless_except_for_the_topology(tmp_path, compression, chunked,
                                                         expected):
    src, dst = tmp_path / "in.mcap", tmp_path / "out.mcap"
    write_foreign(src, compression=compression, chunked=chunked)
    before = src.read_bytes()
    report = annotate_recording(src, dst, CMG.annotations(), control_channel="/diag")
    assert src.read_bytes() == before  # the input is never touched
    a, b = dump(src), dump(dst)
    assert b["header"] == a["header"] == ("x-acme", "acme-logger 2.1")
    assert b["messages"] == a["messages"] and len(b["messages"]) == 240
    assert b["attachments"] == a["attachments"] and len(b["attachments"]) == 2
    assert b["metadata"] == a["metadata"]
    assert a["compression"] == b["compression"] == expected
    assert report.compression == (None if not chunked else next(iter(expected)))
    assert (report.messages, report.channels, report.schemas) == (240, 4, 3)
    assert (report.attachments, report.metadata) == (2, 2)
    # channels: everything but the topology keys is as it was
    for topic, (enc, schema, meta) in a["channels"].items():
        enc2, schema2, meta2 = b["channels"][topic]
        assert (enc2, schema2) == (enc, schema)
        kept = {k: v for k, v in meta.items() if not k.startswith("rocas.")}
        assert {k: v for k, v in meta2.items() if not k.startswith("rocas.")} == kept
    assert b["channels"]["/clock"][2] == {"frame": "utc", "rocas.writers": "clock_driver",
                                          "rocas.readers": "monitor"}
    assert b["channels"]["/diag"][2] == {"rocas.writers": "monitor", "rocas.role": "control"}
    assert b["channels"]["/range"][2] == {"callerid": "/sonar_node", "rocas.readers": "monitor"}
    assert b["channels"]["/raw"][2] == {}
    assert report.annotated == ("/clock", "/diag", "/range")


def test_annotated_file_reads_like_the_input_plus_the_cmg_file(tmp_path):
    src, dst = tmp_path / "in.mcap", tmp_path / "out.mcap"
    write_foreign(src)
    annotate_recording(src, dst, CMG.annotations(), control_channel=CMG.control_channel)
    strip = lambda topo: {t: (c.writers, c.readers, c.is_control) for t, c in topo.items()}  # noqa: E731
    with_file = resolve_topology(read_channels(src)[0], CMG)
    stored = resolve_topology(read_channels(dst)[0])
    assert strip(stored) == strip(with_file)
    assert stored["/clock"].writers_source == "metadata"
    assert stored["/range"].writers_source == "callerid"  # the recorded convention still counts
    assert read_channels(dst)[1] == {"/clock": 60, "/diag": 60, "/range": 60, "/raw": 60}


def test_control_channel_moves_and_unnamed_channels_keep_their_metadata(tmp_path):
    src, mid, dst = tmp_path / "in.mcap", tmp_path / "mid.mcap", tmp_path / "out.mcap"
    write_foreign(src)
    annotate_recording(src, mid, {}, control_channel="/diag")
    annotate_recording(mid, dst, {"/raw": ChannelAnnotation(writers=("dumper",))},
                       control_channel="/clock")
    ch = dump(dst)["channels"]
    assert ch["/clock"][2]["rocas.role"] == "control"
    assert "rocas.role" not in ch["/diag"][2]
    assert ch["/clock"][2]["rocas.readers"] == "old_reader"  # not named: kept
    assert ch["/raw"][2] == {"rocas.writers": "dumper"}


def test_names_the_recording_lacks_are_reported_not_fatal(tmp_path):
    src, dst = tmp_path / "in.mcap", tmp_path / "out.mcap"
    write_foreign(src)
    report = annotate_recording(src, dst, {"/ghost": ChannelAnnotation(writers=("x",))})
    assert report.missing == ("/ghost",) and report.annotated == ()


def test_refusals_leave_no_output(tmp_path):
    src, dst = tmp_path / "in.mcap", tmp_path / "out.mcap"
    write_foreign(src)
    with pytest.raises(UsageError, match="is the input recording"):
        annotate_recording(src, tmp_path / "." / "in.mcap", {})
    with pytest.raises(TopologyError, match="'/nope' is not in"):
        annotate_recording(src, dst, {}, control_channel="/nope")
    assert not dst.exists()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(src.read_bytes()[: src.stat().st_size // 2])
    with pytest.raises(RecordingError) as info:
        annotate_recording(cut, dst, {})
    # was "(EndOfFile: )": the message says what is wrong, in words
    start = max(off for off, _ in _records(src.read_bytes()) if off < cut.stat().st_size)
    assert info.value.message == (
        f"{cut} is truncated: it ends at byte {cut.stat().st_size}, in the middle of the record "
        f"that starts at byte {start}; annotate copies complete recordings only"
    )
    assert "mcap recover" in info.value.hint
    cut.write_bytes(src.read_bytes()[:start])  # ends exactly where a record ends
    with pytest.raises(RecordingError, match=f"is truncated: it ends at byte {start}, after a "
                       "complete record but before the end of its data section"):
        annotate_recording(cut, dst, {})
    assert not dst.exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    with pytest.raises(InputError, match="no such file"):
        annotate_recording(tmp_path / "missing.mcap", dst, {})


def test_damage_inside_a_chunk_is_described_in_words():
    from mcap.exceptions import EndOfFile

    from rocas.recording.annotate import _damage

    assert _damage(EndOfFile(), 100, 500, copying=True, at_end=False) == (
        "is damaged: a record inside the chunk at byte 100 ends early"
    )
    assert _damage(ValueError(""), 100, 500, copying=False, at_end=False) == (
        "is damaged or truncated (ValueError)"
    )


def test_repair_and_convert_hints_name_tools_that_are_installed(tmp_path):
    """The mcap CLI is not installed by pip: hints say so and name what is installed."""
    import shutil
    import subprocess

    from rocas.errors import RecordingError
    from rocas.recording import open_recording
    from rocas.recording.annotate import REPAIR_HINT

    assert "separate download" in REPAIR_HINT and "'rerun mcap check FILE'" in REPAIR_HINT
    rerun = shutil.which("rerun")
    assert rerun is not None
    done = subprocess.run([rerun, "mcap", "check", "--help"], capture_output=True, timeout=60,
                          check=False)
    assert done.returncode == 0
    not_mcap = tmp_path / "log.dat"  # no format rocas reads (bags and .db3 are read directly)
    not_mcap.write_bytes(b"some other logger's format\x00")
    with pytest.raises(RecordingError) as info:
        open_recording(not_mcap)
    assert "rosbags-convert" in info.value.hint and shutil.which("rosbags-convert") is not None
    broken_db3 = tmp_path / "bag.db3"
    broken_db3.write_bytes(b"SQLite format 3\x00")
    with pytest.raises(RecordingError, match="rosbag2 .db3 file that cannot be read") as info:
        open_recording(broken_db3)
    assert "ros2 bag reindex" in info.value.hint
