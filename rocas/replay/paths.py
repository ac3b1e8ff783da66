"""From a reconstructed track to an actor the simulator can drive: a waypoint path, extended
along the map before the first and after the last observation, and a speed profile designed so
that the simulator's actor model (speed tracking with a 1.5 /s gain and acceleration limits)
arrives where the track says, when it says.
"""

from __future__ import annotations

import numpy as np

from rocas.replay.lanes import arc_length as _arc
from rocas.replay.lanes import walk_lanes
from rocas.replay.tracks import Track
from rocas.scenarios.model import Actor, Lane
from rocas.sim.actors import (
    ACTOR_ACCEL_MPS2,
    ACTOR_DECEL_MPS2,
    FRONT_AXLE_AHEAD_M,
    SPEED_GAIN_PER_S,
    WHEELBASE_M,
)
from rocas.sim.world import MODEL_CODES

WAYPOINT_SPACING_M = 0.5     # [m] smallest spacing of waypoints taken from a track
PROFILE_TOLERANCE_MPS = 0.05  # [m/s] speed-profile knots are dropped within this error
STATION_GAIN = 1.0           # [1/s^2] position feedback of the profile design
SPEED_GAIN = 2.0             # [1/s] speed feedback of the profile design
MAX_SPEED_MPS = 40.0
ENTRY_MOVING_MPS = 0.5       # [m/s] slower at its first sighting: it stood there before
ENDPOINT_WINDOW_S = 1.0      # [s] window of the entry and exit velocity estimates


def _thin(points: np.ndarray, spacing: float) -> np.ndarray:
    """Drop points closer than ``spacing`` to the previous kept one (keeps the last)."""
    keep = [0]
    for i in range(1, len(points)):
        if np.hypot(*(points[i] - points[keep[-1]])) >= spacing:
            keep.append(i)
    if keep[-1] != len(points) - 1 and np.hypot(*(points[-1] - points[keep[-1]])) > 0.05:
        keep.append(len(points) - 1)
    return points[keep]


