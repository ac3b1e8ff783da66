"""gnss: the ego's own state as the GNSS/IMU unit reports it (20 Hz), with its route progress."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rocas.sim.rng import normal
from rocas.sim.world import BatchWorld, project_on_reference

_STREAM = 9101  # noise stream ids of this stack (distinct from the built-in ADS's)


@dataclass(frozen=True, eq=False)
class EgoEstimate:
    """(N,) each: x, y [m], heading [rad], speed [m/s], accel [m/s^2], route_s [m]."""

    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    accel: np.ndarray
    route_s: np.ndarray


class Gnss:
    def __init__(self, world: BatchWorld, params: Mapping[str, np.ndarray]) -> None:
        self.world = world
        self.pos_std = params["gnss.position_noise_m"]
        self.speed_std = params["gnss.speed_noise_mps"]

    def step(self, tick: int, x: np.ndarray, y: np.ndarray, yaw: np.ndarray, speed: np.ndarray,
             accel: np.ndarray) -> EgoEstimate:
        z = normal(self.world.seeds, tick, _STREAM, (3,))
        ex = x + self.pos_std * z[:, 0]
        ey = y + self.pos_std * z[:, 1]
        v = np.maximum(speed + self.speed_std * z[:, 2], 0.0)
        _, s, _ = project_on_reference(self.world.road, ex, ey)
        return EgoEstimate(ex, ey, yaw.copy(), v, accel.copy(), s)
