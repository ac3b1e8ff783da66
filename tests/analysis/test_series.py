"""Pairing and binning rules of the MDR series, on small hand-built recordings."""

import numpy as np
import pytest

from rocas.analysis.series import compute_series
from rocas.errors import RecordingError
from rocas.msgs import control_pb2
from rocas.recording import RecordingWriter, open_recording
from rocas.recording.decoding import DecoderCache

S = 1_000_000_000


def _write(path, times_s, values, start_ns=0, topic="/control"):
    with RecordingWriter(path) as w:
        w.add_channel(topic, control_pb2.ControlCommand, writers=["control"], role="control")
        for t, v in zip(times_s, values, strict=True):
            w.write(topic, control_pb2.ControlCommand(throttle=v), log_time_ns=start_ns + int(t * S))
    return path


def _series(tmp_path, a, b, **kw):
    cache = DecoderCache()
    return compute_series(open_recording(a, cache), open_recording(b, cache), bin_s=0.1, **kw)


N_FIELDS = len(control_pb2.ControlCommand.DESCRIPTOR.fields)


def test_recordings_align_at_their_first_message(tmp_path):
    a = _write(tmp_path / "a.mcap", [0.0, 0.1, 0.2], [1, 2, 3], start_ns=5 * S)
    b = _write(tmp_path / "b.mcap", [0.0, 0.1, 0.2], [1, 2, 4], start_ns=900 * S)
    s = _series(tmp_path, a, b).series["/control"]
    assert list(s.times_s) == pytest.approx([0.0, 0.1, 0.2])
    assert list(s.mdr) == pytest.approx([0, 0, 1 / N_FIELDS])


def test_unpaired_messages_score_one_and_bins_average(tmp_path):
    a = _write(tmp_path / "a.mcap", [0.0, 0.1, 0.12], [1, 2, 3])
    b = _write(tmp_path / "b.mcap", [0.0, 0.1], [1, 2])
    s = _series(tmp_path, a, b).series["/control"]
    # bin 0.1: (2 vs 2) -> 0, third message unpaired -> 1; mean over 2 messages
    assert list(s.mdr) == pytest.approx([0.0, 0.5])
    assert s.messages.tolist() == [[1, 1], [2, 1]]


def test_kth_message_pairs_with_kth(tmp_path):
    a = _write(tmp_path / "a.mcap", [0.0, 0.01, 0.02], [1, 2, 3])
    b = _write(tmp_path / "b.mcap", [0.0, 0.01, 0.02], [1, 3, 2])
    s = _series(tmp_path, a, b).series["/control"]
    assert s.mdr[0] == pytest.approx((0 + 2 / N_FIELDS) / 3)


def test_a_message_that_slipped_over_a_bin_edge_pairs_with_its_twin(tmp_path):
    a = _write(tmp_path / "a.mcap", [0.0, 0.149, 0.3], [1, 2, 3])
    b = _write(tmp_path / "b.mcap", [0.0, 0.151, 0.3], [1, 2, 3])
    adjacent = _series(tmp_path, a, b).series["/control"]
    assert list(adjacent.mdr) == [0.0, 0.0, 0.0]  # bins 0.0, 0.1 (with its twin), 0.3
    strict = _series(tmp_path, a, b, adjacent_pairing=False).series["/control"]
    assert list(strict.mdr) == [0.0, 1.0, 1.0, 0.0]


def test_channel_in_one_recording_only_is_reported(tmp_path):
    a = _write(tmp_path / "a.mcap", [0.0, 0.1], [1, 2])
    b = _write(tmp_path / "b.mcap", [0.0, 0.1], [1, 2], topic="/other")
    res = _series(tmp_path, a, b)
    assert res.series["/control"].only_in == "accident"
    assert res.series["/other"].only_in == "reference"
    assert np.all(res.series["/control"].mdr == 1.0)


def test_schema_mismatch_between_files_is_an_error(tmp_path):
    from rocas.msgs import planning_pb2

    a = _write(tmp_path / "a.mcap", [0.0], [1])
    with RecordingWriter(tmp_path / "b.mcap") as w:
        w.add_channel("/control", planning_pb2.ADCTrajectory)
        w.write("/control", planning_pb2.ADCTrajectory(), log_time_ns=0)
    with pytest.raises(RecordingError, match="different schema"):
        _series(tmp_path, a, tmp_path / "b.mcap")


def test_series_is_streamed_in_bounded_windows(tmp_path):
    times = np.arange(0, 60, 0.01)
    a = _write(tmp_path / "a.mcap", times, np.zeros_like(times))
    b = _write(tmp_path / "b.mcap", times, np.where(times > 30, 1.0, 0.0))
    s = _series(tmp_path, a, b).series["/control"]
    assert len(s.mdr) == 601  # bins are centred: 0.0 holds [-0.05, 0.05), 60.0 a half bin
    assert s.mdr[:300].max() == 0 and s.mdr[301:].min() == pytest.approx(1 / N_FIELDS)