def _progress(path: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Monotone arc length (n,) of each point of a trajectory projected on ``path``."""
    arc = _arc(path)
    a, b = path[:-1], path[1:]
    d = b - a
    ll = np.maximum((d * d).sum(1), 1e-12)
    rel = xy[:, None, :] - a[None]                                     # (n, P-1, 2)
    u = np.clip((rel * d[None]).sum(-1) / ll[None], 0.0, 1.0)
    q = a[None] + u[..., None] * d[None]
    dist = np.hypot(*(xy[:, None, :] - q).transpose(2, 0, 1))
    s = np.empty(len(xy))
    last = 0.0
    for i in range(len(xy)):
        # nearest among segments not behind the previous progress (monotone, local)
        cand = arc[:-1] + u[i] * np.sqrt(ll)
        ok = cand >= last - 0.5
        j = int(np.argmin(np.where(ok, dist[i], np.inf)))
        last = max(last, float(cand[j]))
        s[i] = last
    return s


def design_profile(times: np.ndarray, s_target: np.ndarray, dt_s: float, duration_s: float
                   ) -> tuple[tuple[float, float], ...]:
    """Speed-profile knots that make the simulator's actor follow ``s_target(t)``.

    The simulator tracks the profile speed with ``a = clip(1.5 (v_profile - v), -6, 2.5)``;
    this runs that law forward and picks, at every simulation tick, the profile speed that
    feeds forward the target acceleration and corrects speed and position errors. Knots the
    linear interpolation reproduces within :data:`PROFILE_TOLERANCE_MPS` are dropped.

    Args:
        times: (n,) increasing target times [s], covering [0, duration_s].
        s_target: (n,) target arc length along the actor's path [m].
        dt_s: simulation step [s].
        duration_s: simulated time [s].
    """
    k = int(round(duration_s / dt_s)) + 1
    tk = np.arange(k) * dt_s
    s_d = np.interp(tk, times, s_target)
    v_d = np.gradient(s_d, dt_s) if k > 1 else np.zeros(1)
    v_d = np.clip(v_d, 0.0, MAX_SPEED_MPS)
    a_d = np.gradient(v_d, dt_s) if k > 1 else np.zeros(1)
    cmd = np.empty(k)
    v, s = float(v_d[0]), float(s_d[0])
    cmd[0] = v
    for i in range(k - 1):
        if i > 0:
            a_ref = a_d[i] + SPEED_GAIN * (v_d[i] - v) + STATION_GAIN * (s_d[i] - s)
            cmd[i] = min(max(v + a_ref / SPEED_GAIN_PER_S, 0.0), MAX_SPEED_MPS)
        a = min(max(SPEED_GAIN_PER_S * (cmd[i] - v), -ACTOR_DECEL_MPS2), ACTOR_ACCEL_MPS2)
        v_new = max(v + a * dt_s, 0.0)
        s += 0.5 * (v + v_new) * dt_s
        v = v_new
    cmd[-1] = cmd[-2] if k > 1 else cmd[0]
    keep = [0]
    i = 0
    while i < k - 1:
        j = i + 1
        while j + 1 < k:
            u = (tk[i:j + 2] - tk[i]) / (tk[j + 1] - tk[i])
            line = cmd[i] + u * (cmd[j + 1] - cmd[i])
            if np.max(np.abs(line - cmd[i:j + 2])) > PROFILE_TOLERANCE_MPS:
                break
            j += 1
        keep.append(j)
        i = j
    return tuple((round(float(tk[i]), 6), round(float(cmd[i]), 4)) for i in keep)


def actor_from_track(track: Track, lanes: tuple[Lane, ...], dt_s: float, duration_s: float
                     ) -> Actor:
    """The scenario actor that re-enacts ``track`` (non-reactive: it follows the recording).

    Before its first observation the actor is assumed to have driven at its first observed
    speed along the map (backwards through lane predecessors); after its last one it keeps its
    last speed along the map (first successors).

    The simulator steers a vehicle's front axle along its path and lets the body trail, so a
    vehicle's path is its front axle's: the perceived centre moved ahead along the perceived
    body heading (the body's off-tracking in turns is then reproduced, not applied twice).
    """
    t0, t1 = float(track.times[0]), float(track.times[-1])
    # entry speed: the smaller of the derivative at the first sighting and the mean over the
    # first second (a standing pedestrian's noise must not set it walking before it was seen)
    vw, hw = track.velocity_between(t0, t0 + ENDPOINT_WINDOW_S)
    v0 = min(float(track.speed[0]), vw)
    h0 = float(track.heading[0]) if track.speed[0] > 1.0 else hw
    v1, h1 = float(track.speed[-1]), float(track.heading[-1])
    v0 = v0 if v0 >= ENTRY_MOVING_MPS else 0.0  # else it stood there before it was seen
    vehicle = track.kind == "vehicle"
    model = MODEL_CODES.get(track.model, 0)
    ahead = float(FRONT_AXLE_AHEAD_M[model]) if vehicle else 0.0
    wheelbase = float(WHEELBASE_M[model]) if vehicle else 0.0
    body_h = track.heading if track.body_heading is None else track.body_heading
    times = track.times
    xy = track.xy + ahead * np.stack([np.cos(body_h), np.sin(body_h)], axis=1)
    core = _thin(xy, WAYPOINT_SPACING_M)
    moving = len(core) >= 2 and not track.stationary
    # the start arc length is the centre's: the front axle starts ``ahead`` farther on
    back_len = v0 * t0 + ahead if moving else 0.0
    fwd_len = v1 * max(duration_s - t1, 0.0) + 5.0
    back = walk_lanes(lanes, core[0], h0, back_len, forward=False)
    if not moving:
        h = float(body_h[0])
        d = np.array([np.cos(h), np.sin(h)])
        # room behind the front axle for the rear axle, so the body starts on the heading
        core = np.vstack([xy[0] - (0.25 + wheelbase) * d, xy[0] + 0.25 * d])
    fwd = walk_lanes(lanes, core[-1], h1, fwd_len, forward=True) \
        if moving else np.zeros((0, 2))
    path = _thin(np.vstack([back, core, fwd]), 0.05)
    start_core = float(_arc(np.vstack([back, core[:1]]))[-1]) if len(back) else 0.0
    s_core = start_core + _progress(core, xy) if moving else np.full(len(times),
                                                                     0.25 + wheelbase)
    tt = [np.array([0.0])] if t0 > 0 else []
    ss = [np.array([s_core[0] - v0 * t0])] if t0 > 0 else []
    tt.append(times)
    ss.append(s_core)
    if t1 < duration_s:
        tt.append(np.array([duration_s + 1.0]))
        ss.append(np.array([s_core[-1] + v1 * (duration_s + 1.0 - t1)]))
    t_all, s_all = np.concatenate(tt), np.concatenate(ss)
    start = max(float(s_all[0]), ahead)
    profile = design_profile(t_all, s_all - start, dt_s, duration_s) if moving else ((0.0, 0.0),)
    return Actor(
        id=track.name, kind=track.kind, model=track.model, color=track.color, route=(),
        waypoints=tuple((round(float(x), 4), round(float(y), 4)) for x, y in path),
        start_s_m=round(start - ahead, 4), speed_profile=profile, reactive=False,
    )


__all__ = ["actor_from_track", "design_profile"]
