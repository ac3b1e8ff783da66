"""Rebuild the MCAP files of tests/data/real/ from their public sources (see README.md there).

    python tests/data/real/make_real.py --turtle-bag example.bag --autoware-db3 bag_ego_trajectory.db3 \
        --control-yaml-dir DIR

``DIR`` holds the four ``*_control_cmd.yaml`` files (``ros2 topic echo`` output) of the Arm
actuation port. Each source is converted without changing a value: the ROS 1 bag with
``rosbags-convert`` (ros1 -> cdr, rosbag2 with mcap storage); the rosbag2 ``.db3`` by copying its
CDR payloads into MCAP with the ``ros2msg`` text of its type; the YAML echo output by encoding
each document as ``autoware_control_msgs/msg/Control`` (log time = the message's ``stamp``, the
only time the echo output keeps).
"""

from __future__ import annotations

import argparse
import shutil
import sqlite3
import subprocess
import tempfile
from pathlib import Path

import yaml
from mcap.writer import Writer

HERE = Path(__file__).resolve().parent

CONTROL_MSG = """builtin_interfaces/Time stamp
builtin_interfaces/Time control_time
autoware_control_msgs/Lateral lateral
autoware_control_msgs/Longitudinal longitudinal
================================================================================
MSG: autoware_control_msgs/Lateral
builtin_interfaces/Time stamp
builtin_interfaces/Time control_time
float32 steering_tire_angle
float32 steering_tire_rotation_rate
bool is_defined_steering_tire_rotation_rate
================================================================================
MSG: autoware_control_msgs/Longitudinal
builtin_interfaces/Time stamp
builtin_interfaces/Time control_time
float32 velocity
float32 acceleration
float32 jerk
bool is_defined_acceleration
bool is_defined_jerk
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""
CONTROL_TOPIC = "/control/trajectory_follower/control_cmd"


def turtle(bag: Path, out: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        dst = Path(tmp) / "turtle"
        subprocess.run(["rosbags-convert", "--src", str(bag), "--dst", str(dst), "--dst-storage", "mcap"],
                       check=True)
        shutil.copyfile(next(dst.glob("*.mcap")), out)


def autoware_db3(db3: Path, out: Path) -> None:
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    con = sqlite3.connect(db3)
    topics = con.execute("select id, name, type, serialization_format, offered_qos_profiles from topics "
                         "order by id").fetchall()
    with open(out, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="tests/data/real/make_real.py")
        ids = {}
        for tid, name, typ, fmt, qos in topics:
            text, _ = store.generate_msgdef(typ, ros_version=2)
            sid = w.register_schema(typ, "ros2msg", text.encode())
            ids[tid] = w.register_channel(name, fmt, sid, {"offered_qos_profiles": qos})
        for tid, ts, data in con.execute("select topic_id, timestamp, data from messages order by timestamp, id"):
            w.add_message(ids[tid], ts, bytes(data), ts)
        w.finish()


def control_yaml(src: Path, out: Path) -> None:
    from mcap_ros2.writer import Writer as Ros2Writer

    docs = [d for d in yaml.safe_load_all(src.read_text()) if d]
    with open(out, "wb") as f:
        w = Ros2Writer(f)
        schema = w.register_msgdef("autoware_control_msgs/msg/Control", CONTROL_MSG)
        for d in docs:
            t = int(d["stamp"]["sec"]) * 1_000_000_000 + int(d["stamp"]["nanosec"])
            w.write_message(CONTROL_TOPIC, schema, d, log_time=t, publish_time=t)
        w.finish()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--turtle-bag", type=Path)
    ap.add_argument("--autoware-db3", type=Path)
    ap.add_argument("--control-yaml-dir", type=Path)
    args = ap.parse_args()
    if args.turtle_bag:
        turtle(args.turtle_bag, HERE / "turtle_tf.mcap")
    if args.autoware_db3:
        autoware_db3(args.autoware_db3, HERE / "autoware_ego_trajectory.mcap")
    if args.control_yaml_dir:
        for name in ("autoware_original", "arm_s32z", "fvp", "arm_automotive_kit"):
            src = args.control_yaml_dir / f"{name}_control_cmd.yaml"
            control_yaml(src, HERE / f"arm_control_{name}.mcap")


if __name__ == "__main__":
    main()
