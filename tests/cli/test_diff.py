import json

import pytest
from foreign_stack import make_pair
from mcap.reader import make_reader

from rocas.msgs import control_pb2, planning_pb2
from rocas.recording import RecordingWriter


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    return make_pair(tmp_path_factory.mktemp("pair"), deviating="forecaster")


def _one_error_line(res, *needles):
    assert res.code != 0
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("rocas: error:")]
    assert len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr
    for n in needles:
        assert n in lines[0]
    return lines[0]


def test_json_output_has_the_documented_keys(rocas, pair):
    res = rocas("diff", pair.accident, pair.reference, "--json")
    assert res.code == 0, res.stderr
    data = json.loads(res.stdout)
    assert data["deviating_module"] == "forecaster"
    assert data["control_channel"] == "/vehicle/actuation"
    assert data["path"][0] == "/vehicle/actuation" and data["path"][-1] == "forecaster"
    ch = {c["topic"]: c for c in data["channels"]}
    for c in ch.values():
        assert {"topic", "writers", "readers", "change_point_s", "change_points_s", "mdr_before",
                "mdr_after", "only_in", "bins", "penalty", "noise_std"} <= set(c)
        assert c["noise_std"] >= 0 and c["penalty"] > 0
    assert ch["/fusion/forecast"]["writers"] == ["forecaster"]
    assert ch["/fusion/forecast"]["change_point_s"] == pytest.approx(6.0, abs=0.15)
    mods = {m["name"]: m for m in data["modules"]}
    assert mods["forecaster"]["reachable"] and not mods["vehicle"]["reachable"]
    assert set(mods["forecaster"]) >= {"name", "change_point_s", "reachable"}


def test_terminal_report(rocas, pair):
    res = rocas("diff", pair.accident, pair.reference)
    assert res.code == 0
    assert "Initial deviating module: forecaster" in res.stdout
    assert "/vehicle/actuation -> actuator -> /behaviour/plan -> behaviour" in res.stdout
    assert "vehicle: not reachable" in res.stdout


def test_control_channel_override(rocas, pair):
    res = rocas("diff", pair.accident, pair.reference, "--json",
                "--control-channel", "/behaviour/plan")
    assert json.loads(res.stdout)["control_channel"] == "/behaviour/plan"
    res = rocas("diff", pair.accident, pair.reference, "--control-channel", "/nope")
    _one_error_line(res, "/nope", "choose one of")


def test_missing_file(rocas, pair, tmp_path):
    res = rocas("diff", tmp_path / "nope.mcap", pair.reference)
    assert res.code == 3
    _one_error_line(res, "no such file")


def test_not_mcap_and_empty(rocas, pair, tmp_path):
    (tmp_path / "a.txt").write_text("just text")
    _one_error_line(rocas("diff", tmp_path / "a.txt", pair.reference), "not an MCAP file")
    (tmp_path / "e.mcap").write_bytes(b"")
    _one_error_line(rocas("diff", pair.accident, tmp_path / "e.mcap"), "empty")


def test_truncated_accident_still_diffs_with_a_warning(rocas, pair, tmp_path):
    data = pair.accident.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.8)])
    res = rocas("diff", cut, pair.reference, "--json")
    assert res.code == 0, res.stderr
    assert "rocas: warning:" in res.stderr and "truncated" in res.stderr
    assert json.loads(res.stdout)["deviating_module"] == "forecaster"


def test_an_accident_with_no_readable_message_is_refused(rocas, pair, tmp_path):
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(pair.accident.read_bytes()[:9000])
    res = rocas("diff", cut, pair.reference)
    assert res.code == 3 and res.stdout == ""
    _one_error_line(res, f"the accident recording {cut} holds no readable message")


def test_corrupted_chunk_is_skipped_with_a_warning(rocas, pair, tmp_path):
    with open(pair.accident, "rb") as f:
        offsets = sorted(c.chunk_start_offset for c in make_reader(f).get_summary().chunk_indexes)
    data = bytearray(pair.accident.read_bytes())
    for k in range(80, 120):
        data[offsets[0] + k] ^= 0x5A
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    res = rocas("diff", bad, pair.reference, "--json")
    assert res.code == 0, res.stderr
    assert f"corrupted chunk at offset {offsets[0]}" in res.stderr


