"""Scripted ROS 2 recordings: the built-in channel mix as a ROS 2 stack would record it.

The same story as :mod:`rocas.recording.synthetic`, in the ``ros2`` MCAP profile (CDR
messages, ``ros2msg`` schemas) and written with mcap-ros2-support's ``Writer``, the
reference ROS 2 MCAP writer for Python. Nodes and topics are named as ROS 2 users name them:

==================  =========================  ==============================  ======
node                topic                      type                            rate
==================  =========================  ==============================  ======
localization_node   /localization/odometry     nav_msgs/msg/Odometry           100 Hz
perception_node     /perception/obstacles      geometry_msgs/msg/PoseArray     10 Hz
prediction_node     /prediction/obstacles      rocas_msgs/msg/PredictedObstacles 10 Hz
planning_node       /planning/path             nav_msgs/msg/Path               10 Hz
control_node        /control/cmd               ackermann_msgs/msg/AckermannDriveStamped 100 Hz
==================  =========================  ==============================  ======

In the *accident* run, prediction starts to treat one slowly moving car as static at
``deviate_at_s``; planning stops yielding ``lag_s`` later, control ``lag_s`` after that.
Perception carries independent sensor noise in both runs, so its channel differs throughout
while the true first deviating node is ``prediction_node``.

Like a file recorded by ``ros2 bag record``, the channels name no publisher (rosbag2 stores
none, see the recording contract); :data:`ROS2_CMG` is the topology a user supplies with
``--cmg`` or writes into a copy with ``rocas annotate``.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from rocas.recording.synthetic import MixConfig

_SEP = "=" * 80

_TIME = "int32 sec\nuint32 nanosec"
_HEADER = "builtin_interfaces/Time stamp\nstring frame_id"
_POINT = "float64 x\nfloat64 y\nfloat64 z"
_QUATERNION = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1"
_POSE = "Point position\nQuaternion orientation"
_VECTOR3 = "float64 x\nfloat64 y\nfloat64 z"
_TWIST = "Vector3  linear\nVector3  angular"


def _concat(main: str, *deps: tuple[str, str]) -> str:
    """A ros2msg schema: the main definition, then each dependency under a ``MSG:`` line."""
    parts = [main]
    for name, text in deps:
        parts.append(f"{_SEP}\nMSG: {name}\n{text}")
    return "\n".join(parts) + "\n"


_GEOMETRY = (
    ("geometry_msgs/Pose", _POSE),
    ("geometry_msgs/Point", _POINT),
    ("geometry_msgs/Quaternion", _QUATERNION),
)
_STAMPED = (("std_msgs/Header", _HEADER), ("builtin_interfaces/Time", _TIME))

#: (topic, node, type, rate [Hz], ros2msg schema text)
CHANNELS: tuple[tuple[str, str, str, int, str], ...] = (
    ("/localization/odometry", "localization_node", "nav_msgs/msg/Odometry", 100, _concat(
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist",
        *_STAMPED,
        ("geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance"),
        *_GEOMETRY,
        ("geometry_msgs/TwistWithCovariance", "Twist twist\nfloat64[36] covariance"),
        ("geometry_msgs/Twist", _TWIST),
        ("geometry_msgs/Vector3", _VECTOR3),
    )),
    ("/perception/obstacles", "perception_node", "geometry_msgs/msg/PoseArray", 10, _concat(
        "std_msgs/Header header\ngeometry_msgs/Pose[] poses", *_STAMPED, *_GEOMETRY,
    )),
    ("/prediction/obstacles", "prediction_node", "rocas_msgs/msg/PredictedObstacles", 10, _concat(
        "std_msgs/Header header\nPredictedObstacle[] obstacles",
        *_STAMPED,
        ("rocas_msgs/PredictedObstacle",
         "uint32 id\nbool is_static\nfloat32 speed_mps\ngeometry_msgs/Pose pose\n"
         "geometry_msgs/Point[] trajectory"),
        *_GEOMETRY,
    )),
    ("/planning/path", "planning_node", "nav_msgs/msg/Path", 10, _concat(
        "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses",
        *_STAMPED,
        ("geometry_msgs/PoseStamped", "std_msgs/Header header\nPose pose"),
        *_GEOMETRY,
    )),
    ("/control/cmd", "control_node", "ackermann_msgs/msg/AckermannDriveStamped", 100, _concat(
        "std_msgs/Header header\nAckermannDrive drive",
        *_STAMPED,
        ("ackermann_msgs/AckermannDrive",
         "float32 steering_angle\nfloat32 steering_angle_velocity\nfloat32 speed\n"
         "float32 acceleration\nfloat32 jerk"),
    )),
)
CONTROL_TOPIC = "/control/cmd"
#: Who reads each topic (ROS 2 node names).
READERS = {
    "/localization/odometry": ("prediction_node", "planning_node", "control_node"),
    "/perception/obstacles": ("prediction_node", "planning_node"),
    "/prediction/obstacles": ("planning_node",),
    "/planning/path": ("control_node",),
    "/control/cmd": ("vehicle_interface",),
}
#: The topology as a ``--cmg`` file's JSON (what a ROS 2 user writes by hand).
ROS2_CMG: dict[str, Any] = {
    "modules": {
        node: {
            "writes": [topic],
            "reads": sorted(t for t, rs in READERS.items() if node in rs),
        }
        for topic, node, _, _, _ in CHANNELS
    },
    "control_channel": CONTROL_TOPIC,
}
FIRST_DEVIATING_NODE = "prediction_node"


# the same shape as the protobuf mix (plan_points: poses of the planned path)
Ros2MixConfig = MixConfig
_DEFAULT = MixConfig()


def write_ros2_run(path: str | os.PathLike[str], *, accident: bool,
                   cfg: Ros2MixConfig = _DEFAULT) -> None:
    """Write one scripted ROS 2 run to ``path`` with mcap-ros2-support's ``Writer``."""
    from mcap_ros2.writer import Writer

    rng = np.random.default_rng(cfg.seed * 2 + (1 if accident else 0))
    dev = {
        "prediction_node": cfg.deviate_at_s,
        "planning_node": cfg.deviate_at_s + cfg.lag_s,
        "control_node": cfg.deviate_at_s + 2 * cfg.lag_s,
    } if accident else {}
    tmp = f"{os.fspath(path)}.part"
    with open(tmp, "wb") as f:
        w = Writer(f)
        schemas = {topic: w.register_msgdef(typ, text) for topic, _, typ, _, text in CHANNELS}
        for k in range(int(round(cfg.duration_s * 100))):
            t = k / 100.0
            ns = k * 10_000_000
            for topic, node, _, hz, _ in CHANNELS:
                if k % (100 // hz):
                    continue
                deviated = node in dev and t >= dev[node]
                msg = _message(topic, t, deviated, cfg, rng)
                msg["header"] = {"stamp": {"sec": int(t), "nanosec": (k % 100) * 10_000_000},
                                 "frame_id": "map"}
                w.write_message(topic, schemas[topic], msg, log_time=ns, publish_time=ns)
        w.finish()
    os.replace(tmp, path)


def _pose(x: float, y: float) -> dict[str, Any]:
    return {"position": {"x": x, "y": y, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}


def _obstacle_state(i: int, t: float) -> tuple[float, float, float]:
    """World x [m], y [m] and speed [m/s] of scripted obstacle i at time t [s]."""
    speed = 0.4 if i == 3 else 2.0 + (i % 5)
    return 20.0 + 8.0 * i + speed * t, -6.0 + 4.0 * (i % 4), speed


def _message(topic: str, t: float, deviated: bool, cfg: Ros2MixConfig,
             rng: np.random.Generator) -> dict[str, Any]:
    ego_x, ego_v = 10.0 * t, 10.0
    if topic == "/localization/odometry":
        cov = [0.0] * 36
        cov[0] = cov[7] = 0.01
        return {"child_frame_id": "base_link",
                "pose": {"pose": _pose(ego_x, 0.0), "covariance": cov},
                "twist": {"twist": {"linear": {"x": ego_v, "y": 0.0, "z": 0.0},
                                    "angular": {"x": 0.0, "y": 0.0, "z": 0.0}},
                          "covariance": cov}}
    if topic == "/perception/obstacles":
        poses = []
        for i in range(cfg.obstacles):
            x, y, _ = _obstacle_state(i, t)
            noise = float(rng.normal(0.0, 0.02)) if rng.random() < 0.3 else 0.0
            poses.append(_pose(x - ego_x + noise, y))
        return {"poses": poses}
    if topic == "/prediction/obstacles":
        obstacles = []
        for i in range(cfg.obstacles):
            x, y, v = _obstacle_state(i, t)
            static = i == 3 and deviated  # below the still-obstacle threshold: no forecast
            trajectory = [] if static else [
                {"x": x + v * j * 0.1, "y": y + (0.005 * j if i == 3 else 0.0), "z": 0.0}
                for j in range(cfg.forecast_points)
            ]
            obstacles.append({"id": i, "is_static": static, "speed_mps": v,
                              "pose": _pose(x, y), "trajectory": trajectory})
        return {"obstacles": obstacles}
    if topic == "/planning/path":
        v = 10.0 if deviated else 6.0  # yields to the slow car until prediction loses it
        return {"poses": [{"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": "map"},
                           "pose": _pose(ego_x + v * j * 0.05, 0.0)}
                          for j in range(cfg.plan_points)]}
    if topic == "/control/cmd":
        brake = not deviated
        return {"drive": {"steering_angle": math.sin(t) * 0.1, "steering_angle_velocity": 0.0,
                          "speed": 10.0 if deviated else 6.0,
                          "acceleration": -1.5 if brake else 0.5, "jerk": 0.0}}
    raise ValueError(topic)


def write_ros2_pair(directory: str | os.PathLike[str], cfg: Ros2MixConfig = _DEFAULT,
                    name: str = "ros2") -> tuple[str, str]:
    """Write ``<name>_accident.mcap`` and ``<name>_reference.mcap``; returns both paths."""
    acc = os.path.join(directory, f"{name}_accident.mcap")
    ref = os.path.join(directory, f"{name}_reference.mcap")
    write_ros2_run(acc, accident=True, cfg=cfg)
    write_ros2_run(ref, accident=False, cfg=cfg)
    return acc, ref
