import json
import random
import struct

import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from rocas.errors import InputError, RecordingError
from rocas.msgs import control_pb2, planning_pb2
from rocas.recording import RecordingWriter, mcap_records, open_recording


def _write(path, n=300, chunk_size=2048, compression="zstd"):
    with RecordingWriter(path, chunk_size=chunk_size, compression=compression) as w:
        w.add_channel("/control", control_pb2.ControlCommand, writers=["control"], role="control")
        w.add_channel("/planning", planning_pb2.ADCTrajectory, writers=["planning"],
                      readers=["control"])
        for i in range(n):
            w.write("/control", control_pb2.ControlCommand(throttle=i), log_time_ns=i * 10**7)
            m = planning_pb2.ADCTrajectory(lane_id=f"l{i}")
            w.write("/planning", m, log_time_ns=i * 10**7 + 1)
        w.add_attachment("rocas/world.json", b'{"lanes": []}', media_type="application/json")
    return path


def _chunk_offsets(path):
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    return sorted(ci.chunk_start_offset for ci in summary.chunk_indexes)


def test_reads_messages_channels_and_attachments(tmp_path):
    rec = open_recording(_write(tmp_path / "r.mcap"))
    msgs = list(rec.decoded())
    assert len(msgs) == 600
    assert msgs[0].message.throttle == 0 and msgs[1].message.lane_id == "l0"
    assert rec.report.complete and not rec.report.truncated
    topics = rec.topics()
    assert topics["/control"].metadata["rocas.role"] == "control"
    assert topics["/planning"].metadata["rocas.readers"] == "control"
    assert rec.attachment("rocas/world.json") == b'{"lanes": []}'
    assert rec.report.channel_stats["/control"].decoded == 300


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_every_compression_reads(tmp_path, compression):
    rec = open_recording(_write(tmp_path / "r.mcap", compression=compression))
    assert sum(1 for _ in rec.decoded()) == 600


def test_truncated_file_is_read_up_to_the_last_complete_record(tmp_path):
    path = _write(tmp_path / "r.mcap")
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    rec = open_recording(cut)
    n = sum(1 for _ in rec.decoded())
    assert 0 < n < 600
    assert rec.report.truncated
    (warning,) = rec.report.warnings("cut.mcap")
    assert "truncated" in warning and "stopped at offset" in warning


def test_corrupted_chunk_is_skipped_with_its_offset(tmp_path):
    path = _write(tmp_path / "r.mcap")
    offsets = _chunk_offsets(path)
    assert len(offsets) > 3
    data = bytearray(path.read_bytes())
    target = offsets[1]
    for k in range(60, 80):  # inside the chunk's compressed records
        data[target + k] ^= 0xFF
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    rec = open_recording(bad)
    n = sum(1 for _ in rec.decoded())
    assert 0 < n < 600
    assert rec.report.skipped_chunks and rec.report.skipped_chunks[0][0] == target
    assert any(f"offset {target}" in w for w in rec.report.warnings("bad.mcap"))


