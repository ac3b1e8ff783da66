"""Actor behaviour: follow a route with a speed profile, optionally keep a distance (IDM).

Vehicles steer their front axle with pure pursuit through the friction-limited bicycle (so a
truck on a wet road drifts wide in a turn); the body trails behind it, its rear axle dragged
toward the front one, so a long vehicle's body cuts inside a turn (off-tracking) and its
heading lags the path's. On a straight path the body centre is where its arc length says.
Cyclists and pedestrians are points moved along their path.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from rocas import numerics
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
PURSUIT_MIN_LOOKAHEAD_M = 4.0  # [m] shortest pure-pursuit look-ahead of actors
PURSUIT_LOOKAHEAD_S = 0.9      # [s] look-ahead per unit of speed
#: Per vehicle model (sedan, suv, truck, bus): wheelbase [m] and how far the front axle is
#: ahead of the body centre [m] (half the length minus the front overhang).
WHEELBASE_M = np.array([2.8, 2.9, 5.0, 6.5])
FRONT_AXLE_AHEAD_M = np.array([1.45, 1.5, 2.95, 3.4])


def axle_geometry(kind: np.ndarray, model: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(front axle ahead of the centre, wheelbase) [m] per actor; 0 for non-vehicles."""
    is_veh = kind == KIND_VEHICLE
    m = clip(model, 0, 3)
    return np.where(is_veh, FRONT_AXLE_AHEAD_M[m], 0.0), np.where(is_veh, WHEELBASE_M[m], 0.0)


