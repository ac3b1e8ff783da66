"""From a reconstructed track to an actor the simulator can drive: a waypoint path, extended
along the map before the first and after the last observation, and a speed profile designed so
that the simulator's actor model (speed tracking with a 1.5 /s gain and acceleration limits)
arrives where the track says, when it says.
"""

from __future__ import annotations

import numpy as np

from rocas import numerics
from rocas.replay.lanes import arc_length as _arc
from rocas.replay.lanes import walk_lanes
from rocas.replay.tracks import Track
from rocas.scenarios.model import Actor, Lane
from rocas.sim.actors import (
    ACTOR_ACCEL_MPS2,
    ACTOR_DECEL_MPS2,
    FRONT_AXLE_AHEAD_M,
    PROJECTION_WINDOW,
    SPEED_GAIN_PER_S,
    WHEELBASE_M,
    pursuit_curvature,
    pursuit_lookahead,
)
from rocas.sim.geometry import resample_polyline
from rocas.sim.world import MODEL_CODES

WAYPOINT_SPACING_M = 0.5     # [m] smallest spacing of waypoints taken from a track
PROFILE_TOLERANCE_MPS = 0.05  # [m/s] speed-profile knots are dropped within this error
PROFILE_DRIFT_M = 0.02       # [m] ... and while the position drift it adds stays within this
STATION_GAIN = 1.0           # [1/s^2] position feedback of the profile design
SPEED_GAIN = 2.0             # [1/s] speed feedback of the profile design
MAX_SPEED_MPS = 40.0
ENTRY_MOVING_MPS = 0.5       # [m/s] slower at its first sighting: it stood there before
ENDPOINT_WINDOW_S = 1.0      # [s] window of the entry and exit velocity estimates
PURSUIT_ITERATIONS = 3       # corrections of a vehicle's steered path for pure-pursuit cutting
PURSUIT_SMOOTH_SAMPLES = 6       # half width of the moving average of the error [samples]
PREVIEW_S = 3.0              # [s] how far ahead the profile design looks for a target it ...
PREVIEW_MIN_S = 1.0          # [s] ... could only reach by starting now (nearer: feedback's job)


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
    linear interpolation reproduces within :data:`PROFILE_TOLERANCE_MPS` are dropped, as long
    as the integral of that error (the position it would cost) stays within
    :data:`PROFILE_DRIFT_M`.

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
    tau = np.arange(1, int(round(PREVIEW_S / dt_s)) + 1) * dt_s
    far = tau >= PREVIEW_MIN_S - 1e-9
    for i in range(k - 1):
        if i > 0:
            a_ref = a_d[i] + SPEED_GAIN * (v_d[i] - v) + STATION_GAIN * (s_d[i] - s)
            a_ref = _preview(a_ref, s_d[i + 1:i + 1 + len(tau)], s, v, tau, far)
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
            err = line - cmd[i:j + 2]
            # a small speed error held for seconds still moves the actor: bound its integral
            if np.max(np.abs(err)) > PROFILE_TOLERANCE_MPS \
                    or np.max(np.abs(np.cumsum(err))) * dt_s > PROFILE_DRIFT_M:
                break
            j += 1
        keep.append(j)
        i = j
    return tuple((round(float(tk[i]), 6), round(float(cmd[i]), 4)) for i in keep)


def _preview(a_ref: float, s_ahead: np.ndarray, s: float, v: float, tau: np.ndarray,
             far: np.ndarray) -> float:
    """The acceleration [m/s^2] to command now: ``a_ref`` (feedback on the present target),
    unless a target ahead is only reachable at the actor's acceleration (or deceleration)
    limit from now on; then the constant acceleration that reaches the hardest one.

    A target at the limit (a truck speeding up at the simulator's 2.5 m/s^2, as recorded with
    a tracker's lag) cannot be caught up once the actor has fallen behind: feedback alone
    starts too late and the actor stays behind by metres for good.

    Args:
        a_ref: the feedback's acceleration [m/s^2].
        s_ahead: (m,) target arc lengths at the next m ticks [m] (fewer near the end).
        s, v: the actor's arc length [m] and speed [m/s] now.
        tau: (M,) time to each tick ahead [s]; far: (M,) the ticks far enough to look at.
    """
    m = len(s_ahead)
    sel = far[:m]
    if not sel.any():
        return a_ref
    t = tau[:m][sel]
    need = 2.0 * (s_ahead[sel] - s - v * t) / (t * t)
    up, down = float(need.max()), float(need.min())
    if up >= ACTOR_ACCEL_MPS2:
        return max(a_ref, up)
    if down <= -ACTOR_DECEL_MPS2:
        return min(a_ref, down)
    return a_ref


