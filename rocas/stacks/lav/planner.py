"""planner: waypoints along the mission route and LAV's ``plan_collide`` check.

The speed rises from the current one toward ``min(MAX_SPEED, curve limit)`` at 2 m/s^2; the
waypoints are where that profile puts the ego along the route at every ``waypoint_spacing_s``.
``plan_collide`` compares the ego's planned position with each forecast agent's position at the
same times: closer (centre to centre) than ``dist_threshold_moving_m`` for a moving agent, or
than ``dist_threshold_static_m`` plus both half-widths for a standing one, is a collision.
A collision holds for ``COLLIDE_HOLD_S``: the check samples the plan only at the forecast's
times (0.5 s, about 5 m apart at speed), so an agent near the threshold is caught at some
frames and slips between samples at others, and without the hold the hazard brake chatters
on and off at the planner's rate.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rocas.sim.world import EGO_WIDTH_M, BatchWorld, reference_at
from rocas.stacks.lav.gnss import EgoEstimate
from rocas.stacks.lav.pnp import Agents

NUM_WAYPOINTS = 10
PLAN_ACCEL_MPS2 = 2.0     # [m/s^2] speed rise the waypoints assume
CURVE_PREVIEW_M = 30.0    # [m] curvature this far ahead limits the speed
MIN_WAYPOINT_GAP_M = 1.0  # [m] waypoints stay at least this far apart (a standing ego)
BEHIND_M = 1.0            # [m] agents whose centre is this far behind the ego's are not checked
COLLIDE_HOLD_S = 0.5      # [s] a detected plan collision is kept this long after its last frame


@dataclass(frozen=True, eq=False)
class EgoPlan:
    """waypoints: (N, W, 2) [m]; waypoint_t: (N, W) [s]; target_speed (N,) [m/s];
    collide (N,) bool; collide_in_s (N,) [s]; collide_agent (N,) index into the agents."""

    waypoints: np.ndarray
    waypoint_t: np.ndarray
    target_speed: np.ndarray
    collide: np.ndarray
    collide_in_s: np.ndarray
    collide_agent: np.ndarray


def _distance_along(v0: np.ndarray, v1: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Distance at times t (N, K) of a speed ramping from v0 to v1 (N,) at PLAN_ACCEL_MPS2."""
    a = np.where(v1 >= v0, PLAN_ACCEL_MPS2, -PLAN_ACCEL_MPS2)[:, None]
    t_ramp = (np.abs(v1 - v0) / PLAN_ACCEL_MPS2)[:, None]
    tr = np.minimum(t, t_ramp)
    return v0[:, None] * tr + 0.5 * a * tr * tr + v1[:, None] * np.maximum(t - t_ramp, 0.0)


class Planner:
    def __init__(self, world: BatchWorld, params: Mapping[str, np.ndarray], period_s: float
                 ) -> None:
        """``period_s``: time between two calls of :meth:`step` [s]."""
        self.world = world
        n = world.batch_size
        self.hold_steps = int(round(COLLIDE_HOLD_S / period_s))
        self.held = np.zeros(n, dtype=np.int64)  # (N,) frames the last collision still holds
        self.held_in_s = np.zeros(n)
        self.held_agent = np.zeros(n, dtype=np.int64)
        self.max_speed = params["planner.max_speed_kmh"] / 3.6
        self.lat_accel = params["planner.max_lateral_accel_mps2"]
        self.spacing = params["planner.waypoint_spacing_s"]
        self.d_moving = params["planner.dist_threshold_moving_m"]
        self.d_static = params["planner.dist_threshold_static_m"]
        road = world.road
        self.destination = road.destination_s_m

    def step(self, ego: EgoEstimate, agents: Agents) -> EgoPlan:
        road = self.world.road
        n = ego.x.shape[0]
        preview = ego.route_s[:, None] + np.linspace(0.0, CURVE_PREVIEW_M, 16)[None, :]
        _, _, _, kappa = reference_at(road, preview)
        curve = np.sqrt(self.lat_accel / np.maximum(np.abs(kappa).max(axis=1), 1e-6))
        left = np.maximum(self.destination - ego.route_s, 0.0)
        v_end = np.sqrt(2.0 * PLAN_ACCEL_MPS2 * left)
        target = np.minimum(np.minimum(self.max_speed, curve), v_end)
        tw = self.spacing[:, None] * np.arange(1, NUM_WAYPOINTS + 1)[None, :]
        dist = np.maximum(_distance_along(ego.speed, target, tw),
                          MIN_WAYPOINT_GAP_M * np.arange(1, NUM_WAYPOINTS + 1)[None, :])
        wx, wy, _, _ = reference_at(road, ego.route_s[:, None] + dist)
        # plan_collide at the forecast times
        ft = agents.forecast_t  # (N, K)
        ex, ey, _, _ = reference_at(road, ego.route_s[:, None] + _distance_along(
            ego.speed, target, ft))
        fx, fy = agents.forecast[..., 0], agents.forecast[..., 1]  # (N, M, K)
        gap = np.hypot(fx - ex[:, None, :], fy - ey[:, None, :])
        threshold = np.where(agents.is_static,
                             self.d_static[:, None] + 0.5 * (agents.width + EGO_WIDTH_M),
                             self.d_moving[:, None])  # (N, M)
        ahead = ((agents.x - ego.x[:, None]) * np.cos(ego.heading)[:, None]
                 + (agents.y - ego.y[:, None]) * np.sin(ego.heading)[:, None]) > -BEHIND_M
        hit = (gap < threshold[..., None]) & agents.forecast_valid[:, None, :] & \
            (agents.seen & ahead)[..., None]  # (N, M, K)
        any_k = hit.any(axis=1)  # (N, K)
        collide = any_k.any(axis=1)
        first_k = np.where(collide, any_k.argmax(axis=1), 0)
        when = np.where(collide, ft[np.arange(n), first_k], 0.0)
        first_m = (hit[np.arange(n), :, first_k].argmax(axis=1) if hit.shape[1]
                   else np.zeros(n, dtype=np.intp))  # no agent at all (an empty road)
        # the hold: a fresh collision restarts it, a held one keeps its time and agent
        held = ~collide & (self.held > 0)
        self.held = np.where(collide, self.hold_steps, np.maximum(self.held - 1, 0))
        self.held_in_s = np.where(collide, when, self.held_in_s)
        self.held_agent = np.where(collide, first_m, self.held_agent)
        collide = collide | held
        when = np.where(held, self.held_in_s, when)
        agent = np.where(held, self.held_agent, np.where(collide, first_m, 0))
        return EgoPlan(np.stack([wx, wy], -1), tw, target, collide, when, agent)
