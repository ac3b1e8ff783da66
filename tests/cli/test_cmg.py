"""rocas cmg: per channel, who writes and reads it, from where, and what to add."""

from __future__ import annotations

import io
import json

import pytest
from mcap.writer import Writer as McapWriter

from rocas.cli.console import Env
from rocas.cli.main import main
from rocas.msgs import control_pb2, planning_pb2
from rocas.recording import RecordingWriter


def run(*argv: str) -> tuple[int, str, str]:
    env = Env(stdout=io.StringIO(), stderr=io.StringIO())
    code = main(list(argv), env=env)
    return code, env.stdout.getvalue(), env.stderr.getvalue()


@pytest.fixture
def bare(tmp_path):
    """Protobuf channels without any topology."""
    path = tmp_path / "bare.mcap"
    with RecordingWriter(path) as rec:
        rec.add_channel("/planning", planning_pb2.ADCTrajectory)
        rec.add_channel("/control", control_pb2.ControlCommand)
        rec.write("/planning", planning_pb2.ADCTrajectory(), log_time_ns=1)
        rec.write("/control", control_pb2.ControlCommand(), log_time_ns=2)
    return path


@pytest.fixture
def ros1(tmp_path):
    """A ROS 1 profile recording: callerid names the publisher, messages are ros1msg."""
    path = tmp_path / "ros1.mcap"
    with open(path, "wb") as f:
        w = McapWriter(f)
        w.start(profile="ros1", library="bag2mcap")
        s = w.register_schema("geometry_msgs/Twist", "ros1msg", b"float64 x")
        cmd = w.register_channel("/cmd_vel", "ros1", s, {"callerid": "/move_base"})
        odom = w.register_channel("/odom", "ros1", s,
                                  {"callerid": "/base", "rocas.readers": "move_base"})
        for i in range(3):
            w.add_message(cmd, log_time=i, publish_time=i, data=b"\x00" * 8)
            w.add_message(odom, log_time=i, publish_time=i, data=b"\x00" * 8)
        w.finish()
    return path


def test_no_topology_shows_missing_and_says_what_to_add(bare):
    code, out, err = run("cmg", str(bare))
    assert code == 0 and err == ""
    assert "/planning" in out and "missing" in out
    assert "declares no topology: 'rocas diff' needs it" in out
    assert "rocas.writers / rocas.readers" in out
    assert f"rocas annotate {bare} --cmg FILE -o OUT.mcap" in out
    assert "no control channel" in out


def test_cmg_file_fills_the_graph(bare, tmp_path):
    cmg = tmp_path / "cmg.json"
    cmg.write_text(json.dumps({
        "modules": {"planning": {"writes": ["/planning"]},
                    "control": {"reads": ["/planning"], "writes": ["/control"]}},
        "control_channel": "/control",
    }))
    code, out, err = run("cmg", str(bare), "--cmg", str(cmg))
    assert code == 0 and err == ""
    assert "/control (control)" in out and "--cmg" in out
    assert "control: reads /planning; writes /control" in out
    assert "Control channel: /control (from cmg)" in out
    code, out, _ = run("cmg", str(bare), "--cmg", str(cmg), "--format", "json")
    doc = json.loads(out)
    assert doc["control_channel"] == "/control" and doc["control_source"] == "cmg"
    chans = {c["topic"]: c for c in doc["channels"]}
    assert chans["/planning"]["writers_source"] == "cmg"
    assert chans["/planning"]["schema"].endswith("ADCTrajectory")
    assert chans["/control"]["messages"] == 1
    code, out, _ = run("cmg", str(bare), "--cmg", str(cmg), "--format", "dot")
    assert out.startswith("digraph cmg {") and '"module:control" -> "channel:/control";' in out


