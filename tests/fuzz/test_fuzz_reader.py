"""Fuzzing the reader and ``rocas diff`` with mutated real recordings (a CI-sized campaign).

Every input is a deterministic mutation (seed = input number) of one of the seed
recordings written by :func:`fuzz.mutate.write_seeds`: truncations, bit flips, splices
between recordings, corrupted length fields and record edits. The reader must never raise
anything but a :class:`~rocas.errors.RocasError`, ``rocas diff`` must exit 0 or 3 with one
error line, nothing may take more than a few seconds, and memory must stay flat. The
10,000-input campaign is tests/benchmarks/bench_fuzz.py.
"""

from __future__ import annotations

import resource
import struct

import pytest
from fuzz.mutate import KINDS, case, layout, load_seeds, run_one, write_seeds

from rocas.recording import open_recording
from rocas.recording.mcap_records import MAX_CHUNK_BYTES

READER_INPUTS = 360
DIFF_INPUTS = 120


@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    d = tmp_path_factory.mktemp("seeds")
    paths = write_seeds(d)
    return paths, load_seeds(paths)


def test_mutations_are_deterministic_and_cover_every_kind(seeds):
    _, loaded = seeds
    a = [case(loaded, s) for s in range(12)]
    b = [case(loaded, s) for s in range(12)]
    assert a == b
    assert {kind for kind, _, _ in a} == set(KINDS)
    assert all(data != loaded[0][0] for _, data, _ in a[:6])


def test_the_reader_survives_mutated_recordings(seeds, tmp_path):
    paths, loaded = seeds
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    failures = []
    for s in range(READER_INPUTS):
        kind, data, what = case(loaded, s)
        try:
            run_one(data, tmp_path / "in.mcap", paths[1], limit_s=5.0, diff=False)
        except Exception as exc:  # collect them all: one report lists every failing seed
            failures.append(f"seed {s} ({kind}: {what}): {type(exc).__name__}: {exc}")
    assert not failures, "\n".join(failures[:20])
    grown_mb = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss_before) / 1024
    assert grown_mb < 200, f"peak RSS grew by {grown_mb:.0f} MB"


def test_rocas_diff_survives_mutated_recordings(seeds, tmp_path):
    paths, loaded = seeds
    failures = []
    for s in range(10_000, 10_000 + DIFF_INPUTS):
        kind, data, what = case(loaded, s)
        try:
            run_one(data, tmp_path / "in.mcap", paths[1], limit_s=10.0, diff=True)
        except Exception as exc:
            failures.append(f"seed {s} ({kind}: {what}): {type(exc).__name__}: {exc}")
    assert not failures, "\n".join(failures[:20])


# -- regressions: inputs the fuzzer found ---------------------------------------------------


@pytest.fixture(scope="module")
def long_run(tmp_path_factory):
    from foreign_stack import write_run

    path = tmp_path_factory.mktemp("long") / "long.mcap"
    write_run(path, accident=True, duration_s=8)
    data = path.read_bytes()
    chunks = [(off, size) for off, op, size in layout(data).records if op == 0x06]
    assert len(chunks) >= 3
    return data, chunks, sum(1 for _ in open_recording(path).decoded())


@pytest.mark.parametrize("claimed", [3 << 30, 100, 0, (1 << 64) - 1])
def test_a_corrupted_chunk_length_skips_that_chunk_only(long_run, tmp_path, claimed):
    # was: "truncated (record at offset 36 claims 3221225472 bytes ...)", 0 messages read
    data, chunks, total = long_run
    buf = bytearray(data)
    struct.pack_into("<Q", buf, chunks[0][0] + 1, claimed)
    path = tmp_path / "bad.mcap"
    path.write_bytes(bytes(buf))
    rec = open_recording(path)
    n = sum(1 for _ in rec.decoded())
    assert 0 < n < total
    warnings = "\n".join(rec.report.warnings("bad"))
    assert f"damaged data at offset {chunks[0][0]}" in warnings
    assert f"resumed at offset {chunks[1][0]}" in warnings or "resumed at offset" in warnings
    assert "summary section" in warnings  # the lost channel declarations came back
    assert not rec.report.truncated


def test_a_huge_uncompressed_size_is_refused_without_allocating(long_run, tmp_path):
    data, chunks, total = long_run
    off = chunks[1][0] + 9 + 16  # record header, message start/end times
    for claimed in (MAX_CHUNK_BYTES + 1, 1 << 40, (1 << 64) - 1):
        buf = bytearray(data)
        struct.pack_into("<Q", buf, off, claimed)
        path = tmp_path / "bomb.mcap"
        path.write_bytes(bytes(buf))
        rec = open_recording(path)
        n = sum(1 for _ in rec.decoded())
        assert 0 < n < total
        assert rec.report.skipped_chunks[0][0] == chunks[1][0]
        assert "uncompressed" in rec.report.skipped_chunks[0][1]


def test_a_slightly_wrong_uncompressed_size_is_caught(long_run, tmp_path):
    data, chunks, total = long_run
    off = chunks[1][0] + 9 + 16
    buf = bytearray(data)
    (size,) = struct.unpack_from("<Q", buf, off)
    struct.pack_into("<Q", buf, off, size + 1000)
    path = tmp_path / "off.mcap"
    path.write_bytes(bytes(buf))
    rec = open_recording(path)
    assert 0 < sum(1 for _ in rec.decoded()) < total
    assert "header says" in rec.report.skipped_chunks[0][1]


def test_an_invalid_opcode_resynchronises(long_run, tmp_path):
    data, chunks, total = long_run
    buf = bytearray(data)
    buf[chunks[1][0]] = 0x42  # neither a spec opcode nor a user one
    path = tmp_path / "op.mcap"
    path.write_bytes(bytes(buf))
    rec = open_recording(path)
    assert 0 < sum(1 for _ in rec.decoded()) < total
    assert "invalid record opcode 0x42" in "\n".join(rec.report.warnings("op"))


def test_cutting_at_every_record_boundary_never_loses_earlier_messages(long_run, tmp_path):
    data, _, total = long_run
    counts = []
    for off, _, _ in layout(data).records:
        path = tmp_path / "cut.mcap"
        path.write_bytes(data[:off])
        counts.append(sum(1 for _ in open_recording(path).decoded()))
    assert counts == sorted(counts) and counts[-1] == total