def trail_body(gx: np.ndarray, gy: np.ndarray, rear_x: np.ndarray, rear_y: np.ndarray,
               yaw_prev: np.ndarray, ahead: np.ndarray, wheelbase: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body (centre x, y, yaw) of a vehicle whose front axle is at (gx, gy) and whose rear axle
    was at (rear_x, rear_y): the rear axle is dragged toward the front one (the body turns to
    point from it to the front axle). Points (wheelbase 0) keep ``yaw_prev``."""
    dx, dy = gx - rear_x, gy - rear_y
    yaw = np.where((wheelbase > 0) & (np.hypot(dx, dy) > 1e-6), numerics.arctan2(dy, dx), yaw_prev)
    return gx - ahead * np.cos(yaw), gy - ahead * np.sin(yaw), yaw


def pursuit_lookahead(speed: np.ndarray) -> np.ndarray:
    """Look-ahead distance [m] of an actor's pure pursuit at ``speed`` [m/s] (any shape)."""
    return np.maximum(PURSUIT_MIN_LOOKAHEAD_M, PURSUIT_LOOKAHEAD_S * speed)


def pursuit_curvature(x: np.ndarray, y: np.ndarray, yaw: np.ndarray, tx: np.ndarray,
                      ty: np.ndarray) -> np.ndarray:
    """Curvature [1/m] pure pursuit steers from pose (x, y, yaw) towards target (tx, ty)
    (any matching shapes)."""
    alpha = wrap_angle(numerics.arctan2(ty - y, tx - x) - yaw)
    return 2.0 * np.sin(alpha) / np.maximum(np.hypot(tx - x, ty - y), 1.0)


@dataclass(frozen=True, eq=False)
class ActorState:
    """Actor states, each (N, A): the body (centre pose and motion), the steered point that
    follows the path (``guide``: a vehicle's front axle, else the body itself), its progress
    ``s`` on the path [m] and the nearest path sample ``index``."""

    body: VehicleState
    s: np.ndarray
    index: np.ndarray
    guide: VehicleState


def initial_actors(world: BatchWorld) -> ActorState:
    ahead, wb = axle_geometry(world.actor_kind, world.actor_model)
    ahead = np.broadcast_to(ahead, world.actor_start_s.shape)
    path, ph, ds = world.actor_path, world.actor_path_heading, world.actor_path_ds
    last = _statics(world).last
    s = world.actor_start_s + ahead  # the front axle, ahead of the centre's arc length
    x, y, h = path_point(path, ph, ds, s, last)
    rx, ry, _ = path_point(path, ph, ds, s - wb, last)
    bx, by, byaw = trail_body(x, y, rx, ry, h, ahead, wb)
    v = profile_speed(0.0, world.actor_profile_t, world.actor_profile_v)
    idx = np.round(s / np.maximum(ds, 1e-9)).astype(np.int64)
    return ActorState(VehicleState(bx, by, byaw, byaw.copy(), v), s, idx,
                      VehicleState(x, y, h, h.copy(), v))


@dataclass(frozen=True, eq=False)
class _Statics:
    """What :func:`step_actors` reads from a world that no step changes (computed once)."""

    ahead: np.ndarray       # (N, A) front axle ahead of the centre [m]
    wheelbase: np.ndarray   # (N, A) [m]
    back: np.ndarray        # (N, A) rear axle behind the centre [m]
    is_veh: np.ndarray      # (N, A) bool
    grip: np.ndarray        # (N, A) lateral grip factor
    ds: np.ndarray          # (N, A) path spacing, at least 1e-9 [m]
    not_self: np.ndarray    # (1, A, A + 1) bool: other road users (actors, then the ego)
    lat_reach: np.ndarray   # (N, A, A + 1) lateral distance within which another is ahead [m]
    lon_reach: np.ndarray   # (N, A, A + 1) centre distance of two touching bodies [m]
    rows: np.ndarray        # (N, 1) batch index
    cols: np.ndarray        # (1, A) actor index
    path_rows: np.ndarray   # (N, A) first sample of each path in the path tables
    path_x: np.ndarray      # (U * P,) the distinct paths' x, y [m] and heading [rad], flat
    path_y: np.ndarray
    path_h: np.ndarray
    last: np.ndarray        # (N, A) highest sample position a path is read at
    last_index: np.ndarray  # (N, A, 1) index of each path's last own sample
    knots_sorted: bool      # every speed profile's knot times are nondecreasing


_STATICS: weakref.WeakKeyDictionary[BatchWorld, _Statics] = weakref.WeakKeyDictionary()


def _path_tables(path: np.ndarray, heading: np.ndarray) -> dict[str, np.ndarray]:
    """The distinct paths (N, A, P, 2) and headings (N, A, P), bit for bit, as flat tables of
    x, y and heading, and each actor's first sample in them (``path_rows`` (N, A)).

    Variants mostly share their paths; N copies of a path make a batch's gathers range over
    N times the memory (24 MB at batch 256 on junction_straight, 94 kB distinct), so a
    step's lookups read the distinct paths instead: the same values."""
    n, a, p = heading.shape
    bits = np.concatenate([path.reshape(n * a, 2 * p), heading.reshape(n * a, p)], 1)
    bits = bits.view(np.int64)  # compared bit for bit (+0.0 and -0.0 differ)
    ids = np.empty(n * a, dtype=np.int64)
    first: dict[bytes, int] = {}
    same = (bits.reshape(n, a, 3 * p) == bits[:a][None]).all(axis=2).reshape(-1)
    for r in range(n * a):
        if same[r]:  # variant 0's path of the same actor
            ids[r] = r % a
        else:
            key = bits[r].tobytes()
            ids[r] = first.setdefault(key, len(first))  # numbered after variant 0's below
    own = ids.copy()
    own[~same] += a
    rows = np.concatenate([np.arange(a), np.flatnonzero(~same)[
        np.unique(ids[~same], return_index=True)[1]]]) if (~same).any() else np.arange(a)
    flat_path = path.reshape(n * a, p, 2)[rows]
    flat_head = heading.reshape(n * a, p)[rows]
    return {"path_rows": (own * p).reshape(n, a),
            "path_x": np.ascontiguousarray(flat_path[..., 0]).reshape(-1),
            "path_y": np.ascontiguousarray(flat_path[..., 1]).reshape(-1),
            "path_h": np.ascontiguousarray(flat_head).reshape(-1)}


def _path_at(st: _Statics, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`rocas.sim.dynamics.path_point` of the world's actor paths at arc lengths s
    (..., N, A), read from the distinct-path tables: the same arithmetic and values."""
    f = clip(s / np.maximum(st.ds, 1e-9), 0.0, st.last)
    i = f.astype(np.int64)
    u = f - i
    k = st.path_rows + i
    x0, y0 = st.path_x.take(k), st.path_y.take(k)
    return (x0 + u * (st.path_x.take(k + 1) - x0), y0 + u * (st.path_y.take(k + 1) - y0),
            st.path_h.take(k))


def _statics(world: BatchWorld) -> _Statics:
    got = _STATICS.get(world)
    if got is None:
        n, a = world.actor_kind.shape
        ahead, wb = axle_geometry(world.actor_kind, world.actor_model)
        ol = np.concatenate([world.actor_dims[..., 0], np.full((n, 1), world.ego_dims[0])], 1)
        ow = np.concatenate([world.actor_dims[..., 1], np.full((n, 1), world.ego_dims[1])], 1)
        got = _Statics(
            ahead=ahead, wheelbase=wb, back=wb - ahead, is_veh=world.actor_kind == KIND_VEHICLE,
            grip=LATERAL_GRIP_FACTOR[clip(world.actor_model, 0, 3)],
            ds=np.maximum(world.actor_path_ds, 1e-9),
            not_self=~np.eye(a, a + 1, dtype=bool)[None],
            lat_reach=(world.actor_dims[..., 1:2] + ow[:, None, :]) / 2 + 0.3,
            lon_reach=(world.actor_dims[..., 0:1] + ol[:, None, :]) / 2,
            rows=np.arange(n)[:, None], cols=np.arange(a)[None, :],
            **_path_tables(world.actor_path, world.actor_path_heading),
            last=world.actor_path_count - 1.000001,
            last_index=(world.actor_path_count - 1)[..., None],
            knots_sorted=bool((np.diff(world.actor_profile_t, axis=-1) >= 0.0).all()))
        _STATICS[world] = got
    return got


def step_actors(world: BatchWorld, state: ActorState, t: float, ego: VehicleState,
                friction: np.ndarray) -> ActorState:
    """Advance every actor by one step (decide, then integrate)."""
    dt = world.dt_s
    b = state.body
    fa = state.guide  # the front axle (points: the body)
    n, a = b.x.shape
    if a == 0:
        return state
    st = _statics(world)
    v_target = profile_speed(t, world.actor_profile_t, world.actor_profile_v, st.knots_sorted)
    accel = clip(SPEED_GAIN_PER_S * (v_target - b.speed), -ACTOR_DECEL_MPS2, ACTOR_ACCEL_MPS2)
    # reactive actors keep a distance to the ego and to other actors ahead
    ox = np.concatenate([b.x, ego.x[:, None]], 1)
    oy = np.concatenate([b.y, ego.y[:, None]], 1)
    ov = np.concatenate([b.speed, ego.speed[:, None]], 1)
    c, s = np.cos(b.yaw)[..., None], np.sin(b.yaw)[..., None]
    dx = ox[:, None, :] - b.x[..., None]
    dy = oy[:, None, :] - b.y[..., None]
    lon = dx * c + dy * s
    lat = -dx * s + dy * c
    ahead = st.not_self & (lon > 0) & (np.abs(lat) < st.lat_reach)
    gap = np.where(ahead, lon - st.lon_reach, np.inf)
    j = np.argmin(gap, axis=-1)
    g = gap.min(axis=-1)
    v_lead = ov[st.rows, j]
    sstar = world.actor_reactive_gap + np.maximum(
        0.0, b.speed * REACTIVE_HEADWAY_S + b.speed * (b.speed - v_lead)
        / (2 * np.sqrt(ACTOR_ACCEL_MPS2 * 3.0)))
    idm = ACTOR_ACCEL_MPS2 * (1 - (sstar / np.maximum(g, 0.1)) ** 2)
    accel = np.where(world.actor_reactive & np.isfinite(g),
                     np.maximum(np.minimum(accel, idm), -ACTOR_DECEL_MPS2), accel)
    # vehicles: pure pursuit through the bicycle model; points move along the path: both
    # read their paths in one call (elementwise, so each value is what its own call gives)
    ds = st.ds
    v_pt = np.maximum(fa.speed + accel * dt, 0.0)
    s_pt = state.s + 0.5 * (b.speed + v_pt) * dt
    (tx, px2), (ty, py2), (_, ph2) = _path_at(
        st, np.stack([state.s + pursuit_lookahead(fa.speed), s_pt]))
    kappa = pursuit_curvature(fa.x, fa.y, fa.yaw, tx, ty)
    veh, _ = bicycle_step(fa, accel, kappa, friction[:, None], st.grip, dt)
    # project vehicles back on their path (local window)
    cand = clip(state.index[..., None] + PROJECTION_WINDOW, 0, st.last_index)
    k = st.path_rows[..., None] + cand  # (N, A, W)
    best = np.argmin((st.path_x.take(k) - veh.x[..., None]) ** 2
                     + (st.path_y.take(k) - veh.y[..., None]) ** 2, axis=-1)
    v_idx = cand[st.rows, st.cols, best]
    is_veh = st.is_veh
    guide = VehicleState(
        x=np.where(is_veh, veh.x, px2), y=np.where(is_veh, veh.y, py2),
        yaw=np.where(is_veh, veh.yaw, ph2), course=np.where(is_veh, veh.course, ph2),
        speed=np.where(is_veh, veh.speed, v_pt))
    # the body trails the front axle (points: the body is the guide)
    # (a vehicle's body ``course`` holds its trailing axis, rear axle -> front axle; its
    # ``yaw`` adds the front axle's slip, so a sliding vehicle's body points inside its motion)
    rear_x = b.x - st.back * np.cos(b.course)
    rear_y = b.y - st.back * np.sin(b.course)
    bx, by, byaw = trail_body(guide.x, guide.y, rear_x, rear_y, guide.yaw, st.ahead, st.wheelbase)
    slip = np.where(is_veh, wrap_angle(guide.yaw - guide.course), 0.0)
    body = VehicleState(x=bx, y=by, yaw=np.where(slip != 0.0, wrap_angle(byaw + slip), byaw),
                        course=np.where(is_veh, byaw, guide.course), speed=guide.speed)
    s_new = np.where(is_veh, v_idx * ds, s_pt)
    idx = np.where(is_veh, v_idx, np.round(s_pt / ds).astype(np.int64))
    return ActorState(body, s_new, idx, guide)
