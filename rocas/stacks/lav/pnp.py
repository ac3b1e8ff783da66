"""pnp: the joint perception-and-prediction model (LAV's ``infer_model`` on the lidar).

It detects every actor and map object within the lidar range and forecasts each one's
trajectory in one pass: constant speed and turn rate (the turn rate from the heading change
since its previous frame), or standing still when slower than ``pnp.static_speed_mps``.
Shapes: N variants, M = A actors + E objects, K forecast waypoints.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rocas.sim.geometry import wrap_angle
from rocas.sim.rng import normal
from rocas.sim.world import KIND_CYCLIST, KIND_PEDESTRIAN, KIND_VEHICLE, BatchWorld

MAX_FORECAST = 10  # waypoints per forecast (the horizon's steps are capped at this)
KIND_NAMES = {KIND_VEHICLE: "vehicle", KIND_CYCLIST: "bicycle", KIND_PEDESTRIAN: "pedestrian"}
_STREAM = 9201


@dataclass(frozen=True, eq=False)
class Agents:
    """What pnp publishes.

    Attributes:
        seen: (N, M) bool, detected this frame.
        x, y, heading, speed: (N, M) [m, m, rad, m/s].
        length, width, height: (N, M) [m].
        kind: (N, M) world kind code; color: (N, M) colour code (-1: objects).
        is_static: (N, M) bool.
        forecast: (N, M, K, 2) positions [m]; forecast_t: (N, K) times ahead [s];
        forecast_valid: (N, K) bool.
    """

    seen: np.ndarray
    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    length: np.ndarray
    width: np.ndarray
    height: np.ndarray
    kind: np.ndarray
    color: np.ndarray
    is_static: np.ndarray
    forecast: np.ndarray
    forecast_t: np.ndarray
    forecast_valid: np.ndarray


class PerceptionPrediction:
    def __init__(self, world: BatchWorld, params: Mapping[str, np.ndarray], period_s: float
                 ) -> None:
        self.world = world
        self.period_s = period_s
        self.range = params["pnp.lidar_range_m"]
        self.noise = params["pnp.position_noise_m"]
        self.horizon = params["pnp.forecast_horizon_s"]
        self.step_s = params["pnp.forecast_step_s"]
        self.static_speed = params["pnp.static_speed_mps"]
        w = world
        n = w.batch_size
        self.dims = np.concatenate([w.actor_dims, w.object_dims], 1)  # (N, M, 3)
        self.kind = np.concatenate([w.actor_kind, w.object_kind], 1)
        self.color = np.concatenate([w.actor_color, np.full(w.object_kind.shape, -1)], 1)
        self.last_yaw: np.ndarray | None = None
        k = np.arange(1, MAX_FORECAST + 1, dtype=np.float64)
        count = np.minimum(np.round(self.horizon / self.step_s), MAX_FORECAST)
        self.forecast_t = self.step_s[:, None] * k[None, :]  # (N, K)
        self.forecast_valid = k[None, :] <= count[:, None]
        self._n = n

    def step(self, tick: int, ego_x: np.ndarray, ego_y: np.ndarray, ax: np.ndarray,
             ay: np.ndarray, ayaw: np.ndarray, aspeed: np.ndarray) -> Agents:
        """``ego_*`` (N,); ``a*`` (N, A): the actors' true bodies (objects come from the map)."""
        w = self.world
        x = np.concatenate([ax, w.object_pos[..., 0]], 1)
        y = np.concatenate([ay, w.object_pos[..., 1]], 1)
        yaw = np.concatenate([ayaw, w.object_yaw], 1)
        speed = np.concatenate([aspeed, np.zeros(w.object_yaw.shape)], 1)
        m = x.shape[1]
        z = normal(w.seeds, tick, _STREAM, (m, 2))
        x = x + self.noise[:, None] * z[..., 0]
        y = y + self.noise[:, None] * z[..., 1]
        seen = np.hypot(x - ego_x[:, None], y - ego_y[:, None]) <= self.range[:, None]
        turn = np.zeros_like(yaw) if self.last_yaw is None else \
            wrap_angle(yaw - self.last_yaw) / self.period_s
        self.last_yaw = yaw
        static = speed < self.static_speed[:, None]
        v = np.where(static, 0.0, speed)
        w_rate = np.where(static, 0.0, turn)
        fx = np.empty((self._n, m, MAX_FORECAST))
        fy = np.empty((self._n, m, MAX_FORECAST))
        px, py, h = x, y, yaw
        for k in range(MAX_FORECAST):
            dt = self.step_s[:, None]
            mid = h + 0.5 * w_rate * dt
            px = px + v * dt * np.cos(mid)
            py = py + v * dt * np.sin(mid)
            h = h + w_rate * dt
            fx[..., k], fy[..., k] = px, py
        return Agents(seen, x, y, yaw, speed, self.dims[..., 0], self.dims[..., 1],
                      self.dims[..., 2], self.kind, self.color, static,
                      np.stack([fx, fy], -1), self.forecast_t, self.forecast_valid)
