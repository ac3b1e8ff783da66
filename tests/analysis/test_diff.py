"""End to end on recordings of a stack unlike rocas's ADS, where the answer is known."""

import pytest
from foreign_stack import CONTROL, make_pair

from rocas.analysis import diff
from rocas.errors import RecordingError, TopologyError


@pytest.mark.parametrize("deviating", ["tracker", "forecaster", "behaviour"])
@pytest.mark.parametrize("seed", [0, 1])
def test_finds_the_module_that_deviated_first(tmp_path, deviating, seed):
    pair = make_pair(tmp_path, deviating=deviating, seed=seed)
    r = diff(pair.accident, pair.reference)
    assert r.deviating_module == deviating
    assert r.control_channel == CONTROL
    assert r.pinpoint.path[0] == CONTROL and r.pinpoint.path[-1] == deviating
    by_topic = {c.topic: c for c in r.channels}
    # the early distractor is excluded, as /apollo/canbus/chassis is in Appendix A
    assert by_topic["/vehicle/state"].change_point_s == pytest.approx(1.5, abs=0.15)
    assert "not reachable" in r.pinpoint.exclusions["vehicle"]
    assert by_topic["/sensing/cloud"].change_point_s is None  # noise only


def test_no_deviation_gives_no_module(tmp_path):
    pair = make_pair(tmp_path, deviating=None, distractor_at_s=None)
    r = diff(pair.accident, pair.reference)
    assert r.deviating_module is None
    assert all(c.change_point_s is None for c in r.channels)


def test_json_channel_is_compared(tmp_path):
    pair = make_pair(tmp_path)
    r = diff(pair.accident, pair.reference)
    diag = {c.topic: c for c in r.channels}["/diag/status"]
    assert len(diag.series.mdr) > 0 and diag.mdr_before == 0.0


def test_without_topology_the_error_names_both_remedies(tmp_path):
    pair = make_pair(tmp_path, topology=False)
    with pytest.raises(TopologyError) as exc:
        diff(pair.accident, pair.reference)
    assert "--cmg" in str(exc.value) and "rocas annotate" in str(exc.value)
    assert f"no channel topology in {pair.accident} or {pair.reference}" in str(exc.value)


def test_the_reference_topology_stands_in_when_the_accident_has_none(tmp_path):
    from foreign_stack import write_run

    pair = make_pair(tmp_path, topology=False, deviating="tracker")
    reference = tmp_path / "reference_with_topology.mcap"
    write_run(reference, accident=False, deviating="tracker", start_sec=1_700_086_400)
    r = diff(pair.accident, reference)
    assert r.deviating_module == "tracker" and r.control_channel == CONTROL
    assert (f"{pair.accident} declares no channel topology; using the one {reference} "
            "declares (the two recordings have the same channels)") in r.warnings


def _tiny(path, topics, topology):
    from rocas.msgs import control_pb2
    from rocas.recording import RecordingWriter

    with RecordingWriter(path) as w:
        for i, topic in enumerate(topics):
            kw = {"writers": [f"m{i}"], "readers": [f"m{i + 1}"]} if topology else {}
            w.add_channel(topic, control_pb2.ControlCommand, **kw)
            w.write(topic, control_pb2.ControlCommand(), log_time_ns=i)
    return path


def test_a_reference_topology_over_other_channels_is_not_borrowed(tmp_path):
    acc = _tiny(tmp_path / "acc.mcap", ["/a", "/b"], topology=False)
    ref = _tiny(tmp_path / "ref.mcap", ["/a", "/b", "/c"], topology=True)
    with pytest.raises(TopologyError) as exc:
        diff(acc, ref)
    assert str(exc.value).startswith(
        f"{acc} declares no channel topology, and the one {ref} declares does not apply to it "
        "because their channels differ (only in the reference: /c)"
    )
    assert f"rocas cmg {ref} --format json" in exc.value.hint


def test_cmg_file_supplies_the_topology(tmp_path):
    import json

    from foreign_stack import TOPOLOGY

    pair = make_pair(tmp_path, topology=False, deviating="tracker")
    spec = {"modules": {m: {"reads": list(r), "writes": list(w)} for m, (r, w) in TOPOLOGY.items()},
            "control_channel": CONTROL}
    cmg = tmp_path / "cmg.json"
    cmg.write_text(json.dumps(spec))
    assert diff(pair.accident, pair.reference, cmg=cmg).deviating_module == "tracker"


