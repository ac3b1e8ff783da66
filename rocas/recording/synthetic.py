"""Scripted recordings of the built-in ADS's channel mix (no simulation behind them).

For benchmarks, demos and tests that need realistic channel rates and message sizes:
localization, chassis and control at 100 Hz; perception (obstacles, traffic lights,
brake signal), prediction and planning at 10 Hz, with obstacle lists, forecast and
planned trajectories of realistic length (about 1 MB/s, as the paper's 30 MB per 30 s).

In the *accident* run, prediction starts to treat one slowly moving car as static at
``deviate_at_s`` (the mechanism of the paper's accident type A1); planning stops yielding
to it ``lag_s`` later and control stops braking ``lag_s`` after that. Perception carries
independent sensor noise in both runs. The true initial deviating module is ``prediction``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from rocas.msgs import (
    chassis_pb2,
    control_pb2,
    localization_pb2,
    perception_pb2,
    planning_pb2,
    prediction_pb2,
)
from rocas.recording.writer import RecordingWriter

#: (topic, message class, writer, readers, rate [Hz])
CHANNELS = (
    ("/localization/pose", localization_pb2.LocalizationEstimate, "localization",
     ("prediction", "planning", "control"), 100),
    ("/canbus/chassis", chassis_pb2.Chassis, "canbus", ("planning", "control"), 100),
    ("/perception/obstacles", perception_pb2.PerceptionObstacles, "perception",
     ("prediction", "planning"), 10),
    ("/perception/traffic_light", perception_pb2.TrafficLightDetection, "perception",
     ("planning",), 10),
    ("/perception/brake_signal", perception_pb2.BrakeSignal, "perception", ("planning",), 10),
    ("/prediction", prediction_pb2.PredictionObstacles, "prediction", ("planning",), 10),
    ("/planning", planning_pb2.ADCTrajectory, "planning", ("control",), 10),
    ("/control", control_pb2.ControlCommand, "control", ("canbus",), 100),
)
CONTROL_TOPIC = "/control"


@dataclass(frozen=True)
class MixConfig:
    """Shape of a scripted run.

    Attributes:
        duration_s: length of the run [s].
        obstacles: obstacles perceived and predicted per frame.
        forecast_points: points per predicted trajectory.
        plan_points: points of the planned trajectory.
        deviate_at_s: when prediction deviates in the accident run [s].
        lag_s: delay from one module's deviation to the next one's [s].
        seed: random seed (sensor noise).
    """

    duration_s: float = 30.0
    obstacles: int = 30
    forecast_points: int = 80
    plan_points: int = 150
    deviate_at_s: float = 20.0
    lag_s: float = 0.8
    seed: int = 0


def write_mix_run(path: str | os.PathLike[str], *, accident: bool, cfg: MixConfig = MixConfig()
                  ) -> None:
    """Write one scripted run to ``path`` (atomically)."""
    rng = np.random.default_rng(cfg.seed * 2 + (1 if accident else 0))
    dev = {
        "prediction": cfg.deviate_at_s,
        "planning": cfg.deviate_at_s + cfg.lag_s,
        "control": cfg.deviate_at_s + 2 * cfg.lag_s,
    } if accident else {}
    seqs = {c[0]: 0 for c in CHANNELS}
    with RecordingWriter(path) as w:
        for topic, cls, writer, readers, _ in CHANNELS:
            w.add_channel(topic, cls, writers=[writer], readers=readers,
                          role="control" if topic == CONTROL_TOPIC else None)
        ticks = int(round(cfg.duration_s * 100))
        for k in range(ticks):
            t = k / 100.0
            ns = k * 10_000_000
            ego_x, ego_v = 10.0 * t, 10.0
            for topic, _, writer, _, hz in CHANNELS:
                if k % (100 // hz):
                    continue
                deviated = writer in dev and t >= dev[writer]
                msg = _message(topic, t, ego_x, ego_v, deviated, cfg, rng)
                msg.header.timestamp_sec = t
                msg.header.module_name = writer
                msg.header.sequence_num = seqs[topic]
                seqs[topic] += 1
                w.write(topic, msg, log_time_ns=ns)


def _obstacle_state(i: int, t: float) -> tuple[float, float, float]:
    """World x, y and speed of scripted obstacle i at time t."""
    speed = 0.4 if i == 3 else 2.0 + (i % 5)
    return 20.0 + 8.0 * i + speed * t, -6.0 + 4.0 * (i % 4), speed


def _message(topic, t, ego_x, ego_v, deviated, cfg: MixConfig, rng):
    if topic == "/localization/pose":
        m = localization_pb2.LocalizationEstimate(lane_id="lane_1", lane_s=ego_x)
        m.pose.position.x, m.pose.linear_velocity.x = ego_x, ego_v
        return m
    if topic == "/canbus/chassis":
        return chassis_pb2.Chassis(speed_mps=ego_v, odometer_m=ego_x, engine_started=True,
                                   throttle_percentage=20.0, gear_location=1, driving_mode=1)
    if topic == "/perception/obstacles":
        m = perception_pb2.PerceptionObstacles()
        m.ego_position.x = ego_x
        for i in range(cfg.obstacles):
            x, y, v = _obstacle_state(i, t)
            o = m.perception_obstacle.add(id=i, type=5, sub_type=1 + i % 4, color="white",
                                          theta=0.0, length=4.5, width=1.9, height=1.5,
                                          tracking_time=t)
            o.position.x, o.position.y = x - ego_x, y
            o.velocity.x = v
            o.confidence = round(0.9 + rng.normal(0, 0.02), 3) if rng.random() < 0.3 else 0.9
            for cx, cy in ((2.25, 0.95), (2.25, -0.95), (-2.25, -0.95), (-2.25, 0.95)):
                o.polygon_point.add(x=x - ego_x + cx, y=y + cy)
        return m
    if topic == "/perception/traffic_light":
        m = perception_pb2.TrafficLightDetection(contain_lights=True, selected_light_id="tl_1")
        m.traffic_light.add(id="tl_1", color=3, confidence=0.95, distance_m=120.0 - ego_x)
        return m
    if topic == "/perception/brake_signal":
        return perception_pb2.BrakeSignal(brake_probability=0.05, brake_threshold=0.5)
    if topic == "/prediction":
        m = prediction_pb2.PredictionObstacles(start_timestamp=t, end_timestamp=t + 8.0)
        for i in range(cfg.obstacles):
            x, y, v = _obstacle_state(i, t)
            po = m.prediction_obstacle.add(timestamp=t, predicted_period=8.0, intent=1)
            po.perception_obstacle.id = i
            po.perception_obstacle.position.x, po.perception_obstacle.position.y = x, y
            if i == 3 and deviated:  # below the still-obstacle threshold: no forecast
                po.is_static = True
                po.intent = 4
                continue
            traj = po.trajectory.add(probability=1.0)
            for j in range(cfg.forecast_points):
                dt = j * 0.1
                p = traj.trajectory_point.add(theta=0.0, v=v, relative_time=dt)
                p.position.x, p.position.y = x + v * dt, y + (0.05 * dt if i == 3 else 0.0)
        return m
    if topic == "/planning":
        m = planning_pb2.ADCTrajectory(lane_id="lane_1", cruise_speed=10.0)
        yield_to_3 = not deviated
        v = 6.0 if yield_to_3 else 10.0
        for j in range(cfg.plan_points):
            s = v * j * 0.05
            m.trajectory_point.add(x=ego_x + s, y=0.0, theta=0.0, kappa=0.0, s=s, v=v,
                                   a=-1.0 if yield_to_3 else 0.0, relative_time=j * 0.05)
        m.total_path_length = m.trajectory_point[-1].s
        m.total_path_time = m.trajectory_point[-1].relative_time
        m.main_decision.type = 0
        d = m.object_decision.add(id="3", type=2 if yield_to_3 else 0,
                                  distance_s=8.0 if yield_to_3 else 0.0)
        d.reason = "yield to slow car" if yield_to_3 else "static obstacle off path"
        return m
    if topic == "/control":
        brake = 0.0 if deviated else 15.0
        return control_pb2.ControlCommand(throttle=0.0 if brake else 20.0, brake=brake,
                                          acceleration=-1.5 if brake else 0.5,
                                          steering_target=math.sin(t) * 0.1)
    raise ValueError(topic)


def write_mix_pair(directory: str | os.PathLike[str], cfg: MixConfig = MixConfig(),
                   name: str = "mix") -> tuple[str, str]:
    """Write ``<name>_accident.mcap`` and ``<name>_reference.mcap``; returns both paths."""
    acc = os.path.join(directory, f"{name}_accident.mcap")
    ref = os.path.join(directory, f"{name}_reference.mcap")
    write_mix_run(acc, accident=True, cfg=cfg)
    write_mix_run(ref, accident=False, cfg=cfg)
    return acc, ref
