"""Walking the map: which lane a pose is on, and where it leads forward or came from."""

from __future__ import annotations

import numpy as np

from rocas import numerics
from rocas.replay.frames import wrap
from rocas.scenarios.model import Lane

LANE_MATCH_HEADING_RAD = np.deg2rad(40.0)
LANE_MATCH_EXTRA_M = 1.0     # [m] beyond the lane's half width


def _polyline(lane: Lane) -> np.ndarray:
    return np.asarray(lane.centerline, dtype=np.float64)


def arc_length(points: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points, axis=0).T))])


def project(points: np.ndarray, p: np.ndarray) -> tuple[float, float, float]:
    """(arc length, signed lateral offset (left +), segment heading) of p on a polyline."""
    a, b = points[:-1], points[1:]
    d = b - a
    ll = np.maximum((d * d).sum(1), 1e-12)
    u = np.clip(((p - a) * d).sum(1) / ll, 0.0, 1.0)
    q = a + u[:, None] * d
    dist = np.hypot(*(p - q).T)
    i = int(np.argmin(dist))
    h = float(numerics.arctan2(d[i, 1], d[i, 0]))
    side = -np.sin(h) * (p[0] - q[i, 0]) + np.cos(h) * (p[1] - q[i, 1])
    lat = float(np.copysign(dist[i], side))  # true distance (a clamped end is not "beside")
    return float(arc_length(points)[i] + u[i] * np.sqrt(ll[i])), lat, h


def match_lane(lanes: tuple[Lane, ...], p: np.ndarray, heading: float
               ) -> tuple[Lane, float, float] | None:
    """The lane a pose drives on: (lane, arc length, lateral offset) or None."""
    best = None
    for lane in lanes:
        s, lat, h = project(_polyline(lane), p)
        if abs(float(wrap(heading - h))) > LANE_MATCH_HEADING_RAD:
            continue
        if abs(lat) > lane.width_m / 2 + LANE_MATCH_EXTRA_M:
            continue
        if best is None or abs(lat) < abs(best[2]):
            best = (lane, s, lat)
    return best


def _offset(points: np.ndarray, lateral_m: float) -> np.ndarray:
    if len(points) < 2 or lateral_m == 0.0:
        return points
    g = np.gradient(points, axis=0)
    h = numerics.arctan2(g[:, 1], g[:, 0])
    return points + lateral_m * np.stack([-np.sin(h), np.cos(h)], -1)


def _graph(lanes: tuple[Lane, ...]) -> tuple[dict[str, Lane], dict[str, list[str]]]:
    by_id = {ln.id: ln for ln in lanes}
    preds: dict[str, list[str]] = {}
    for ln in lanes:
        for succ in ln.successors:
            preds.setdefault(succ, []).append(ln.id)
    return by_id, preds


def _sequences(lanes: tuple[Lane, ...], first: Lane, s: float, length_m: float, forward: bool,
               limit: int) -> list[list[str]]:
    """Lane sequences from ``first`` (at arc length s) long enough to cover ``length_m``,
    every branch (successors forward, predecessors backward), at most ``limit``."""
    by_id, preds = _graph(lanes)
    out: list[list[str]] = []

    def visit(seq: list[str], remaining: float) -> None:
        if len(out) >= limit:
            return
        lane = by_id[seq[-1]]
        nxt = lane.successors if forward else tuple(preds.get(lane.id, ()))
        if remaining <= 0.0 or not nxt or len(seq) > 30:
            out.append(seq)
            return
        for n in nxt:
            visit([*seq, n], remaining - float(arc_length(_polyline(by_id[n]))[-1]))

    own = float(arc_length(_polyline(first))[-1])
    visit([first.id], length_m - ((own - s) if forward else s))
    return out


def _build(lanes: tuple[Lane, ...], p: np.ndarray, heading: float, length_m: float,
           forward: bool, match: tuple[Lane, float, float] | None, seq: list[str]) -> np.ndarray:
    by_id = {ln.id: ln for ln in lanes}
    parts: list[np.ndarray] = []
    total = 0.0
    direction = np.array([np.cos(heading), np.sin(heading)]) * (1.0 if forward else -1.0)
    end = p
    if match is not None:
        _, s, lat = match
        for k, lane_id in enumerate(seq):
            pts = _polyline(by_id[lane_id])
            arc = arc_length(pts)
            if k > 0:
                s = -1.0 if forward else float(arc[-1]) + 1.0
            shifted = _offset(pts, lat)
            keep = shifted[arc > s + 1e-6] if forward else shifted[arc < s - 1e-6][::-1]
            if len(keep):
                seg = np.vstack([end, keep])
                parts.append(seg[1:])
                total += float(arc_length(seg)[-1])
                end = seg[-1]
            if total >= length_m:
                break
        if parts:
            allp = np.vstack(parts)
            tail = allp[-2:] if len(allp) >= 2 else np.vstack([p, allp])
            d = tail[-1] - tail[-2]
            direction = d / max(float(np.hypot(*d)), 1e-9)
    if total < length_m:
        extra = length_m - total + 1.0
        parts.append(end + direction * np.linspace(1.0, extra, max(2, int(extra // 5) + 2))[:, None])
    out = _trim(np.vstack([p, *parts]), length_m)[1:]
    return out if forward else out[::-1]


def walk_lanes(lanes: tuple[Lane, ...], p: np.ndarray, heading: float, length_m: float,
               forward: bool) -> np.ndarray:
    """Points along the map from pose ``p`` for ``length_m`` metres, forward (following first
    successors) or backward (through first predecessors), keeping the pose's offset from the
    lane centre; a straight line where the map ends or the pose matches no lane. Forward:
    ordered away from p; backward: ordered towards p. p itself is excluded."""
    if length_m <= 0.0:
        return np.zeros((0, 2))
    m = match_lane(lanes, p, heading)
    seq = _sequences(lanes, m[0], m[1], length_m, forward, 1)[0] if m is not None else []
    return _build(lanes, p, heading, length_m, forward, m, seq)


def forward_branches(lanes: tuple[Lane, ...], p: np.ndarray, heading: float, length_m: float,
                     limit: int = 16) -> list[np.ndarray]:
    """Every way forward from pose ``p`` over ``length_m`` metres (one polyline per branch,
    starting with p); a single straight line when the pose matches no lane."""
    m = match_lane(lanes, p, heading)
    seqs = _sequences(lanes, m[0], m[1], length_m, True, limit) if m is not None else [[]]
    return [np.vstack([p, _build(lanes, p, heading, length_m, True, m, q)]) for q in seqs]


def _trim(points: np.ndarray, length_m: float) -> np.ndarray:
    """Cut a polyline at arc length ``length_m``."""
    arc = arc_length(points)
    if arc[-1] <= length_m:
        return points
    k = int(np.searchsorted(arc, length_m))
    u = (length_m - arc[k - 1]) / max(arc[k] - arc[k - 1], 1e-12)
    return np.vstack([points[:k], points[k - 1] + u * (points[k] - points[k - 1])])


__all__ = ["arc_length", "forward_branches", "match_lane", "project", "walk_lanes"]
