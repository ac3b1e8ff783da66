"""Obstacle tracks from perception: stitching id switches and dropped tracks, bridging gaps,
smoothing, and mapping perceived type/sub-type/colour back to scenario actor kinds.

A perception tracker switches ids when its association gate is violated and drops a track
after a few missed frames (occlusion, range); both split one physical actor into several
track ids. :func:`build_tracks` links such pieces when the later one starts where the earlier
one, extrapolated at its last velocity, would be, then resamples the chain on a uniform grid
(Hermite bridges over gaps) and smooths it with a local linear Gaussian regression.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from dataclasses import dataclass

import numpy as np

from rocas import numerics
from rocas.replay.frames import wrap
from rocas.replay.lanes import arc_length, forward_branches, project
from rocas.replay.source import (
    TYPE_BICYCLE,
    TYPE_PEDESTRIAN,
    TYPE_UNKNOWN_UNMOVABLE,
    TYPE_VEHICLE,
    Detections,
)
from rocas.scenarios.model import COLORS, Lane
from rocas.stacks.base import AlphaBetaTracker

MAX_GAP_S = 2.5             # [s] longest gap between two pieces of one actor that is bridged
STITCH_GATE_M = 2.0         # [m] distance gate at zero gap ...
STITCH_GATE_PER_S = 1.5     # [m/s] ... growing with the gap
MAX_REIDENTIFY_S = 30.0     # [s] longest gap across which a piece is re-identified on the map
REIDENTIFY_GATE_M = 3.0     # [m] largest distance of the later piece from the way forward
LONG_GAP_PENALTY = 100.0    # long-gap links rank after every short-gap link
SMOOTH_SIGMA_S = 0.25       # [s] Gaussian kernel of the smoother ...
SMOOTH_DISTANCE_M = 0.5     # [m] ... widened for slow obstacles to span this much travel ...
SLOW_SIGMA_MAX_S = 1.0      # [s] ... up to this
MIN_DETECTIONS = 2          # chains with fewer detections are dropped as spurious
STATIC_SPREAD_M = 0.8       # [m] a track whose detections stay this close to their median is parked
MOVING_SPEED_MPS = 1.0      # [m/s] above this the heading follows the velocity
DEFAULT_COLOR = "white"     # used when the colour was never recognised
BRIDGE_VELOCITY_S = 0.3     # [s] span of a piece's end velocity for a bridge between pieces
COAST_TOLERANCE = 1e-6      # [m, m/s] a frame this close to its predecessor's prediction is coasted

#: PerceptionObstacle.SubType -> (kind, model).
SUB_TYPES: dict[int, tuple[str, str]] = {
    1: ("vehicle", "sedan"), 2: ("vehicle", "suv"), 3: ("vehicle", "truck"),
    4: ("vehicle", "bus"), 5: ("cyclist", "sedan"), 6: ("pedestrian", "sedan"),
}
_TYPE_KIND = {TYPE_VEHICLE: "vehicle", TYPE_BICYCLE: "cyclist", TYPE_PEDESTRIAN: "pedestrian"}
_STATIC_SUB_TYPES = (7, 8)  # traffic cone, box: map entities, replayed from the world


@dataclass(frozen=True, eq=False)
class Track:
    """One physical obstacle reconstructed from perception, on a uniform time grid.

    Attributes:
        track_ids: perception track ids stitched into this track, in time order.
        times: (n,) grid times [s], one perception period apart.
        xy: (n, 2) smoothed world position [m].
        heading: (n,) world heading [rad] (velocity direction when moving).
        speed: (n,) speed along the trajectory [m/s].
        observed: (n,) True where a detection fell on the grid sample (False: bridged).
        kind, model, color: scenario actor kind, vehicle model, colour name.
        size: (3,) median perceived length, width, height [m].
        notes: what was assumed (unknown colour, class from size, ...).
        stationary: never moved (pose = median of the detections).
        body_heading: (n,) perceived body heading [rad] (the detected box's orientation; a
            turning long vehicle's body points inside its velocity), or None (= ``heading``).
    """

    track_ids: tuple[int, ...]
    times: np.ndarray
    xy: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    observed: np.ndarray
    kind: str
    model: str
    color: str
    size: np.ndarray
    notes: tuple[str, ...] = ()
    stationary: bool = False
    body_heading: np.ndarray | None = None

    def velocity_between(self, t_a: float, t_b: float) -> tuple[float, float]:
        """(speed [m/s], heading [rad]) of the displacement between two times of the track:
        steadier than the derivative at a track's end."""
        if len(self.times) < 2 or self.stationary:
            return 0.0, float(self.heading_at(t_a))
        t_a = max(t_a, float(self.times[0]))
        t_b = min(max(t_b, t_a + 1e-6), float(self.times[-1]))
        pa, pb = self.position_at(t_a), self.position_at(t_b)
        assert pa is not None and pb is not None
        d = pb - pa
        speed = float(np.hypot(*d)) / max(t_b - t_a, 1e-9)
        heading = float(numerics.arctan2(d[1], d[0])) if speed > 0.2 else self.heading_at(t_a)
        return speed, heading

    @property
    def name(self) -> str:
        """Stable actor id: ``obstacle_<first perception track id>``."""
        return f"obstacle_{self.track_ids[0]}"

    def position_at(self, t: float, max_extrapolation_s: float = 1.0) -> np.ndarray | None:
        """(2,) position at ``t`` [m]; extrapolated at the end speed up to the limit, else None."""
        t0, t1 = float(self.times[0]), float(self.times[-1])
        if t0 <= t <= t1:
            return np.array([np.interp(t, self.times, self.xy[:, 0]),
                             np.interp(t, self.times, self.xy[:, 1])])
        if t0 - max_extrapolation_s <= t < t0:
            i, dt = 0, t - t0
        elif t1 < t <= t1 + max_extrapolation_s:
            i, dt = -1, t - t1
        else:
            return None
        d = np.array([np.cos(self.heading[i]), np.sin(self.heading[i])])
        return self.xy[i] + d * self.speed[i] * dt

    def heading_at(self, t: float) -> float:
        i = int(np.clip(np.searchsorted(self.times, t), 0, len(self.times) - 1))
        return float(self.heading[i])


@dataclass(frozen=True, eq=False)
class _Piece:
    track_id: int
    rows: np.ndarray  # indices into Detections, time ordered

    def start(self, d: Detections) -> float:
        return float(d.times[self.rows[0]])

    def end(self, d: Detections) -> float:
        return float(d.times[self.rows[-1]])


def _coarse(d: Detections, rows: np.ndarray) -> str | None:
    kinds = [_TYPE_KIND[t] for t in d.type[rows].tolist() if t in _TYPE_KIND]
    return Counter(kinds).most_common(1)[0][0] if kinds else None


def _identity(d: Detections, rows: np.ndarray) -> tuple[int | None, str | None]:
    """(most frequent known sub-type, most frequent known colour) of a piece."""
    subs = [x for x in d.sub_type[rows].tolist() if x in SUB_TYPES]
    colors = [c for c in (d.color[i] for i in rows.tolist()) if c in COLORS]
    return (Counter(subs).most_common(1)[0][0] if subs else None,
            Counter(colors).most_common(1)[0][0] if colors else None)


def _reidentify(d: Detections, a: _Piece, b: _Piece, gap: float,
                branches: list[np.ndarray]) -> float | None:
    """Cost of linking ``b`` to ``a`` across a long gap (occlusion, out of range): ``b`` must
    start on a way forward from ``a``'s end at a speed ``a`` could have kept."""
    ra, rb = a.rows[-1], b.rows[0]
    va = float(np.hypot(*d.velocity[ra]))
    best = None
    for poly in branches:
        arc = arc_length(poly)
        s, lat, _ = project(poly, d.xy[rb])
        if abs(lat) > REIDENTIFY_GATE_M or s <= 0.0 or s >= arc[-1] - 1e-6:
            continue
        v = s / gap
        if not 0.4 * va - 1.0 <= v <= 1.6 * va + 3.0:
            continue
        cost = abs(lat) + abs(v - va)
        best = cost if best is None else min(best, cost)
    return best


def _stitch(d: Detections, pieces: list[_Piece], lanes: tuple[Lane, ...] = ()
            ) -> list[list[_Piece]]:
    """Link pieces into chains (greedy on the extrapolation distance; id switches and short
    gaps first, then re-identification along the map: across long gaps, and across short
    ones whose straight-line prediction misses the gate, as when an actor speeding up is
    lost for a second and the tracker's velocity lags at one end and restarts from rest at
    the other)."""
    links = []
    kinds = [_coarse(d, p.rows) for p in pieces]
    ids = [_identity(d, p.rows) for p in pieces]
    for i, a in enumerate(pieces):
        ra = a.rows[-1]
        branches: list[np.ndarray] | None = None
        for j, b in enumerate(pieces):
            if i == j:
                continue
            gap = b.start(d) - a.end(d)
            if not 0.0 < gap <= MAX_REIDENTIFY_S:
                continue
            if kinds[i] and kinds[j] and kinds[i] != kinds[j]:
                continue
            rb = b.rows[0]
            if abs(d.size[ra, 0] - d.size[rb, 0]) > 3.0:
                continue
            if gap <= MAX_GAP_S + 1e-9:
                pred = d.xy[ra] + d.velocity[ra] * gap
                dist = float(np.hypot(*(d.xy[rb] - pred)))
                if dist <= STITCH_GATE_M + STITCH_GATE_PER_S * gap:
                    links.append((dist + 0.1 * gap, i, j))
                    continue
            (sa, ca), (sb, cb) = ids[i], ids[j]
            if sa is None or sa != sb or (ca and cb and ca != cb):
                continue
            if branches is None:
                va = float(np.hypot(*d.velocity[ra]))
                h = float(numerics.arctan2(d.velocity[ra, 1], d.velocity[ra, 0])) \
                    if va > MOVING_SPEED_MPS else float(d.heading[ra])
                branches = forward_branches(lanes, d.xy[ra], h,
                                            (1.6 * va + 3.0) * MAX_REIDENTIFY_S)
            cost = _reidentify(d, a, b, gap, branches)
            if cost is not None:
                links.append((LONG_GAP_PENALTY + cost, i, j))
    nxt: dict[int, int] = {}
    prv: dict[int, int] = {}
    for _, i, j in sorted(links):
        if i in nxt or j in prv:
            continue
        nxt[i], prv[j] = j, i
    chains = []
    for i in range(len(pieces)):
        if i in prv:
            continue
        chain = [pieces[i]]
        while i in nxt:
            i = nxt[i]
            chain.append(pieces[i])
        chains.append(chain)
    return chains


def _hermite(p0: np.ndarray, v0: np.ndarray, p1: np.ndarray, v1: np.ndarray, h: float,
             u: np.ndarray) -> np.ndarray:
    """Cubic Hermite points (len(u), 2) between p0 and p1 over a gap of h seconds, u in [0, 1]."""
    u = u[:, None]
    h00 = 2 * u**3 - 3 * u**2 + 1
    h10 = u**3 - 2 * u**2 + u
    h01 = -2 * u**3 + 3 * u**2
    h11 = u**3 - u**2
    return h00 * p0 + h10 * h * v0 + h01 * p1 + h11 * h * v1


def smooth(times: np.ndarray, values: np.ndarray,
           sigma_s: float | np.ndarray = SMOOTH_SIGMA_S) -> np.ndarray:
    """Local linear regression with a Gaussian kernel (zero phase, unbiased at the ends).

    Args:
        times: (n,) sample times [s].
        values: (n, D) samples.
        sigma_s: kernel standard deviation [s], one for all samples or (n,) one each.

    Returns:
        (n, D) smoothed samples.
    """
    n = len(times)
    if np.ndim(sigma_s):
        sigma_s = np.asarray(sigma_s, dtype=np.float64)[:, None]
    if n < 3 or np.all(sigma_s <= 0):
        return values.copy()
    dt = times[None, :] - times[:, None]                      # (n, n): sample j relative to i
    w = numerics.exp(-0.5 * (dt / sigma_s) ** 2) * (np.abs(dt) <= 3 * sigma_s)
    s0 = w.sum(1)
    s1 = (w * dt).sum(1)
    s2 = (w * dt * dt).sum(1)
    det = s0 * s2 - s1 * s1
    # weights of the intercept of a weighted linear fit
    lw = w * (s2[:, None] - s1[:, None] * dt) / np.where(np.abs(det) > 1e-12, det, np.inf)[:, None]
    flat = np.abs(det) <= 1e-12
    lw[flat] = w[flat] / s0[flat, None]
    # no BLAS (its kernel would change the sum's order): one fixed-order row sum per column
    return np.stack([(lw * values[:, d]).sum(axis=1) for d in range(values.shape[1])], axis=1)


def slow_sigma(times: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """(n,) smoother kernel [s] per sample: :data:`SMOOTH_SIGMA_S`, widened for a slow
    obstacle to span :data:`SMOOTH_DISTANCE_M` of its travel (at most
    :data:`SLOW_SIGMA_MAX_S`).

    Position noise over a fixed time is a large speed error for a slow obstacle: a car
    creeping at 0.35 m/s was tracked at 0.2-0.5 m/s, every second.

    Args:
        times: (n,) uniform sample times [s]; xy: (n, 2) positions, once smoothed [m].
    """
    if len(times) < 3:
        return np.full(len(times), SMOOTH_SIGMA_S)
    vel = np.gradient(xy, times, axis=0)
    speed = smooth(times, np.hypot(vel[:, 0], vel[:, 1])[:, None], 2 * SMOOTH_SIGMA_S)[:, 0]
    return np.clip(SMOOTH_DISTANCE_M / np.maximum(speed, 1e-3), SMOOTH_SIGMA_S, SLOW_SIGMA_MAX_S)


def two_sided(times: np.ndarray, observed: np.ndarray, sigma_s: float = SMOOTH_SIGMA_S
              ) -> np.ndarray:
    """(n,) how evenly observed samples surround each sample within the smoother's kernel:
    1 where both sides carry at least half a full kernel's weight, down to 0 at an end.

    Args:
        times: (n,) uniform sample times [s]; observed: (n,) True where detected.
        sigma_s: kernel standard deviation [s].
    """
    dt = times[None, :] - times[:, None]
    w = numerics.exp(-0.5 * (dt / sigma_s) ** 2) * (np.abs(dt) <= 3 * sigma_s) * observed[None, :]
    left = (w * (dt < 0)).sum(axis=1)
    right = (w * (dt > 0)).sum(axis=1)
    step = float(times[1] - times[0]) if len(times) > 1 else 1.0
    k = np.arange(1, int(3 * sigma_s / step + 1e-9) + 1) * step
    half = float(numerics.exp(-0.5 * (k / sigma_s) ** 2).sum())
    return np.clip(np.minimum(left, right) / max(half, 1e-12), 0.0, 1.0)


def _classify(d: Detections, rows: np.ndarray) -> tuple[str, str, str, np.ndarray, list[str]]:
    notes = []
    size = np.median(d.size[rows], axis=0)
    subs = [s for s in d.sub_type[rows].tolist() if s in SUB_TYPES]
    if subs:
        kind, model = SUB_TYPES[Counter(subs).most_common(1)[0][0]]
    else:
        coarse = _coarse(d, rows)
        length, width = float(size[0]), float(size[1])
        if coarse in (None, "vehicle") and width >= 1.2:
            kind = "vehicle"
            model = ("bus" if length >= 10.3 else "truck" if length >= 6.7
                     else "suv" if length >= 4.8 else "sedan")
        elif coarse == "cyclist" or (coarse is None and length >= 1.2):
            kind, model = "cyclist", "sedan"
        else:
            kind, model = "pedestrian", "sedan"
        notes.append(f"class never recognised; {kind} ({model}) from the perceived size "
                     f"{length:.1f} x {width:.1f} m")
    colors = [c for c in (d.color[i] for i in rows.tolist()) if c in COLORS]
    if colors:
        color = Counter(colors).most_common(1)[0][0]
    else:
        color = DEFAULT_COLOR
        notes.append(f"colour never recognised; assumed {DEFAULT_COLOR}")
    return kind, model, color, size, notes


def _displacement_velocity(d: Detections, rows: np.ndarray, end: int) -> np.ndarray:
    """(2,) velocity [m/s] at one end of a piece (``end`` 0: its first detection, -1: its
    last) from the piece's own displacement over up to ``BRIDGE_VELOCITY_S``.

    A tracker's velocity is a filter state, not a measurement: a new track starts it from
    rest (the first published velocity of a truck re-acquired at 12 m/s was 1.6 m/s, pointing
    backwards), and a lost one coasts on it. A bridge between two pieces takes its end
    tangents from where the detections went instead.
    """
    t = d.times[rows]
    if end == 0:
        far = rows[min(int(np.searchsorted(t, t[0] + BRIDGE_VELOCITY_S + 1e-9)) - 1,
                       len(rows) - 1)]
        near = rows[0]
    else:
        far = rows[max(int(np.searchsorted(t, t[-1] - BRIDGE_VELOCITY_S - 1e-9)), 0)]
        near = rows[-1]
    span = abs(float(d.times[near] - d.times[far]))
    if span <= 0.0:
        return d.velocity[near]
    step = d.xy[near] - d.xy[far] if end == -1 else d.xy[far] - d.xy[near]
    return step / span


def _resample(d: Detections, chain: list[_Piece], period: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Chain detections on a uniform grid: (times, xy, perceived heading, observed)."""
    rows = np.concatenate([p.rows for p in chain])
    t = d.times[rows]
    t0, t1 = float(t[0]), float(t[-1])
    n = int(round((t1 - t0) / period)) + 1
    grid = t0 + period * np.arange(n)
    slot = np.clip(np.round((t - t0) / period).astype(np.int64), 0, n - 1)
    xy = np.full((n, 2), np.nan)
    heading = np.full(n, np.nan)
    vel = np.zeros((n, 2))
    xy[slot] = d.xy[rows]
    heading[slot] = d.heading[rows]
    vel[slot] = d.velocity[rows]
    starts = np.cumsum([0] + [len(p.rows) for p in chain])  # each piece's first index in rows
    for k in range(1, len(chain)):  # the bridge between pieces k - 1 and k
        vel[slot[starts[k] - 1]] = _displacement_velocity(d, chain[k - 1].rows, -1)
        vel[slot[starts[k]]] = _displacement_velocity(d, chain[k].rows, 0)
    observed = ~np.isnan(xy[:, 0])
    obs = np.flatnonzero(observed)
    for a, b in zip(obs[:-1], obs[1:], strict=True):
        if b - a > 1:
            u = (np.arange(a + 1, b) - a) / (b - a)
            xy[a + 1:b] = _hermite(xy[a], vel[a], xy[b], vel[b], (b - a) * period, u)
            heading[a + 1:b] = np.where(u < 0.5, heading[a], heading[b])
    return grid, xy, heading, observed


def measured(d: Detections, rows: np.ndarray) -> np.ndarray:
    """(len(rows),) False where a track's frame carries no measurement: the tracker coasted
    (the obstacle was missed and the track predicted at constant velocity).

    Such a frame's velocity is its predecessor's, unchanged, and its position the
    predecessor's advanced by that velocity over the time between them (frames of a standing
    track, velocity zero, are kept: they are the same pose either way). Kept as an
    observation, a coasted tail puts an accelerating truck 0.6 m behind where it was (the
    mirrored A3 variant's, missed for 0.3 s before its track was dropped).

    Args:
        d: the detections; rows: one track id's rows in time order.
    """
    keep = np.ones(len(rows), dtype=bool)
    if len(rows) < 2:
        return keep
    a, b = rows[:-1], rows[1:]
    step = (d.times[b] - d.times[a])[:, None]
    same_v = np.abs(d.velocity[b] - d.velocity[a]).max(1) <= COAST_TOLERANCE
    on_pred = np.abs(d.xy[b] - (d.xy[a] + d.velocity[a] * step)).max(1) <= COAST_TOLERANCE
    moving = np.abs(d.velocity[a]).max(1) > COAST_TOLERANCE  # a standing one loses nothing
    keep[1:] = ~(same_v & on_pred & moving)
    return keep


def undo_alpha_beta(d: Detections, rows: np.ndarray, tracker: AlphaBetaTracker,
                    period_s: float) -> np.ndarray:
    """(len(rows), 2) the measurements [m] behind one track's published positions.

    The tracker predicts ``p_k = x_{k-1} + v_{k-1} dt`` and publishes
    ``x_k = p_k + a (z_k - p_k)``: so ``z_k = p_k + (x_k - p_k) / a``. A track's first
    published frame, after one hidden update from rest, has ``v = b (z - x_0) / dt`` and
    ``x = x_0 + a (z - x_0)``: so ``z = x + (1 - a) v dt / b``. The published positions lag an
    accelerating obstacle (0.1 m at 2.5 m/s^2 for the built-in ADS) and a new track (0.2 m
    for a car first seen at 4.5 m/s); the measurements do not. Frames that cannot be
    inverted (a predecessor not one period before; more hidden frames) are left as they are.

    Args:
        d: the detections; rows: one track id's rows in time order (coasted ones included:
            they are the prediction the next measurement corrects).
        tracker: the stack's alpha-beta gains.
        period_s: the tracker's period [s].
    """
    a, b = tracker.position_gain, tracker.velocity_gain
    xy = d.xy[rows].copy()
    if tracker.hidden_frames == 1:
        xy[0] += (1.0 - a) * d.velocity[rows[0]] * period_s / b
    if len(rows) < 2:
        return xy
    prev, cur = rows[:-1], rows[1:]
    step = d.times[cur] - d.times[prev]
    ok = np.abs(step - period_s) <= 0.25 * period_s
    pred = d.xy[prev] + d.velocity[prev] * step[:, None]
    xy[1:] = np.where(ok[:, None], pred + (d.xy[cur] - pred) / a, xy[1:])
    return xy


def build_tracks(d: Detections, period_s: float, lanes: tuple[Lane, ...] = (),
                 tracker: AlphaBetaTracker | None = None) -> list[Track]:
    """Tracks of every movable obstacle (map entities are left to the world attachment).

    Args:
        d: the recording's detections (world frame).
        period_s: perception period [s].
        lanes: the map, to re-identify an obstacle after a long gap along its ways forward.
        tracker: the recording stack's tracker, whose coasted frames are dropped and whose
            lag is undone (None: every frame, positions as published).

    Returns:
        Tracks ordered by their first perception track id.
    """
    pieces, d = _pieces(d, period_s, tracker)
    tracks = [track for chain in _stitch(d, pieces, lanes)
              if (track := _track(d, chain, period_s)) is not None]
    return sorted(tracks, key=lambda tr: tr.track_ids[0])


def _pieces(d: Detections, period_s: float, tracker: AlphaBetaTracker | None
            ) -> tuple[list[_Piece], Detections]:
    """One piece per perception track id of a movable obstacle (rows in time order), and the
    detections with the tracker's lag undone (``d`` itself without a tracker).

    A tracker that coasts has its coasted frames dropped from the pieces (unless that leaves
    fewer than :data:`MIN_DETECTIONS`) and its lag undone on every row of the track.
    """
    movable = (d.type != TYPE_UNKNOWN_UNMOVABLE) & ~np.isin(d.sub_type, _STATIC_SUB_TYPES)
    pieces = []
    undone: list[tuple[np.ndarray, np.ndarray]] = []
    for tid in np.unique(d.track_id[movable]).tolist():
        rows = np.flatnonzero(movable & (d.track_id == tid))
        rows = rows[np.argsort(d.times[rows], kind="stable")]
        if tracker is not None:  # a tracker that coasts: drop its coasted frames, undo its lag
            undone.append((rows, undo_alpha_beta(d, rows, tracker, period_s)))
            kept = rows[measured(d, rows)]
            rows = kept if len(kept) >= MIN_DETECTIONS else rows
        pieces.append(_Piece(int(tid), rows))
    if undone:
        fixed = d.xy.copy()
        for rows, xy in undone:
            fixed[rows] = xy
        d = dataclasses.replace(d, xy=fixed)
    return pieces, d


@dataclass(frozen=True)
class _Motion:
    """A track's motion on its time grid: (n, 2) position [m], (n,) speed [m/s], (n,) heading
    of travel and (n,) heading of the body [rad, unwrapped]."""

    xy: np.ndarray
    speed: np.ndarray
    heading: np.ndarray
    body: np.ndarray


def _track(d: Detections, chain: list[_Piece], period_s: float) -> Track | None:
    """The track of one stitched chain of pieces (None for one with fewer than
    :data:`MIN_DETECTIONS` detections, spurious)."""
    rows = np.concatenate([p.rows for p in chain])
    if len(rows) < MIN_DETECTIONS:
        return None
    grid, xy, perceived, observed = _resample(d, chain, period_s)
    kind, model, color, size, notes = _classify(d, rows)
    raw = d.xy[rows]
    centre = np.median(raw, axis=0)
    stationary = bool(np.percentile(np.hypot(*(raw - centre).T), 90) < STATIC_SPREAD_M)
    motion = (_parked(d, rows, grid, centre) if stationary
              else _moving(grid, xy, perceived, observed, kind))
    return Track(
        track_ids=tuple(p.track_id for p in chain), times=grid, xy=motion.xy,
        heading=wrap(motion.heading), speed=motion.speed, observed=observed, kind=kind,
        model=model, color=color, size=size, notes=tuple(notes), stationary=stationary,
        body_heading=wrap(motion.body))


def _parked(d: Detections, rows: np.ndarray, grid: np.ndarray, centre: np.ndarray) -> _Motion:
    """A parked obstacle: its median position and mean (axial) heading all along, not a drift
    of tracker noise."""
    xy = np.repeat(centre[None], len(grid), 0)
    speed = np.zeros(len(grid))
    h2 = 2.0 * d.heading[rows]
    heading = np.full(len(grid), 0.5 * numerics.arctan2(np.sin(h2).mean(), np.cos(h2).mean()))
    return _Motion(xy, speed, heading, heading)


def _moving(grid: np.ndarray, xy: np.ndarray, perceived: np.ndarray, observed: np.ndarray,
            kind: str) -> _Motion:
    """A moving obstacle's motion from its resampled positions ``xy`` and ``perceived``
    headings, smoothed (``observed``: which samples have detections around them)."""
    # a vehicle's twiced where detections surround a sample (the residual smoothed and
    # added back): a local linear fit cuts a turn's corner by a sigma^2 / 2 (0.1 m for
    # a car turning at 6.5 m/s on an 11.5 m radius), twicing is exact for quadratic
    # motion; near a track's ends and gaps it would double the one-sided fit's noise.
    # Cyclists and pedestrians turn gently at their speeds and are detected no better:
    # twiced, the LAV-like stack's unrecognised cyclist (l04) put the replayed ego
    # 0.36 m RMS off instead of 0.26 m
    once = smooth(grid, xy)
    sigma = slow_sigma(grid, once)
    if np.any(sigma > SMOOTH_SIGMA_S):
        once = smooth(grid, xy, sigma)
    if kind == "vehicle":
        xy = once + two_sided(grid, observed)[:, None] * smooth(grid, xy - once, sigma)
    else:
        xy = once
    vel = np.gradient(xy, grid, axis=0)
    speed = np.hypot(vel[:, 0], vel[:, 1])
    heading = np.where(speed > MOVING_SPEED_MPS, numerics.arctan2(vel[:, 1], vel[:, 0]),
                       perceived)
    # the box orientation, its pi ambiguity resolved toward the direction of travel
    # (a slow vehicle's: its overall displacement)
    travel = xy[-1] - xy[0]
    ref = np.where(speed > MOVING_SPEED_MPS, heading, numerics.arctan2(travel[1], travel[0])
                   if np.hypot(*travel) > 0.5 else perceived)
    body = np.where(np.isnan(perceived), ref, perceived)
    body = np.where(np.cos(body - ref) < 0.0, body + np.pi, body)
    # the detector's orientation noise, moved ahead to the front axle (paths.py), made
    # a turning car's target speed jitter by 0.25 m/s (its profile by 3 m/s)
    body = smooth(grid, np.unwrap(body)[:, None])[:, 0]
    return _Motion(xy, speed, heading, body)


__all__ = ["SUB_TYPES", "Track", "build_tracks", "measured", "smooth", "two_sided", "undo_alpha_beta"]
