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


def test_an_unpaired_message_scores_one_where_the_other_run_is_silent(tmp_path):
    # the reference is silent from 1.0 s to 1.9 s while the accident goes on publishing
    times = [i / 10 for i in range(30)]
    a = _write(tmp_path / "a.mcap", times, list(range(30)))
    kept = [i for i in range(30) if not 10 <= i <= 19]
    b2 = _write(tmp_path / "b2.mcap", [times[i] for i in kept], kept)
    res = _series(tmp_path, a, b2)
    s = res.series["/control"]
    # near the edges of the silence the reference still wrote most of what the accident did
    # within half a second: set aside; in its middle it wrote (almost) nothing: they score 1
    scored = [round(t, 1) for t, v in zip(s.times_s, s.mdr, strict=True) if v]
    assert len(scored) >= 3 and all(1.0 < t < 1.9 for t in scored)
    assert set(s.mdr) == {0.0, 1.0}
    assert res.accounts["/control"].aside == (10 - len(scored), 0)
    # past the reference's last message nothing is compared: the span both files cover
    b = _write(tmp_path / "b.mcap", [0.0, 0.1], [0, 1])
    short = _series(tmp_path, a, b)
    assert list(short.series["/control"].mdr) == [0.0, 0.0]
    assert short.compared_s == pytest.approx((0.0, 0.1))
    assert short.accounts["/control"].outside == (28, 0)


def test_a_lost_message_is_missing_not_different(tmp_path):
    times = [i / 10 for i in range(30)]
    a = _write(tmp_path / "a.mcap", times, list(range(30)))
    b = _write(tmp_path / "b.mcap", times[:12] + times[13:], list(range(12)) + list(range(13, 30)))
    res = _series(tmp_path, a, b)
    assert not res.series["/control"].mdr.any()
    assert res.accounts["/control"].aside == (1, 0)


def test_a_repeated_message_is_counted_once(tmp_path):
    times = [i / 10 for i in range(20)]
    a = _write(tmp_path / "a.mcap", times, list(range(20)))
    b = _write(tmp_path / "b.mcap", times[:5] + [0.4005] + times[5:], list(range(5)) + [4]
               + list(range(5, 20)))
    res = _series(tmp_path, a, b)
    assert not res.series["/control"].mdr.any()
    assert res.accounts["/control"].repeated == (0, 1)


def test_a_channel_at_half_rate_pairs_each_message_with_its_nearest_partner(tmp_path):
    times = [i / 10 for i in range(30)]
    a = _write(tmp_path / "a.mcap", times, list(range(30)))
    b = _write(tmp_path / "b.mcap", times[::2], list(range(30))[::2])
    res = _series(tmp_path, a, b)
    assert not res.series["/control"].mdr.any()
    assert res.accounts["/control"].aside == (14, 0)
    assert res.accounts["/control"].outside == (1, 0)  # 2.9 s: after the reference's last


def test_the_same_message_pairs_with_itself_and_the_rest_by_time(tmp_path):
    # the same messages at other times within a bin (jitter, another logging order) pair
    # with themselves
    a = _write(tmp_path / "a.mcap", [0.0, 0.01, 0.02], [1, 2, 3])
    b = _write(tmp_path / "b.mcap", [0.0, 0.01, 0.02], [1, 3, 2])
    assert _series(tmp_path, a, b).series["/control"].mdr[0] == 0.0
    # differing messages pair in time order (the k-th with the k-th at equal times)
    c = _write(tmp_path / "c.mcap", [0.0, 0.01, 0.02], [1, 5, 6])
    assert _series(tmp_path, a, c).series["/control"].mdr[0] == pytest.approx(
        (0 + 2 / N_FIELDS) / 3)


