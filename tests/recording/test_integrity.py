"""Metadata records carry a checksum that the reader verifies (issue 21: a flipped bit in the
recorded ego's mission changed the replayed scenario without a word)."""

from pathlib import Path

import pytest
from mcap.writer import Writer

from rocas.recording import RecordingWriter
from rocas.recording.formats import open_recording
from rocas.recording.integrity import CHECKSUM_KEY, checksum_problem, with_checksum
from rocas.replay.reconstruction import reconstruct

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"


def _write(path: Path, metadata: dict[str, str]) -> None:
    with RecordingWriter(path) as w:
        w.add_metadata("rocas.ego", metadata)


def _flip_in(data: bytes, text: bytes) -> bytes:
    at = data.index(text)
    return data[:at] + bytes([data[at] ^ 0x01]) + data[at + 1 :]


def test_a_record_reads_back_as_written_without_its_checksum(tmp_path):
    path = tmp_path / "r.mcap"
    _write(path, {"start_speed_mps": "8.0", "route": "a,b"})
    rec = open_recording(path).scan()
    assert rec.metadata == [("rocas.ego", {"start_speed_mps": "8.0", "route": "a,b"})]
    assert rec.warnings("r") == []


@pytest.mark.parametrize("where", [b"8.0", b"rocas.ego", b"start_speed"])
def test_a_damaged_record_is_dropped_with_a_warning(tmp_path, where):
    path = tmp_path / "r.mcap"
    _write(path, {"start_speed_mps": "8.0", "route": "a,b"})
    path.write_bytes(_flip_in(path.read_bytes(), where))
    rec = open_recording(path).scan()
    assert rec.metadata == []
    (line,) = rec.warnings("r")
    assert "fails its checksum" in line and "not used" in line


def test_a_record_without_a_checksum_is_read_as_it_is(tmp_path):
    path = tmp_path / "plain.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        w.add_metadata("other.tool", {"k": "v"})
        w.finish()
    rec = open_recording(path).scan()
    assert rec.metadata == [("other.tool", {"k": "v"})] and rec.warnings("p") == []


def test_the_checksum_covers_name_and_pairs_and_replaces_an_old_one():
    good = with_checksum("n", {"a": "1", CHECKSUM_KEY: "00000000"})
    assert checksum_problem("n", good) is None
    assert checksum_problem("m", good) is not None
    assert checksum_problem("n", {**good, "a": "2"}) is not None
    assert checksum_problem("n", {"a": "1"}) is None  # none written: nothing claimed


def test_a_flipped_digit_in_the_recorded_mission_is_not_replayed_silently(tmp_path):
    src = next(RECORDINGS.glob("a10_*.mcap"))
    base = reconstruct(src)
    assert base.complete
    data = src.read_bytes()
    speed = f'"start_speed_mps": {base.scenario.ego.start_speed_mps!r}'.encode()
    at = data.index(speed) + len(speed) - 1  # the last digit of the start speed in the JSON
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(data[:at] + bytes([data[at] ^ 0x01]) + data[at + 1 :])
    got = reconstruct(damaged)
    assert not got.complete and any("rocas.ego" in w and "checksum" in w for w in got.warnings)