def test_ros1_callerid_counts_as_the_writer_and_the_output_says_so(ros1):
    code, out, err = run("cmg", str(ros1), "--control-channel", "/cmd_vel")
    assert code == 0 and err == ""
    assert "/move_base" in out and "callerid" in out
    assert "come from the ROS 1 'callerid' channel metadata" in out
    assert "rocas decodes only" not in out  # ROS 1 channels are decoded
    assert "Control channel: /cmd_vel (from --control-channel)" in out
    doc = json.loads(run("cmg", str(ros1), "--format", "json")[1])
    chans = {c["topic"]: c for c in doc["channels"]}
    assert chans["/odom"]["writers"] == ["/base"] and chans["/odom"]["writers_source"] == "callerid"
    assert chans["/odom"]["readers_source"] == "metadata"


def test_cmg_naming_an_absent_channel_warns(bare, tmp_path):
    cmg = tmp_path / "cmg.json"
    cmg.write_text(json.dumps({"modules": {"planning": {"writes": ["/planning", "/ghost"]}},
                               "control_channel": "/gone"}))
    code, out, err = run("cmg", str(bare), "--cmg", str(cmg))
    assert code == 0
    assert f"rocas: warning: {cmg} names channel /ghost, which is not in {bare}; ignored" in err
    assert "names control channel /gone" in err
    assert "/ghost" not in out


def test_a_truncated_recording_is_reported_on_stderr(tmp_path):
    path = tmp_path / "full.mcap"
    with RecordingWriter(path, chunk_size=512) as rec:
        rec.add_channel("/control", control_pb2.ControlCommand, writers=["control"])
        for i in range(200):
            rec.write("/control", control_pb2.ControlCommand(throttle=i), log_time_ns=i)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    code, out, err = run("cmg", str(cut))
    assert code == 0 and "/control" in out  # what was read before the cut is still shown
    assert err.startswith(f"rocas: warning: {cut}: recording is truncated (")
    assert "stopped at offset" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["cmg", "{tmp}/nope.mcap"], "no such file"),
        (["cmg", "{rec}", "--cmg", "{tmp}/bad.json"], "not valid JSON"),
        (["cmg", "{rec}", "--cmg", "{tmp}/nope.json"], "cannot read CMG file"),
        (["cmg", "{rec}", "--control-channel", "/nope"], "'/nope' (from --control-channel)"),
    ],
)
def test_bad_input_is_one_error_line(bare, tmp_path, argv, needle):
    (tmp_path / "bad.json").write_text("{oops")
    argv = [a.format(tmp=tmp_path, rec=bare) for a in argv]
    code, out, err = run(*argv)
    assert code == 3 and out == ""
    assert err.startswith("rocas: error: ") and needle in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_json_output_feeds_back_as_cmg_and_gives_the_same_graph(tmp_path):
    from foreign_stack import make_pair

    pair = make_pair(tmp_path, deviating="tracker")
    code, out, err = run("cmg", str(pair.accident), "--format", "json")
    assert code == 0, err
    doc = json.loads(out)
    assert {"recording", "control_source", "notes", "hints", "channels"} <= set(doc)
    cmg = tmp_path / "g.json"
    cmg.write_text(out)
    # rocas cmg, rocas diff and rocas annotate all take it back as --cmg
    code, again, err = run("cmg", str(pair.accident), "--cmg", str(cmg), "--format", "json")
    assert code == 0 and err == ""
    back = json.loads(again)
    assert back["modules"] == doc["modules"]
    assert back["control_channel"] == doc["control_channel"]
    def edges(d):
        return [(c["topic"], sorted(c["writers"]), sorted(c["readers"]), c["control"])
                for c in d["channels"]]

    assert edges(back) == edges(doc)
    code, out, err = run("diff", str(pair.accident), str(pair.reference), "--cmg", str(cmg),
                         "--json")
    assert code == 0, err
    assert json.loads(out)["deviating_module"] == "tracker"
    copy = tmp_path / "annotated.mcap"
    code, out, err = run("annotate", str(pair.accident), "--cmg", str(cmg), "-o", str(copy))
    assert code == 0 and err == ""
    assert json.loads(run("cmg", str(copy), "--format", "json")[1])["modules"] == doc["modules"]