def test_non_protobuf_channels_are_skipped_with_a_warning(rocas, tmp_path):
    from mcap.writer import Writer

    def write(path, throttle):
        with open(path, "wb") as f:
            w = Writer(f)
            w.start()
            from rocas.recording import register_protobuf_channel

            cid = register_protobuf_channel(w, "/control", control_pb2.ControlCommand,
                                            writers=["control"], readers=["car"], role="control")
            sid = w.register_schema("std_msgs/String", "ros1msg", b"string data")
            rid = w.register_channel("/ros_topic", "msgpack", sid, {"rocas.writers": "car"})
            for i in range(100):
                t = i * 10**8
                m = control_pb2.ControlCommand(throttle=throttle if i > 60 else 0)
                w.add_message(cid, log_time=t, publish_time=t, data=m.SerializeToString())
                w.add_message(rid, log_time=t, publish_time=t, data=b"\x01\x00\x00\x00x")
            w.finish()

    write(tmp_path / "a.mcap", 50)
    write(tmp_path / "b.mcap", 0)
    res = rocas("diff", tmp_path / "a.mcap", tmp_path / "b.mcap", "--json")
    assert res.code == 0, res.stderr
    # one warning per channel and recording, as docs/own-stack.md says
    skipped = [ln for ln in res.stderr.splitlines() if "skipped channel" in ln]
    assert skipped == [
        f"rocas: warning: {tmp_path / name}: skipped channel /ros_topic: 100 messages in an "
        "encoding rocas cannot decode (only protobuf, json, ROS 2 cdr and ROS 1 are compared)"
        for name in ("a.mcap", "b.mcap")
    ]
    assert json.loads(res.stdout)["deviating_module"] == "control"


def test_schema_differs_between_files(rocas, pair, tmp_path):
    other = make_pair(tmp_path, "other", extra_plan_field=True)
    _one_error_line(rocas("diff", other.accident, pair.reference), "/behaviour/plan",
                    "different schema")


def test_no_control_channel_lists_candidates(rocas, tmp_path):
    for name in ("a", "b"):
        with RecordingWriter(tmp_path / f"{name}.mcap") as w:
            w.add_channel("/planning", planning_pb2.ADCTrajectory, writers=["planning"])
            w.add_channel("/cmd", control_pb2.ControlCommand, writers=["control"])
            w.write("/planning", planning_pb2.ADCTrajectory(), log_time_ns=0)
            w.write("/cmd", control_pb2.ControlCommand(), log_time_ns=0)
    line = _one_error_line(rocas("diff", tmp_path / "a.mcap", tmp_path / "b.mcap"),
                           "--control-channel", "candidates")
    assert "/cmd" in line and "/planning" in line


def test_cmg_naming_absent_channels_warns_and_an_absent_control_channel_is_refused(
    rocas, pair, tmp_path
):
    cmg = tmp_path / "ghost.json"
    cmg.write_text(json.dumps({"modules": {"ghost": {"writes": ["/ghost/out"]}}}))
    res = rocas("diff", pair.accident, pair.reference, "--cmg", cmg, "--json")
    assert res.code == 0, res.stderr
    assert (f"rocas: warning: {cmg} names channel /ghost/out, which is not in "
            f"{pair.accident} or {pair.reference}; ignored") in res.stderr
    assert "ghost" not in [m["name"] for m in json.loads(res.stdout)["modules"]]
    res = rocas("diff", pair.accident, pair.reference, "--control-channel", "/ghost/cmd")
    assert res.code == 3
    _one_error_line(res, "'/ghost/cmd' (from --control-channel) is not in", str(pair.reference))


def test_bad_options_are_usage_errors(rocas, pair):
    res = rocas("diff", pair.accident, pair.reference, "--bin", "0")
    assert res.code == 2 and "rocas: error:" in res.stderr and "Traceback" not in res.stderr
    res = rocas("diff", pair.accident)
    assert res.code == 2


def test_traceback_flag_shows_the_story(rocas, pair, tmp_path):
    res = rocas("--traceback", "diff", tmp_path / "nope.mcap", pair.reference)
    assert res.code == 3 and "Traceback" in res.stderr