def test_missing_empty_and_foreign_files_are_refused(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        open_recording(tmp_path / "nope.mcap")
    (tmp_path / "empty.mcap").write_bytes(b"")
    with pytest.raises(RecordingError, match="empty"):
        open_recording(tmp_path / "empty.mcap")
    (tmp_path / "x.mcap").write_text("hello, this is text")
    with pytest.raises(RecordingError, match="not an MCAP file"):
        open_recording(tmp_path / "x.mcap")
    with pytest.raises(InputError, match="directory"):
        open_recording(tmp_path)


def test_foreign_encodings_are_counted_not_fatal(tmp_path):
    path = tmp_path / "mixed.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        js = w.register_schema("s", "jsonschema", b"{}")
        ros = w.register_schema("std_msgs/String", "ros1msg", b"string data")
        cj = w.register_channel("/json", "json", js)
        cr = w.register_channel("/ros", "msgpack", ros)  # ros1 is decoded: see test_formats
        cb = w.register_channel("/broken", "protobuf", 0)
        for i in range(5):
            w.add_message(cj, log_time=i, publish_time=i, data=json.dumps({"i": i}).encode())
            w.add_message(cr, log_time=i, publish_time=i, data=b"\x01\x00\x00\x00x")
            w.add_message(cb, log_time=i, publish_time=i, data=b"\x08\x01")
        w.finish()
    rec = open_recording(path)
    decoded = list(rec.decoded())
    assert [m.message for m in decoded] == [{"i": i} for i in range(5)]
    stats = rec.report.channel_stats
    assert stats["/ros"].skipped_encoding == 5
    assert stats["/broken"].undecodable == 5
    warnings = " ".join(rec.report.warnings("mixed.mcap"))
    assert "/ros" in warnings and "/broken" in warnings


def test_the_writer_is_atomic(tmp_path):
    out = tmp_path / "out.mcap"
    out.write_bytes(b"previous content")
    with pytest.raises(RuntimeError):
        with RecordingWriter(out) as w:
            w.add_channel("/control", control_pb2.ControlCommand)
            w.write("/control", control_pb2.ControlCommand(), log_time_ns=0)
            raise RuntimeError("interrupted")
    assert out.read_bytes() == b"previous content"
    assert list(tmp_path.iterdir()) == [out]


def _unchunked(path, payloads):
    """An unchunked JSON recording, one message per payload; returns the message offsets."""
    with open(path, "wb") as f:
        w = Writer(f, use_chunking=False)
        w.start()
        cid = w.register_channel("/j", "json", w.register_schema("s", "jsonschema", b"{}"))
        offsets = []
        for i, data in enumerate(payloads):
            offsets.append(f.tell())
            w.add_message(cid, log_time=i, publish_time=i, data=data)
        w.finish()
    return offsets


def test_resync_tries_candidates_that_overlap_a_real_header(tmp_path):
    # Each message ends in 0x07, so one byte before every message header reads as a record
    # header too (opcode 0x07, a length that runs past the file): a resync must try the
    # real header one byte later instead of skipping past it.
    payloads = [json.dumps({"i": i, "pad": "x" * 20}).encode() + b" \x07" for i in range(6)]
    path = tmp_path / "u.mcap"
    offsets = _unchunked(path, payloads)
    data = bytearray(path.read_bytes())
    struct.pack_into("<Q", data, offsets[2] + 1, 1 << 40)  # message 2's length is corrupted
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    rec = open_recording(bad)
    seqs = [m.log_time_ns for m in rec.messages()]
    assert seqs == [0, 1, 3, 4, 5]  # only the damaged message is lost
    ((offset, size, _),) = rec.report.skipped_ranges
    assert (offset, offset + size) == (offsets[2], offsets[3])


def _one_big_message(path, payload, chunked):
    with open(path, "wb") as f:
        w = Writer(f, use_chunking=chunked, compression=CompressionType.ZSTD)
        w.start()
        cid = w.register_channel("/b", "json", w.register_schema("s", "jsonschema", b"{}"))
        for i in range(3):
            w.add_message(cid, log_time=i, publish_time=i, data=b"small")
        w.add_message(cid, log_time=3, publish_time=3, data=payload)
        w.add_message(cid, log_time=4, publish_time=4, data=b"after")
        w.finish()
    return path


@pytest.mark.parametrize("chunked", [True, False])
def test_a_record_over_the_memory_limit_is_read_when_it_fits_the_file(
    tmp_path, monkeypatch, chunked
):
    # the limits stand for 512 MiB: a 10 KiB message plays a 600 MiB one
    monkeypatch.setattr(mcap_records, "MAX_RECORD_BYTES", 4096)
    monkeypatch.setattr(mcap_records, "MAX_CHUNK_BYTES", 4096)
    payload = random.Random(0).randbytes(10_000)  # incompressible: the file holds it all
    rec = open_recording(_one_big_message(tmp_path / "big.mcap", payload, chunked))
    msgs = list(rec.messages())
    assert [m.log_time_ns for m in msgs] == [0, 1, 2, 3, 4]
    assert msgs[3].data == payload
    assert rec.report.complete and rec.report.warnings("big") == []


def test_a_long_length_that_ends_inside_a_record_is_still_damage(tmp_path, monkeypatch):
    monkeypatch.setattr(mcap_records, "MAX_RECORD_BYTES", 4096)
    payloads = [json.dumps({"i": i, "pad": "x" * 1000}).encode() for i in range(8)]
    path = tmp_path / "u.mcap"
    offsets = _unchunked(path, payloads)
    data = bytearray(path.read_bytes())
    struct.pack_into("<Q", data, offsets[1] + 1, 5000)  # fits in the file, ends mid-record
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    rec = open_recording(bad)
    assert [m.log_time_ns for m in rec.messages()] == [0, 2, 3, 4, 5, 6, 7]
    ((offset, size, reason),) = rec.report.skipped_ranges
    assert (offset, offset + size) == (offsets[1], offsets[2])
    assert "claims 5000 bytes (over 4096 bytes) but no record starts where it would end" in reason


def test_a_chunk_inflating_beyond_the_limit_and_the_file_size_is_skipped(tmp_path, monkeypatch):
    monkeypatch.setattr(mcap_records, "MAX_CHUNK_BYTES", 4096)
    path = _one_big_message(tmp_path / "z.mcap", bytes(10_000), chunked=True)
    assert path.stat().st_size < 10_000  # zeros compress: the chunk inflates past the file
    rec = open_recording(path)
    assert list(rec.messages()) == []
    ((_, reason),) = rec.report.skipped_chunks
    assert "more than rocas inflates (4096 bytes: 4096 bytes or the file's size" in reason


@pytest.mark.parametrize("frames", [1, 2])
def test_a_zstd_chunk_inflates_whether_it_is_one_frame_or_several(frames):
    """One frame that states its size is inflated in one call; anything else (here two
    frames, or a frame one byte short of what the chunk claims) takes the streamed path."""
    import zlib

    import zstandard
    from mcap.records import Chunk

    raw = bytes(range(256)) * 300
    parts = [raw] if frames == 1 else [raw[:1000], raw[1000:]]
    data = b"".join(zstandard.ZstdCompressor().compress(p) for p in parts)
    chunk = Chunk(compression="zstd", data=data, message_start_time=0, message_end_time=0,
                  uncompressed_crc=zlib.crc32(raw), uncompressed_size=len(raw))
    assert mcap_records.inflate(chunk, 1 << 20) == raw
    assert (mcap_records.inflate_one_frame(data, len(raw)) is None) == (frames == 2)
    short = Chunk(compression="zstd", data=data, message_start_time=0, message_end_time=0,
                  uncompressed_crc=0, uncompressed_size=len(raw) + 1)
    with pytest.raises(ValueError, match="inflates to"):
        mcap_records.inflate(short, 1 << 20)
