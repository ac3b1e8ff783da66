"""Actor behaviour: follow a route with a speed profile, optionally keep a distance (IDM).

Vehicles steer with pure pursuit through the friction-limited bicycle (so a truck on a wet
road drifts wide in a turn); cyclists and pedestrians are points moved along their path.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rocas.sim.dynamics import (
    LATERAL_GRIP_FACTOR,
    VehicleState,
    bicycle_step,
    path_point,
    profile_speed,
)
from rocas.sim.geometry import clip, wrap_angle
from rocas.sim.world import KIND_VEHICLE, BatchWorld

ACTOR_ACCEL_MPS2 = 2.5       # [m/s^2] largest acceleration of actors
ACTOR_DECEL_MPS2 = 6.0       # [m/s^2] largest deceleration of actors
SPEED_GAIN_PER_S = 1.5       # [1/s] speed-tracking gain
REACTIVE_HEADWAY_S = 1.2     # [s]
PROJECTION_WINDOW = np.arange(-2, 7)  # samples around the last match (0.5 m apart)


@dataclass(frozen=True, eq=False)
class ActorState:
    """Actor states, each (N, A): pose and motion, plus progress ``s`` on the path [m] and
    the nearest path sample ``index``."""

    body: VehicleState
    s: np.ndarray
    index: np.ndarray


def initial_actors(world: BatchWorld) -> ActorState:
    s = world.actor_start_s.copy()
    x, y, h = path_point(world.actor_path, world.actor_path_heading, world.actor_path_ds, s)
    v = profile_speed(0.0, world.actor_profile_t, world.actor_profile_v)
    idx = np.round(s / np.maximum(world.actor_path_ds, 1e-9)).astype(np.int64)
    return ActorState(VehicleState(x, y, h, h.copy(), v), s, idx)


def step_actors(world: BatchWorld, state: ActorState, t: float, ego: VehicleState,
                friction: np.ndarray) -> ActorState:
    """Advance every actor by one step (decide, then integrate)."""
    dt = world.dt_s
    b = state.body
    n, a = b.x.shape
    if a == 0:
        return state
    v_target = profile_speed(t, world.actor_profile_t, world.actor_profile_v)
    accel = clip(SPEED_GAIN_PER_S * (v_target - b.speed), -ACTOR_DECEL_MPS2, ACTOR_ACCEL_MPS2)
    # reactive actors keep a distance to the ego and to other actors ahead
    ox = np.concatenate([b.x, ego.x[:, None]], 1)
    oy = np.concatenate([b.y, ego.y[:, None]], 1)
    ov = np.concatenate([b.speed, ego.speed[:, None]], 1)
    ol = np.concatenate([world.actor_dims[..., 0], np.full((n, 1), world.ego_dims[0])], 1)
    ow = np.concatenate([world.actor_dims[..., 1], np.full((n, 1), world.ego_dims[1])], 1)
    c, s = np.cos(b.yaw)[..., None], np.sin(b.yaw)[..., None]
    dx = ox[:, None, :] - b.x[..., None]
    dy = oy[:, None, :] - b.y[..., None]
    lon = dx * c + dy * s
    lat = -dx * s + dy * c
    not_self = ~np.eye(a, a + 1, dtype=bool)[None]
    ahead = not_self & (lon > 0) & (np.abs(lat) < (world.actor_dims[..., 1:2] + ow[:, None, :])
                                    / 2 + 0.3)
    gap = np.where(ahead, lon - (world.actor_dims[..., 0:1] + ol[:, None, :]) / 2, np.inf)
    j = np.argmin(gap, axis=-1)
    g = gap.min(axis=-1)
    v_lead = ov[np.arange(n)[:, None], j]
    sstar = world.actor_reactive_gap + np.maximum(
        0.0, b.speed * REACTIVE_HEADWAY_S + b.speed * (b.speed - v_lead)
        / (2 * np.sqrt(ACTOR_ACCEL_MPS2 * 3.0)))
    idm = ACTOR_ACCEL_MPS2 * (1 - (sstar / np.maximum(g, 0.1)) ** 2)
    accel = np.where(world.actor_reactive & np.isfinite(g),
                     np.maximum(np.minimum(accel, idm), -ACTOR_DECEL_MPS2), accel)
    # vehicles: pure pursuit through the bicycle model
    ds = np.maximum(world.actor_path_ds, 1e-9)
    look = np.maximum(4.0, 0.9 * b.speed)
    tx, ty, _ = path_point(world.actor_path, world.actor_path_heading, ds, state.s + look)
    alpha = wrap_angle(np.arctan2(ty - b.y, tx - b.x) - b.yaw)
    kappa = 2.0 * np.sin(alpha) / np.maximum(np.hypot(tx - b.x, ty - b.y), 1.0)
    grip = LATERAL_GRIP_FACTOR[clip(world.actor_model, 0, 3)]
    veh, _ = bicycle_step(b, accel, kappa, friction[:, None], grip, dt)
    # project vehicles back on their path (local window)
    p = world.actor_path.shape[2]
    cand = clip(state.index[..., None] + PROJECTION_WINDOW, 0, p - 1)
    rn = np.arange(n)[:, None, None]
    ra = np.arange(a)[None, :, None]
    pts = world.actor_path[rn, ra, cand]  # (N, A, W, 2)
    best = np.argmin((pts[..., 0] - veh.x[..., None]) ** 2 + (pts[..., 1] - veh.y[..., None]) ** 2,
                     axis=-1)
    v_idx = cand[rn[..., 0], ra[..., 0], best]
    # points: move along the path
    v_pt = np.maximum(b.speed + accel * dt, 0.0)
    s_pt = state.s + 0.5 * (b.speed + v_pt) * dt
    px2, py2, ph2 = path_point(world.actor_path, world.actor_path_heading, ds, s_pt)
    is_veh = world.actor_kind == KIND_VEHICLE
    body = VehicleState(
        x=np.where(is_veh, veh.x, px2), y=np.where(is_veh, veh.y, py2),
        yaw=np.where(is_veh, veh.yaw, ph2), course=np.where(is_veh, veh.course, ph2),
        speed=np.where(is_veh, veh.speed, v_pt))
    s_new = np.where(is_veh, v_idx * ds, s_pt)
    idx = np.where(is_veh, v_idx, np.round(s_pt / ds).astype(np.int64))
    return ActorState(body, s_new, idx)