def _timeline(times: np.ndarray, s_core: np.ndarray, v0: float, v1: float, duration_s: float,
              ahead: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(times, arc lengths) the actor must keep over the whole run (at its entry speed before
    the first observation, its exit speed after the last) and its start arc length."""
    t0, t1 = float(times[0]), float(times[-1])
    tt = [np.array([0.0])] if t0 > 0 else []
    ss = [np.array([s_core[0] - v0 * t0])] if t0 > 0 else []
    tt.append(times)
    ss.append(s_core)
    if t1 < duration_s:
        tt.append(np.array([duration_s + 1.0]))
        ss.append(np.array([s_core[-1] + v1 * (duration_s + 1.0 - t1)]))
    t_all, s_all = np.concatenate(tt), np.concatenate(ss)
    return t_all, s_all, max(float(s_all[0]), ahead)


def _pursue(path: np.ndarray, ds: float, s_t: np.ndarray, dt_s: float) -> np.ndarray:
    """Front-axle positions (T, 2) of the simulator's actor steering along the equally spaced
    ``path`` with its arc length following ``s_t`` (one per tick): the pure pursuit of
    :func:`rocas.sim.actors.step_actors` (its look-ahead, steering law and projection window)
    with a kinematic (no-slip) body."""
    p = len(path)
    arc = np.arange(p) * ds

    def at(s: float) -> np.ndarray:
        return np.array([np.interp(s, arc, path[:, 0]), np.interp(s, arc, path[:, 1])])

    s0 = float(s_t[0])
    pos = at(s0)
    d = at(s0 + 0.5) - at(max(s0 - 0.5, 0.0))
    course = float(numerics.arctan2(d[1], d[0]))
    idx = int(round(s0 / ds))
    out = np.empty((len(s_t), 2))
    out[0] = pos
    for k in range(1, len(s_t)):
        v = max((s_t[k] - s_t[k - 1]) / dt_s, 0.0)
        tgt = at(idx * ds + float(pursuit_lookahead(v)))
        kappa = float(pursuit_curvature(pos[0], pos[1], course, tgt[0], tgt[1]))
        new_course = course + v * kappa * dt_s
        mid = 0.5 * (course + new_course)
        pos = pos + v * dt_s * np.array([np.cos(mid), np.sin(mid)])
        course = new_course
        cand = np.clip(idx + PROJECTION_WINDOW, 0, p - 1)
        idx = int(cand[np.argmin(((path[cand] - pos) ** 2).sum(1))])
        out[k] = pos
    return out


def _pursuit_compensated(path: np.ndarray, t_all: np.ndarray, s_all: np.ndarray,
                         dt_s: float) -> np.ndarray:
    """A path whose pure pursuit (as the simulator steers) runs along ``path``: the target
    path is pursued, the lateral error of the pursuing front axle at each arc length is
    subtracted from the steered path, a few times over."""
    total = float(_arc(path)[-1])
    if total < 1.0:
        return path
    n = int(np.ceil(total / 0.5)) + 1
    target, ds = resample_polyline(path, n)
    d = np.gradient(target, axis=0)
    normal = np.stack([-d[:, 1], d[:, 0]], 1) / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]
    arc = np.arange(n) * ds
    tk = np.arange(int(round(float(t_all[-1]) / dt_s)) + 1) * dt_s
    s_t = np.clip(np.interp(tk, t_all, s_all), 0.0, total)
    steer = target.copy()
    offset = np.zeros(n)
    for _ in range(PURSUIT_ITERATIONS):
        run = _pursue(steer, ds, s_t, dt_s)
        # the pursuer's signed lateral error to the target path, by arc length
        s_run = _progress(target, run)
        i = np.clip(np.round(s_run / ds).astype(np.int64), 0, n - 1)
        err = ((run - target[i]) * normal[i]).sum(1)
        order = np.argsort(s_run, kind="stable")
        e = np.interp(arc, s_run[order], err[order], left=0.0, right=0.0)
        # only the smooth part: the pursuer rides over the track's noise, which must not be
        # fed back (it would make the steered path zigzag, longer than the one driven)
        k = np.ones(2 * PURSUIT_SMOOTH_SAMPLES + 1)
        offset -= np.convolve(e, k, "same") / np.convolve(np.ones(n), k, "same")
        steer = target + offset[:, None] * normal
    return steer


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
    # first second (a standing pedestrian's noise must not set it walking before it was seen),
    # that mean taken back to the first sighting along the speed's trend over the second (an
    # actor first seen while braking was faster then than on average over the second)
    vw, hw = track.velocity_between(t0, t0 + ENDPOINT_WINDOW_S)
    first = track.times <= t0 + ENDPOINT_WINDOW_S + 1e-9
    if first.sum() >= 3:
        trend = float(np.polyfit(track.times[first] - t0, track.speed[first], 1)[0])
        vw = max(vw - 0.5 * ENDPOINT_WINDOW_S * trend, 0.0)
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
    t_all, s_all, start = _timeline(times, s_core, v0, v1, duration_s, ahead)
    profile = design_profile(t_all, s_all - start, dt_s, duration_s) if moving else ((0.0, 0.0),)
    if vehicle and moving:
        # the simulator's pure pursuit cuts inside a curved path: steer along a path that
        # is pushed out by as much, so the front axle runs where it was seen. The speed
        # profile stays the one along the seen path: the front axle drives that one (along
        # the pushed-out path a left turner's speed came out 0.1 m/s too fast); only the
        # start is the steered path's
        path = _pursuit_compensated(path, t_all, s_all, dt_s)
        start = _timeline(times, _progress(path, xy), v0, v1, duration_s, ahead)[2]
    return Actor(
        id=track.name, kind=track.kind, model=track.model, color=track.color, route=(),
        waypoints=tuple((round(float(x), 4), round(float(y), 4)) for x, y in path),
        start_s_m=round(start - ahead, 4), speed_profile=profile, reactive=False,
    )


__all__ = ["actor_from_track", "design_profile"]
