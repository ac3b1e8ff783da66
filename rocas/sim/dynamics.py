"""Vehicle and road-user dynamics: a friction-limited kinematic bicycle and a point model.

Decide first, then integrate (HighwayEnv habit): behaviour code computes commands, these
functions only integrate them. All functions are vectorised over any leading shape.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from rocas import numerics
from rocas.sim.geometry import clip, wrap_angle

GRAVITY_MPS2 = 9.81
#: Share of the friction circle heavy vehicles can use laterally before they slide
#: (load transfer and a high centre of gravity); index = model code (sedan, suv, truck, bus).
LATERAL_GRIP_FACTOR = np.array([1.0, 0.95, 0.55, 0.6])
SLIP_RELAX_S = 0.6      # [s] time constant with which slip decays when grip returns
MAX_SLIP_RAD = 0.6      # [rad] body-to-course angle at which a sliding vehicle saturates


@dataclass(frozen=True)
class VehicleState:
    """Planar vehicle states (any leading shape ``(...,)``).

    Attributes:
        x, y: rear-axle-independent body centre [m].
        yaw: body heading [rad].
        course: direction of travel [rad] (differs from ``yaw`` while sliding).
        speed: [m/s], never negative.
    """

    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    course: np.ndarray
    speed: np.ndarray


@functools.cache
def _slip_decay(dt: float) -> float:
    """Factor by which slip decays over one step of ``dt`` [s] while the tyres grip."""
    return numerics.exp(-dt / SLIP_RELAX_S)


def bicycle_step(
    state: VehicleState, accel: np.ndarray, curvature: np.ndarray, friction: np.ndarray,
    grip_factor: np.ndarray, dt: float,
) -> tuple[VehicleState, np.ndarray]:
    """One step of the kinematic bicycle with a friction-limited lateral acceleration.

    Args:
        state: current state.
        accel: longitudinal acceleration demanded [m/s^2].
        curvature: path curvature demanded by the steering, tan(delta) / wheelbase [1/m].
        friction: road friction coefficient (..., ).
        grip_factor: share of friction usable laterally (1 cars, ~0.55 trucks).
        dt: step [s].

    Returns:
        (next state, realised longitudinal acceleration [m/s^2]).

    When ``v^2 * curvature`` exceeds ``friction * grip * g`` the course only turns as fast as
    the tyres allow while the body keeps rotating: the vehicle drifts wide and its heading
    departs from its path tangent.
    """
    mu_g = friction * GRAVITY_MPS2
    a = clip(accel, -mu_g, mu_g)
    v_next = np.maximum(state.speed + a * dt, 0.0)
    realised = (v_next - state.speed) / dt
    v_mid = 0.5 * (state.speed + v_next)
    kappa_max = mu_g * grip_factor / np.maximum(v_mid * v_mid, 1e-6)
    kappa_eff = clip(curvature, -kappa_max, kappa_max)
    sliding = np.abs(curvature) > kappa_max
    course = state.course + v_mid * kappa_eff * dt
    slip = wrap_angle(state.yaw - state.course) + v_mid * (curvature - kappa_eff) * dt
    slip = np.where(sliding, clip(slip, -MAX_SLIP_RAD, MAX_SLIP_RAD),
                    slip * _slip_decay(dt))
    mid_course = 0.5 * (state.course + course)
    x = state.x + v_mid * np.cos(mid_course) * dt
    y = state.y + v_mid * np.sin(mid_course) * dt
    course = wrap_angle(course)
    return VehicleState(x, y, wrap_angle(course + slip), course, v_next), realised


def profile_speed(t: float, knots_t: np.ndarray, knots_v: np.ndarray,
                  nondecreasing: bool = False) -> np.ndarray:
    """Speed-profile value at time ``t``; knots (..., K), linear between knots, held outside.

    ``nondecreasing``: the caller knows every row of ``knots_t`` to be nondecreasing (a
    cheaper count of the knots passed, with the same result)."""
    k = knots_t.shape[-1]
    if k == 1:
        return knots_v[..., 0]
    kt = knots_t.reshape(-1, k)
    kv = knots_v.reshape(-1, k)
    below = kt <= t
    if nondecreasing:
        # kt <= t holds on a prefix of each row: its length is the first False (argmin of a
        # bool row, far cheaper than a sum), or k when all hold
        idx = clip(np.where(below[:, -1], k, np.argmin(below, axis=1)) - 1, 0, k - 2)
    else:
        idx = clip(below.sum(-1) - 1, 0, k - 2)
    r = np.arange(kt.shape[0])
    t0, t1, v0, v1 = kt[r, idx], kt[r, idx + 1], kv[r, idx], kv[r, idx + 1]
    u = clip((t - t0) / np.maximum(t1 - t0, 1e-9), 0.0, 1.0)
    return (v0 + u * (v1 - v0)).reshape(knots_t.shape[:-1])


def path_point(path: np.ndarray, heading: np.ndarray, ds: np.ndarray, s: np.ndarray,
               last: np.ndarray | float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Interpolate equally spaced paths (N, A, P, 2) at arc length s (N, A) -> x, y, heading.

    ``last``: the highest sample position to read each path at ((N, A), or one number; None:
    P - 1.000001, every sample)."""
    p = path.shape[-2]
    f = clip(s / np.maximum(ds, 1e-9), 0.0, p - 1.000001 if last is None else last)
    i = f.astype(np.int64)
    u = f - i
    # one gather on the flattened paths: indexing with three broadcast index arrays costs
    # several times as much on a large batch
    k = path_rows(path) + i
    flat = path.reshape(-1, 2)
    p0 = np.take(flat, k, axis=0)
    p1 = np.take(flat, k + 1, axis=0)
    return (p0[..., 0] + u * (p1[..., 0] - p0[..., 0]), p0[..., 1] + u * (p1[..., 1] - p0[..., 1]),
            heading.reshape(-1)[k])


def path_rows(path: np.ndarray) -> np.ndarray:
    """(N, A) index of each path's first sample in ``path.reshape(-1, 2)`` (path (N, A, P, 2))."""
    n, a, p = path.shape[:3]
    return np.arange(0, n * a * p, p).reshape(n, a)
