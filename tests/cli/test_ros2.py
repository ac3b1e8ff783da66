"""ROS 2 bags (written with mcap-ros2-support's Writer) through diff, cmg, annotate and view."""

import json

from mcap.writer import Writer
from rrd import read_rrd


def test_diff_names_the_first_deviating_node(rocas, ros2_pair):
    acc, ref, cmg = ros2_pair
    res = rocas("diff", acc, ref, "--cmg", cmg, "--json")
    assert res.code == 0, res.stderr
    data = json.loads(res.stdout)
    assert data["deviating_module"] == "prediction_node"
    assert data["path"][0] == "/control/cmd" and data["path"][-1] == "prediction_node"
    ch = {c["topic"]: c for c in data["channels"]}
    assert abs(ch["/prediction/obstacles"]["change_point_s"] - 7.0) <= 0.15
    assert ch["/planning/path"]["change_point_s"] > ch["/prediction/obstacles"]["change_point_s"]
    assert "skipped channel" not in res.stderr


def test_a_bag_without_topology_gets_both_remedies(rocas, ros2_pair):
    acc, ref, _ = ros2_pair
    res = rocas("diff", acc, ref)
    assert res.code == 3
    assert "--cmg FILE" in res.stderr and "rocas annotate" in res.stderr


def test_annotate_then_diff_without_cmg(rocas, ros2_pair, tmp_path):
    acc, ref, cmg = ros2_pair
    out_a, out_r = tmp_path / "a.mcap", tmp_path / "r.mcap"
    assert rocas("annotate", acc, "--cmg", cmg, "-o", out_a).code == 0
    assert rocas("annotate", ref, "--cmg", cmg, "-o", out_r).code == 0
    res = rocas("cmg", out_a)
    assert res.code == 0, res.stderr
    assert "prediction_node" in res.stdout and "/control/cmd" in res.stdout
    res = rocas("diff", out_a, out_r, "--json")
    assert res.code == 0, res.stderr
    assert json.loads(res.stdout)["deviating_module"] == "prediction_node"


def test_view_shows_a_ros2_bag_through_rerun(rocas, ros2_pair, tmp_path):
    acc, _, _ = ros2_pair
    out = tmp_path / "v.rrd"
    res = rocas("view", acc, "--rrd", out, "--no-viewer")
    assert res.code == 0, res.stderr
    assert "5 channels through Rerun's MCAP importer" in res.stdout
    e, blueprints = read_rrd(out)
    assert blueprints == 1
    odom = e["/localization/odometry"]
    assert odom.rows == 1200 and "message_log_time" in odom.timelines
    assert any(c.startswith("nav_msgs.msg.Odometry") for c in odom.columns)


def test_view_refuses_a_recording_without_messages(rocas, tmp_path):
    empty = tmp_path / "empty.mcap"
    with open(empty, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2")
        w.register_channel("/x", "cdr", w.register_schema("pkg/msg/X", "ros2msg", b"float64 x"))
        w.finish()
    out = tmp_path / "v.rrd"
    res = rocas("view", empty, "--rrd", out, "--no-viewer")
    assert res.code == 3 and "nothing to show" in res.stderr
    assert not out.exists()


def test_callerid_on_a_ros2_channel_names_its_writer(rocas, tmp_path):
    path = tmp_path / "callerid.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2")
        sid = w.register_schema("std_msgs/msg/Float64", "ros2msg", b"float64 data")
        cid = w.register_channel("/speed", "cdr", sid, {"callerid": "/speed_node",
                                                        "offered_qos_profiles": ""})
        w.add_message(cid, log_time=0, publish_time=0, data=b"\x00\x01\x00\x00" + bytes(8))
        w.finish()
    res = rocas("cmg", path, "--format", "json")
    assert res.code == 0, res.stderr
    assert "/speed_node" in res.stdout and "callerid" in res.stdout