def test_a_message_that_slipped_over_a_bin_edge_pairs_with_its_twin(tmp_path):
    a = _write(tmp_path / "a.mcap", [0.0, 0.149, 0.3], [1, 2, 3])
    b = _write(tmp_path / "b.mcap", [0.0, 0.151, 0.3], [1, 2, 3])
    adjacent = _series(tmp_path, a, b).series["/control"]
    assert list(adjacent.mdr) == [0.0, 0.0, 0.0]  # bins 0.0, 0.1 (with its twin), 0.3
    # without adjacent-bin pairing each is unpaired, and set aside (the other run publishes
    # the channel close by), not scored as differing
    strict = _series(tmp_path, a, b, adjacent_pairing=False)
    assert list(strict.series["/control"].mdr) == [0.0, 0.0]
    assert strict.accounts["/control"].aside == (1, 1)


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


def _write_raw(path, entries, *, fds=None, statistics=True):
    """Write ``entries`` = [(topic, log time s, throttle)] in the given file order."""
    from mcap.writer import Writer
    from mcap_protobuf.schema import build_file_descriptor_set

    fds = fds or build_file_descriptor_set(control_pb2.ControlCommand)
    with open(path, "wb") as f:
        w = Writer(f, use_statistics=statistics, use_summary_offsets=statistics)
        w.start()
        sid = w.register_schema("rocas.control.ControlCommand", "protobuf", fds.SerializeToString())
        ids = {}
        for topic, t, v in entries:
            if topic not in ids:
                ids[topic] = w.register_channel(topic, "protobuf", sid)
            ns = int(round(t * S))
            w.add_message(ids[topic], ns, control_pb2.ControlCommand(throttle=v).SerializeToString(), ns)
        w.finish()
    return path


def test_a_channel_written_after_the_rest_pairs_as_if_in_log_time_order(tmp_path):
    times = [round(0.1 * k, 1) for k in range(100)]
    ordered = [(topic, t, t) for t in times for topic in ("/a", "/b")]
    late = [e for e in ordered if e[0] == "/a"] + [e for e in ordered if e[0] == "/b"]  # /b 10 s late
    a = _write_raw(tmp_path / "a.mcap", late)
    b = _write_raw(tmp_path / "b.mcap", ordered)
    res = _series(tmp_path, a, b)
    for topic in ("/a", "/b"):
        s = res.series[topic]
        assert len(s.times_s) == 100 and np.all(np.diff(s.times_s) > 0)  # no bin twice
        assert np.all(s.mdr == 0)
    assert res.disorder_s[0] == pytest.approx(9.9) and res.disorder_s[1] == 0
    assert res.reorder_window_s >= 9.9
    in_order = _series(tmp_path, b, b)
    assert in_order.reorder_window_s == 1.0 and in_order.disorder_s == (0, 0)


def test_messages_pair_in_log_time_order_whatever_the_file_order(tmp_path):
    # two messages a bin on one channel; the second file writes each bin's pair swapped
    pairs = [((k * 0.1, k), (k * 0.1 + 0.02, k + 100)) for k in range(30)]
    a = _write_raw(tmp_path / "a.mcap", [("/c", t, v) for p in pairs for t, v in p])
    b = _write_raw(tmp_path / "b.mcap", [("/c", t, v) for p in pairs for t, v in reversed(p)])
    assert np.all(_series(tmp_path, a, b).series["/c"].mdr == 0)


def test_a_file_without_summary_aligns_at_its_earliest_message_not_its_first(tmp_path):
    entries = [("/c", 1.0 + 0.1 * k, k) for k in range(40)]
    early_last = entries[3:] + entries[:3]  # the first 0.3 s written after the rest
    a = _write_raw(tmp_path / "a.mcap", early_last, statistics=False)
    b = _write_raw(tmp_path / "b.mcap", entries)
    assert open_recording(a).summary_start_time_ns() is None
    s = _series(tmp_path, a, b).series["/c"]
    assert np.all(s.mdr == 0) and s.times_s[0] == 0 and len(s.times_s) == 40


