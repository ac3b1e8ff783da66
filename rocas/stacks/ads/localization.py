"""Localization (pose estimate) and canbus (actuators and chassis feedback) modules."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rocas import numerics
from rocas.scenarios.model import EGO_WHEELBASE_M
from rocas.sim import rng
from rocas.sim.dynamics import VehicleState
from rocas.sim.geometry import clip, wrap_angle
from rocas.sim.world import BatchWorld, project_on_reference

_STREAM_LOC = 10
_STREAM_CHASSIS = 20


@dataclass(frozen=True, eq=False)
class LocalizationOutput:
    """Published pose estimate, each field shape (N,).

    Attributes:
        x, y [m], heading [rad], speed [m/s], vx, vy [m/s], ax, ay [m/s^2], yaw_rate [rad/s],
        lane: lane code of the matched route lane (-1 when unmatched), lane_s [m].
    """

    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    ax: np.ndarray
    ay: np.ndarray
    yaw_rate: np.ndarray
    lane: np.ndarray
    lane_s: np.ndarray


class Localization:
    """Publishes the ego pose with configurable noise and matches it to the route lanes."""

    def __init__(self, world: BatchWorld, params: dict[str, np.ndarray]) -> None:
        self.world = world
        self.pos_std = params["localization.position_noise_std_m"]
        self.head_std = params["localization.heading_noise_std_rad"]
        self.speed_std = params["localization.speed_noise_std_mps"]
        self.match_dist = params["localization.lane_match_max_distance_m"]
        self.prev_yaw: np.ndarray | None = None

    def step(self, tick: int, ego: VehicleState, accel: np.ndarray) -> LocalizationOutput:
        noise = rng.normal(self.world.seeds, tick, _STREAM_LOC, (4,))
        x = ego.x + self.pos_std * noise[:, 0]
        y = ego.y + self.pos_std * noise[:, 1]
        heading = wrap_angle(ego.yaw + self.head_std * noise[:, 2])
        speed = np.maximum(ego.speed + self.speed_std * noise[:, 3], 0.0)
        yaw_rate = (np.zeros_like(x) if self.prev_yaw is None
                    else wrap_angle(ego.yaw - self.prev_yaw) / self.world.dt_s)
        self.prev_yaw = ego.yaw
        road = self.world.road
        idx, _, lateral = project_on_reference(road, x, y)
        matched = np.abs(lateral) <= self.match_dist
        c, s = np.cos(ego.course), np.sin(ego.course)
        return LocalizationOutput(
            x=x, y=y, heading=heading, speed=speed, vx=speed * c, vy=speed * s,
            ax=accel * c, ay=accel * s, yaw_rate=yaw_rate,
            lane=np.where(matched, road.ref_lane[idx], -1),
            lane_s=np.where(matched, road.ref_lane_s[idx], 0.0),
        )


@dataclass(frozen=True, eq=False)
class ChassisOutput:
    """Chassis feedback, each field shape (N,): speed [m/s], odometer [m], throttle, brake
    [0, 100] %, steering [-100, 100] %, emergency (bool)."""

    speed: np.ndarray
    odometer: np.ndarray
    throttle: np.ndarray
    brake: np.ndarray
    steering: np.ndarray
    emergency: np.ndarray


class Canbus:
    """Turns control commands into vehicle motion (actuator maps, lag, steering rate) and
    publishes chassis feedback."""

    def __init__(self, world: BatchWorld, params: dict[str, np.ndarray]) -> None:
        n = world.batch_size
        self.world = world
        self.max_accel = params["canbus.throttle_max_accel_mps2"]
        self.max_decel = params["canbus.brake_max_decel_mps2"]
        self.max_steer = params["canbus.max_steer_angle_rad"]
        self.tau = params["canbus.actuator_time_constant_s"]
        self.steer_rate = params["canbus.steer_rate_limit_radps"]
        self.speed_std = params["canbus.speed_sensor_noise_std_mps"]
        # the actuators' first-order lag per step, (N,): fixed for a run
        self.lag_gain = 1.0 - numerics.exp(-world.dt_s / self.tau)
        self.accel = np.zeros(n)          # realised actuator acceleration [m/s^2]
        self.wheel_angle = np.zeros(n)    # road-wheel angle [rad]
        self.throttle = np.zeros(n)
        self.brake = np.zeros(n)
        self.steering_pct = np.zeros(n)
        self.estop = np.zeros(n, dtype=bool)
        self.odometer = np.zeros(n)

    def feedback(self, tick: int, ego: VehicleState) -> ChassisOutput:
        noise = rng.normal(self.world.seeds, tick, _STREAM_CHASSIS, ())
        return ChassisOutput(
            speed=np.maximum(ego.speed + self.speed_std * noise, 0.0), odometer=self.odometer,
            throttle=self.throttle, brake=self.brake,
            steering=self.wheel_angle / self.max_steer * 100.0, emergency=self.estop,
        )

    def actuate(self, throttle: np.ndarray, brake: np.ndarray, steering_pct: np.ndarray,
                estop: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Apply a command for one step; returns (acceleration demand [m/s^2], curvature [1/m])."""
        dt = self.world.dt_s
        self.throttle, self.brake, self.steering_pct, self.estop = (
            throttle, brake, steering_pct, estop)
        target = throttle / 100.0 * self.max_accel - brake / 100.0 * self.max_decel
        k = self.lag_gain
        self.accel = self.accel + (target - self.accel) * k
        target_angle = clip(steering_pct, -100.0, 100.0) / 100.0 * self.max_steer
        step = clip((target_angle - self.wheel_angle) * k, -self.steer_rate * dt,
                       self.steer_rate * dt)
        self.wheel_angle = self.wheel_angle + step
        return self.accel, numerics.tan(self.wheel_angle) / EGO_WHEELBASE_M

    def advance_odometer(self, distance: np.ndarray) -> None:
        self.odometer = self.odometer + distance
