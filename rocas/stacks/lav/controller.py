"""controller: LAV's ``pid_control`` and its post-processing (20 Hz).

A speed PID toward the plan's target speed and pure pursuit on its waypoints give steer,
throttle and brake; then, in LAV's order: the brake model's decision brakes fully, else a
``plan_collide`` brakes toward a stop, and above MAX_SPEED the throttle is cut.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rocas.sim.geometry import clip
from rocas.stacks.lav.brake import BrakePrediction
from rocas.stacks.lav.gnss import EgoEstimate
from rocas.stacks.lav.planner import EgoPlan

INTEGRAL_LIMIT_MPS = 2.0   # [m/s] anti-windup bound
MAX_CURVATURE_1PM = 0.2    # [1/m] the steering's limit
COLLIDE_BRAKE = 0.4        # brake pedal held on a plan_collide (LAV's hazard brake is 1.0)
OVERRIDES = ("", "brake_model", "plan_collide", "max_speed")


@dataclass(frozen=True, eq=False)
class Command:
    """(N,) each: steer in [-1, 1], throttle and brake in [0, 1], override (OVERRIDES
    index), and what the vehicle is asked for: accel [m/s^2], curvature [1/m]."""

    steer: np.ndarray
    throttle: np.ndarray
    brake: np.ndarray
    override: np.ndarray
    accel: np.ndarray
    curvature: np.ndarray


class Controller:
    def __init__(self, params: Mapping[str, np.ndarray], dt_s: float, n: int) -> None:
        self.kp = params["controller.speed_kp"]
        self.ki = params["controller.speed_ki"]
        self.kd = params["controller.speed_kd"]
        self.lookahead_s = params["controller.lookahead_s"]
        self.min_lookahead = params["controller.min_lookahead_m"]
        self.max_throttle = params["controller.max_throttle_accel_mps2"]
        self.max_brake = params["controller.max_brake_decel_mps2"]
        self.max_speed = params["planner.max_speed_kmh"] / 3.6
        self.dt = dt_s
        self.integral = np.zeros(n)
        self.last_error = np.zeros(n)

    def step(self, ego: EgoEstimate, plan: EgoPlan, brake: BrakePrediction) -> Command:
        err = plan.target_speed - ego.speed
        self.integral = clip(self.integral + err * self.dt, -INTEGRAL_LIMIT_MPS,
                             INTEGRAL_LIMIT_MPS)
        a = self.kp * err + self.ki * self.integral + self.kd * (err - self.last_error) / self.dt
        self.last_error = err
        throttle = clip(a / self.max_throttle, 0.0, 1.0)
        pedal = clip(-a / self.max_brake, 0.0, 1.0)
        # pure pursuit: the first waypoint at least the look-ahead distance away
        look = np.maximum(self.min_lookahead, self.lookahead_s * ego.speed)
        dx = plan.waypoints[..., 0] - ego.x[:, None]
        dy = plan.waypoints[..., 1] - ego.y[:, None]
        dist = np.hypot(dx, dy)
        far = dist >= look[:, None]
        idx = np.where(far.any(axis=1), far.argmax(axis=1), dist.shape[1] - 1)
        rows = np.arange(idx.shape[0])
        tx, ty, td = dx[rows, idx], dy[rows, idx], np.maximum(dist[rows, idx], 1e-3)
        lateral = -tx * np.sin(ego.heading) + ty * np.cos(ego.heading)
        curvature = clip(2.0 * lateral / (td * td), -MAX_CURVATURE_1PM, MAX_CURVATURE_1PM)
        override = np.zeros(idx.shape[0], dtype=np.int64)
        too_fast = ego.speed > self.max_speed
        throttle = np.where(too_fast, 0.0, throttle)
        override = np.where(too_fast, 3, override)
        collide = plan.collide & ~brake.brake
        throttle = np.where(collide, 0.0, throttle)
        pedal = np.where(collide, np.maximum(pedal, COLLIDE_BRAKE), pedal)
        override = np.where(collide, 2, override)
        throttle = np.where(brake.brake, 0.0, throttle)
        pedal = np.where(brake.brake, 1.0, pedal)
        override = np.where(brake.brake, 1, override)
        accel = throttle * self.max_throttle - pedal * self.max_brake
        return Command(curvature / MAX_CURVATURE_1PM, throttle, pedal, override, accel,
                       curvature)