def test_protobuf_schemas_compare_by_definition_not_by_file_order(tmp_path):
    from google.protobuf import descriptor_pb2
    from mcap_protobuf.schema import build_file_descriptor_set

    fds = build_file_descriptor_set(control_pb2.ControlCommand)
    assert len(fds.file) > 1
    rev = descriptor_pb2.FileDescriptorSet()
    rev.file.extend(reversed(list(fds.file)))
    a = _write_raw(tmp_path / "a.mcap", [("/c", 0.0, 1)], fds=fds)
    b = _write_raw(tmp_path / "b.mcap", [("/c", 0.0, 1)], fds=rev)
    assert np.all(_series(tmp_path, a, b).series["/c"].mdr == 0)
    # the same name with another definition is still refused, and the message says so
    changed = descriptor_pb2.FileDescriptorSet()
    changed.CopyFrom(fds)
    for f in changed.file:
        for m in f.message_type:
            if m.name == "ControlCommand":
                m.field[0].name = "renamed"
    c = _write_raw(tmp_path / "c.mcap", [("/c", 0.0, 1)], fds=changed)
    with pytest.raises(RecordingError, match="ControlCommand in both, defined differently"):
        _series(tmp_path, a, c)


def _counting_cache():
    """A DecoderCache whose decoders count the payloads they decode (one decoder per schema,
    as in a plain cache)."""
    cache, calls, made = DecoderCache(), [], {}
    plain = cache.decoder

    def decoder(*key):
        decode = plain(*key)
        if decode is None or key in made:
            return made.get(key)

        def counted(payload):
            calls.append(payload)
            return decode(payload)

        made[key] = counted
        return counted

    cache.decoder = decoder  # type: ignore[method-assign]
    return cache, calls


def test_equal_payloads_are_decoded_once_and_differing_ones_on_both_sides(tmp_path):
    a = _write(tmp_path / "a.mcap", [0.0, 0.1, 0.2, 0.3], [1, 2, 3, 4])
    b = _write(tmp_path / "b.mcap", [0.0, 0.1, 0.2, 0.3], [1, 2, 5, 6])
    cache, calls = _counting_cache()
    res = compute_series(open_recording(a, cache), open_recording(b, cache), bin_s=0.1)
    assert list(res.series["/control"].mdr) == pytest.approx([0, 0, 1 / N_FIELDS, 1 / N_FIELDS])
    # one of each equal pair, both of each differing pair, and the last equal message once
    # more where the two begin to differ (to see whether content entered both there)
    assert len(calls) == 2 + 2 * 2 + 1
    assert res.messages_read == (4, 4)


def _json_recording(path, messages):
    """A JSON recording of (time [s], payload bytes) on /j."""
    from mcap.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        cid = w.register_channel("/j", "json", w.register_schema("s", "jsonschema", b"{}"))
        for seq, (t, data) in enumerate(messages):
            w.add_message(cid, log_time=int(t * S), publish_time=int(t * S), data=data,
                          sequence=seq)
        w.finish()
    return path


def test_undecodable_messages_are_left_out_even_where_both_files_hold_them(tmp_path):
    """A payload that does not decode counts for nothing, whether or not the other file holds
    the same bytes (which the series otherwise never decodes twice)."""
    a = _json_recording(tmp_path / "a.mcap", [
        (0.0, b'{"v": 1}'), (0.1, b"{bad"), (0.2, b'{"v": 3}'), (0.3, b'{"v": 4}')])
    b = _json_recording(tmp_path / "b.mcap", [
        (0.0, b'{"v": 1}'), (0.1, b"{bad"), (0.2, b'{"v": 3}'), (0.3, b"{bad"),
        (0.301, b'{"v": 4}')])
    cache = DecoderCache()
    rec_a, rec_b = open_recording(a, cache), open_recording(b, cache)
    res = compute_series(rec_a, rec_b, bin_s=0.1)
    s = res.series["/j"]
    assert list(s.times_s) == pytest.approx([0.0, 0.2, 0.3])
    assert list(s.mdr) == [0.0, 0.0, 0.0]
    assert s.messages.tolist() == [[1, 1], [1, 1], [1, 1]]
    assert res.messages_read == (3, 3)
    stats_a, stats_b = rec_a.report.channel_stats["/j"], rec_b.report.channel_stats["/j"]
    assert (stats_a.decoded, stats_a.undecodable) == (3, 1)
    assert (stats_b.decoded, stats_b.undecodable) == (3, 2)