def test_same_inputs_same_result(tmp_path):
    pair = make_pair(tmp_path)
    a = diff(pair.accident, pair.reference).to_json()
    b = diff(pair.accident, pair.reference).to_json()
    assert a == b


def test_a_file_far_out_of_log_time_order_diffs_to_zero_with_a_warning(tmp_path):
    from mcap.writer import Writer
    from mcap_protobuf.schema import build_file_descriptor_set

    from rocas.msgs import control_pb2
    from rocas.recording import topology_metadata

    def write(path, late):
        fds = build_file_descriptor_set(control_pb2.ControlCommand).SerializeToString()
        entries = [(topic, k) for k in range(600) for topic in ("/cmd", "/echo")]
        if late:  # /echo written after everything else, 60 s late at the start
            entries = [e for e in entries if e[0] == "/cmd"] + [e for e in entries if e[0] == "/echo"]
        with open(path, "wb") as f:
            w = Writer(f)
            w.start()
            sid = w.register_schema("rocas.control.ControlCommand", "protobuf", fds)
            ids = {"/cmd": w.register_channel("/cmd", "protobuf", sid, topology_metadata(
                       writers=["ctrl"], readers=[], role="control")),
                   "/echo": w.register_channel("/echo", "protobuf", sid, topology_metadata(
                       writers=["echo"], readers=["ctrl"]))}
            for topic, k in entries:
                ns = k * 100_000_000
                w.add_message(ids[topic], ns, control_pb2.ControlCommand(throttle=k).SerializeToString(), ns)
            w.finish()
        return path

    a, b = write(tmp_path / "a.mcap", True), write(tmp_path / "b.mcap", False)
    res = diff(a, b)
    assert all(float(c.series.mdr.max()) == 0 for c in res.channels)
    assert res.pinpoint.deviating_module is None
    assert any("59.9 s out of log-time order" in w and str(a) in w for w in res.warnings)
    assert not any(str(b) in w for w in res.warnings)


def test_cmg_channels_in_neither_recording_are_reported_and_left_out(tmp_path):
    import json

    pair = make_pair(tmp_path, deviating="tracker")
    cmg = tmp_path / "cmg.json"
    cmg.write_text(json.dumps({"modules": {
        "ghost": {"reads": ["/ghost/in"], "writes": ["/ghost/out"]},
        "tracker": {"writes": ["/fusion/tracks"]},
    }}))
    r = diff(pair.accident, pair.reference, cmg=cmg)
    assert r.deviating_module == "tracker"
    assert "ghost" not in r.cmg.modules
    assert not {"/ghost/in", "/ghost/out"} & set(r.cmg.channels)
    doc = r.to_json()
    assert "ghost" not in [m["name"] for m in doc["modules"]]
    assert not [e for e in doc["removed_edges"] if "ghost" in e["from"] + e["to"]]
    for topic in ("/ghost/in", "/ghost/out"):
        assert (f"{cmg} names channel {topic}, which is not in {pair.accident} or "
                f"{pair.reference}; ignored") in r.warnings


@pytest.mark.parametrize("via", ["cmg", "override"])
def test_a_control_channel_in_neither_recording_is_refused(tmp_path, via):
    import json

    pair = make_pair(tmp_path)
    cmg = tmp_path / "cmg.json"
    cmg.write_text(json.dumps({"modules": {"ctl": {"writes": ["/ghost/cmd"]}},
                               "control_channel": "/ghost/cmd"}))
    kw = {"cmg": cmg} if via == "cmg" else {"control_channel_topic": "/ghost/cmd"}
    with pytest.raises(TopologyError) as exc:
        diff(pair.accident, pair.reference, **kw)
    origin = str(cmg) if via == "cmg" else "--control-channel"
    assert (f"control channel '/ghost/cmd' (from {origin}) is not in {pair.accident} or "
            f"{pair.reference}") in str(exc.value)
    assert CONTROL in exc.value.hint


@pytest.mark.parametrize("side", ["accident", "reference"])
def test_one_recording_without_a_readable_message_is_refused(tmp_path, side):
    pair = make_pair(tmp_path)
    cut = tmp_path / "cut.mcap"
    whole = pair.accident if side == "accident" else pair.reference
    cut.write_bytes(whole.read_bytes()[:9000])  # the header and a cut-off first chunk
    args = (cut, pair.reference) if side == "accident" else (pair.accident, cut)
    with pytest.raises(RecordingError) as exc:
        diff(*args)
    assert str(exc.value).startswith(f"the {side} recording {cut} holds no readable message: ")
    assert "truncated" in str(exc.value) and exc.value.hint == "check the file with 'mcap info'"
