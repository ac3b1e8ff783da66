"""Plain-Python polyline geometry shared by the scenario format and the simulator (no numpy:
the scenario loader runs it once per entity, the simulator once per compiled world)."""

from __future__ import annotations

import math


def polyline_length(points: tuple[tuple[float, float], ...]) -> float:
    return sum(math.dist(points[i], points[i + 1]) for i in range(len(points) - 1))


def point_at(points: tuple[tuple[float, float], ...], s: float) -> tuple[float, float, float]:
    """(x, y, heading) at arc length ``s`` on a polyline (clamped to its ends)."""
    acc = 0.0
    for i in range(len(points) - 1):
        (x0, y0), (x1, y1) = points[i], points[i + 1]
        seg = math.hypot(x1 - x0, y1 - y0)
        if seg <= 0:
            continue
        if acc + seg >= s or i == len(points) - 2:
            u = min(max((s - acc) / seg, 0.0), 1.0)
            return x0 + u * (x1 - x0), y0 + u * (y1 - y0), math.atan2(y1 - y0, x1 - x0)
        acc += seg
    (x0, y0), (x1, y1) = points[0], points[-1]
    return x0, y0, math.atan2(y1 - y0, x1 - x0)