def _obstacles(path, frames, topic="/perception/obstacles"):
    """A recording of PerceptionObstacles at 0.0, 0.1, ... s: ``frames[i]`` lists the
    sub-types (e.g. ``"ST_BUS"``) of the obstacles in message i."""
    from rocas.msgs import perception_pb2

    with RecordingWriter(path) as w:
        w.add_channel(topic, perception_pb2.PerceptionObstacles, writers=["perception"])
        for i, kinds in enumerate(frames):
            m = perception_pb2.PerceptionObstacles()
            for k, kind in enumerate(kinds):
                m.perception_obstacle.add(id=k + 1, sub_type=kind)
            w.write(topic, m, log_time_ns=int(round(i * 0.1 * S)))
    return path


def _entered(tmp_path, frames_a, frames_b):
    a = _obstacles(tmp_path / "a.mcap", frames_a)
    b = _obstacles(tmp_path / "b.mcap", frames_b)
    s = _series(tmp_path, a, b).series["/perception/obstacles"]
    return [round(float(t), 1) for t in s.times_s[s.entered]]


def test_content_entering_both_runs_at_once_and_differing_is_marked(tmp_path):
    car, bus, truck = "ST_CAR", "ST_BUS", "ST_TRUCK"
    # a bus in one run, a truck in the other, both in view from 0.3 s; a parked car alike
    assert _entered(tmp_path, [[]] * 3 + [[bus]] * 3, [[]] * 3 + [[truck]] * 3) == [0.3]
    assert _entered(tmp_path, [[car]] * 3 + [[car, bus]] * 3,
                    [[car]] * 3 + [[car, truck]] * 3) == [0.3]


def test_content_that_enters_one_run_first_shrinks_or_is_alike_is_not_marked(tmp_path):
    car, bus, truck = "ST_CAR", "ST_BUS", "ST_TRUCK"
    # the truck comes into view a bin later (a hedge hides it in one run)
    assert _entered(tmp_path, [[]] * 3 + [[bus]] * 3, [[]] * 4 + [[truck]] * 2) == []
    # a light leaves both runs' view and the one left differs (A10's shape)
    assert _entered(tmp_path, [[car, bus]] * 3 + [[bus]] * 3, [[car, bus]] * 3 + [[truck]] * 3) == []
    # the runs differed before the content entered
    assert _entered(tmp_path, [[car]] * 3 + [[car, bus]] * 3,
                    [[truck]] * 3 + [[truck, truck]] * 3) == []
    # content entered alike, and the two differ a bin later
    assert _entered(tmp_path, [[]] * 3 + [[bus]] + [[car]] * 2, [[]] * 3 + [[bus]] + [[truck]] * 2) == []


def test_two_files_that_share_no_span_are_refused(tmp_path):
    from rocas.analysis.diff import diff

    times = [i / 10 for i in range(40)]
    a = _write(tmp_path / "a.mcap", times, list(range(40)))
    b = _write(tmp_path / "b.mcap", times, list(range(100, 140)), start_ns=10 * S)
    with pytest.raises(RecordingError, match="share no span of time"):
        diff(a, b, align="log-time")
    # by their first messages they overlap
    assert diff(a, b, align="first").compared_s == pytest.approx((0.0, 3.9))


def test_a_late_logger_is_aligned_by_identical_messages(tmp_path):
    from rocas.analysis.diff import diff

    times = [i / 10 for i in range(60)]
    a = _write(tmp_path / "a.mcap", times, list(range(60)))
    # the reference's logger started 1 s later, on the same clock, and its run differs at 4 s
    b = _write(tmp_path / "b.mcap", times[10:], list(range(10, 40)) + [v + 1 for v in range(40, 60)])
    r = diff(a, b)
    assert r.alignment.method == "content" and r.alignment.offset_s == 0.0
    assert r.compared_s == pytest.approx((0.0, 4.9))
    assert r.channels[0].change_point_s == pytest.approx(3.0)
    assert any("first 1.00 s lie outside the span" in w for w in r.warnings)
    # by first messages (the rule before alignment) the runs seem to differ from the start
    assert diff(a, b, align="first").alignment.offset_s == pytest.approx(-1.0)
