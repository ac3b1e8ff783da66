"""The values one planning cycle passes between its decisions (see
:class:`rocas.stacks.ads.planning.Planning`).

N is the batch (variants), M the obstacle slots, Kp the forecast points, Q the collision
check's times. Distances are along the ego's reference line (route s [m], lateral offset
positive left [m]).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rocas.sim.geometry import clip


@dataclass(frozen=True, eq=False)
class EgoOnReference:
    """The ego on its reference line: s (N,) [m], d (N,) lateral offset [m], v (N,) speed
    [m/s]."""

    s: np.ndarray
    d: np.ndarray
    v: np.ndarray


@dataclass(frozen=True, eq=False)
class RefObstacles:
    """The predicted obstacles placed on the reference line, each (N, M).

    Attributes:
        half_length, half_width [m]: the bodies' half sizes.
        vru: bool, pedestrian or bicycle.
        s [m], l [m]: route position and lateral offset of the centre.
        ref_heading [rad]: the reference's heading at the obstacle.
        heading [rad]: the obstacle's heading now (its forecast's first heading with
            ``use_path_tangent_heading``).
        lat_ext, lon_ext [m]: the body's half extent across and along the reference.
        vru_buffer [m]: the extra lateral buffer around vulnerable road users (0 otherwise).
        not_behind: bool, published and not too far behind the ego.
        consider: bool, not behind and near the reference now.
    """

    half_length: np.ndarray
    half_width: np.ndarray
    vru: np.ndarray
    s: np.ndarray
    l: np.ndarray  # noqa: E741
    ref_heading: np.ndarray
    heading: np.ndarray
    lat_ext: np.ndarray
    lon_ext: np.ndarray
    vru_buffer: np.ndarray
    not_behind: np.ndarray
    consider: np.ndarray


@dataclass(frozen=True, eq=False)
class NudgePath:
    """The path: a lateral offset ``target`` held between ``start`` and ``end`` with ramps of
    ``transition`` on either side, joined from the ego's current offset over ``convergence``.

    Attributes:
        target, start, end, transition, convergence, s0, d0: (N,) [m] (s0, d0: the ego's
            route position and lateral offset now).
        blocking: (N, M) bool, static obstacles across the reference; any_block: (N,) bool;
        first_s: (N,) [m] route position of the nearest blocking body's rear (inf if none);
        no_path: (N,) bool, no offset within reach clears them.
    """

    target: np.ndarray
    start: np.ndarray
    end: np.ndarray
    transition: np.ndarray
    convergence: np.ndarray
    s0: np.ndarray
    d0: np.ndarray
    blocking: np.ndarray
    any_block: np.ndarray
    first_s: np.ndarray
    no_path: np.ndarray

    def offset_at(self, s: np.ndarray) -> np.ndarray:
        """Lateral offset [m] of the path at route positions ``s`` (N, ...) [m]."""
        target, a0, a1, tr, s0 = self.target, self.start, self.end, self.transition, self.s0
        shape = (target.shape[0],) + (1,) * (s.ndim - 1)
        t_, a0_, a1_, tr_ = (v.reshape(shape) for v in (target, a0, a1, tr))
        ramp = clip((s - a0_) / tr_, 0.0, 1.0) * clip((a1_ - s) / tr_, 0.0, 1.0)
        base = t_ * ramp
        r0 = (target * clip((s0 - a0) / tr, 0, 1) * clip((a1 - s0) / tr, 0, 1))
        fade = clip(1.0 - (s - s0.reshape(shape)) / self.convergence.reshape(shape), 0.0, 1.0)
        return base + (self.d0 - r0).reshape(shape) * fade


@dataclass(frozen=True, eq=False)
class ForecastGrid:
    """What the forecast's time grid fixes for the checks.

    Attributes:
        kk: how many leading forecast points some variant checks for overlap.
        tp: (N, Q) the collision check's times [s] (now, then the forecast's); tcheck: (N, Q)
            bool, which of them each variant checks; kc: Q.
        flat: (N, Q) index of the trajectory sample at or before each time in a flattened
            (N, K) trajectory array; frac: (N, Q) the fraction of the next step.
    """

    kk: int
    tp: np.ndarray
    tcheck: np.ndarray
    kc: int
    flat: np.ndarray
    frac: np.ndarray


@dataclass(frozen=True, eq=False)
class StOverlap:
    """Where each moving obstacle's forecast meets the path, each (N, M).

    Attributes:
        any_over: bool, some forecast point within the lateral buffer of the path;
        body_over: bool, some such point whose body overlaps the ego's swept width;
        k_in: index of the first overlapping forecast point;
        s_lo, s_hi [m]: route extent of the overlapping bodies (inf / -inf if none).
    """

    any_over: np.ndarray
    body_over: np.ndarray
    k_in: np.ndarray
    s_lo: np.ndarray
    s_hi: np.ndarray


@dataclass(frozen=True, eq=False)
class Interactions:
    """Each obstacle's relation to the ego, each (N, M).

    Attributes:
        follow, beside, vru_stop, yield_, overtake: bool, followed, held beside (not
            followed, not drawn level with), stopped for, yielded to, overtaken.
        moving: bool, not behind and not static (its forecast is checked).
        s_lo, s_hi [m]: the overlap region with the longitudinal buffer.
        dir_rel [rad]: |angle| between the obstacle's velocity and the reference.
    """

    follow: np.ndarray
    beside: np.ndarray
    vru_stop: np.ndarray
    yield_: np.ndarray
    overtake: np.ndarray
    moving: np.ndarray
    s_lo: np.ndarray
    s_hi: np.ndarray
    dir_rel: np.ndarray


@dataclass(frozen=True, eq=False)
class StopPoints:
    """The speed constraints.

    Attributes:
        gap_follow, gap_beside: (N, M) bumper-to-rear gap [m] to followed / held-beside
            obstacles (inf for the others); v_lead: (N, M) their speed along the route [m/s].
        stop_yield, stop_vru: (N, M) stop points [m along the route] (inf where none);
        stop_block, stop_light: (N,) the same for a blocked path and the traffic light.
    """

    gap_follow: np.ndarray
    gap_beside: np.ndarray
    v_lead: np.ndarray
    stop_yield: np.ndarray
    stop_vru: np.ndarray
    stop_block: np.ndarray
    stop_light: np.ndarray


@dataclass(frozen=True, eq=False)
class SpeedCommand:
    """The commanded acceleration and what set it, each (N,).

    Attributes:
        accel [m/s^2]; reason: index into planning.REASONS; bind_gap [m]: the gap of the
        binding constraint (inf if none); bound: bool, some constraint binds.
    """

    accel: np.ndarray
    reason: np.ndarray
    bind_gap: np.ndarray
    bound: np.ndarray


@dataclass(frozen=True, eq=False)
class EmergencyStop:
    """estop: (N,) bool; code: (N,) planning.E_* reason; perception_brake: (N,) bool, the
    perception brake is among the causes."""

    estop: np.ndarray
    code: np.ndarray
    perception_brake: np.ndarray
