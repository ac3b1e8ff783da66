"""The static map of an execution and its traffic lights over time, under ``<prefix>/world``.

Entities::

    world/roads, world/lane_edges, world/centerlines   lanes (static)
    world/areas/buildings, world/areas/vegetation       map areas (static)
    world/objects                                       cones and boxes (static)
    world/stop_lines, world/traffic_lights              coloured by the light state over time
    world/traffic_light_labels                          each light's state, clear of the road
    world/highlight                                     the mutated map entity (static)

``world`` is the ``rocas/world.json`` attachment of rocas's own recordings (lanes, areas,
objects, traffic lights, the scenario's time step).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from rocas.scenarios.model import OBJECT_DIMENSIONS
from rocas.viz.draw import HIGHLIGHT_COLOR, LIGHT_RGB, ROAD_RGB, box_outline, over_time


def _offset(points: np.ndarray, d: float) -> np.ndarray:
    """The polyline ``points`` (n, 2) moved ``d`` [m] to its left (right when negative)."""
    seg = np.diff(points, axis=0)
    n = np.stack([-seg[:, 1], seg[:, 0]], axis=1)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-9)
    normals = np.vstack([n[:1], (n[:-1] + n[1:]) / 2, n[-1:]]) if len(n) > 1 else np.vstack([n, n])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-9)
    return points + d * normals


def _point_at(points: np.ndarray, s: float) -> tuple[float, float, float]:
    """(x, y, heading [rad]) at arc length ``s`` [m] along the polyline ``points`` (n, 2)."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    i = int(np.clip(np.searchsorted(cum, s) - 1, 0, len(seg) - 1))
    u = 0.0 if seg[i] <= 0 else float(np.clip((s - cum[i]) / seg[i], 0.0, 1.0))
    p = points[i] + u * (points[i + 1] - points[i])
    d = points[i + 1] - points[i]
    return float(p[0]), float(p[1]), math.atan2(d[1], d[0])


def light_color_at(policy: dict[str, Any], enabled: bool, t: float) -> str:
    """Colour a light shows at ``t`` [s] (same rule as the simulator)."""
    if not enabled:
        return "off"
    if policy.get("mode") != "cycle":
        return str(policy.get("color", "green"))
    g, y, r = (float(policy.get(k, 0.0)) for k in ("green_s", "yellow_s", "red_s"))
    phase = (t + float(policy.get("offset_s", 0.0))) % max(g + y + r, 1e-9)
    return "green" if phase < g else "yellow" if phase < g + y else "red"


def log_world(
    rec: Any,
    world: dict[str, Any],
    prefix: str,
    *,
    duration_s: float,
    highlight: frozenset[str] = frozenset(),
) -> None:
    """Log the static map (lanes, areas, objects) and the traffic lights over time."""
    w = f"{prefix}/world"
    lanes = [ln for ln in world.get("lanes", []) if len(ln.get("points", [])) >= 2]
    pts = {ln["id"]: np.asarray(ln["points"], dtype=np.float64) for ln in lanes}
    if lanes:
        _log_lanes(rec, w, lanes, pts)
    _log_areas(rec, w, world.get("areas", []))
    objects = world.get("objects", [])
    if objects:
        _log_objects(rec, w, objects)
    lights = [tl for tl in world.get("traffic_lights", []) if tl.get("stop_lane") in pts]
    if lights:
        road = road_patches(lanes, pts, [tuple(tl["position"]) for tl in lights])
        _log_lights(rec, w, lights, pts, duration_s, float(world.get("scenario", {}).get("dt_s", 0.05)),
                    road)
    _log_world_highlight(rec, w, world, pts, highlight)


def _log_lanes(rec: Any, w: str, lanes: list[dict[str, Any]], pts: dict[str, np.ndarray]) -> None:
    """The asphalt (one strip per lane, radius half the lane's width), lane edges, centrelines."""
    import rerun as rr

    for width in sorted({float(ln.get("width_m", 3.5)) for ln in lanes}):
        group = [ln for ln in lanes if float(ln.get("width_m", 3.5)) == width]
        name = "roads" if width == float(lanes[0].get("width_m", 3.5)) else f"roads_{width:g}m"
        rec.log(
            f"{w}/{name}",
            rr.LineStrips2D(
                [pts[ln["id"]] for ln in group], radii=width / 2, colors=[ROAD_RGB], draw_order=0.0
            ),
            static=True,
        )
    edges = []
    for ln in lanes:
        half = float(ln.get("width_m", 3.5)) / 2
        edges += [_offset(pts[ln["id"]], half), _offset(pts[ln["id"]], -half)]
    rec.log(
        f"{w}/lane_edges",
        rr.LineStrips2D(edges, radii=0.08, colors=[(235, 235, 235, 200)], draw_order=1.0),
        static=True,
    )
    rec.log(
        f"{w}/centerlines",
        rr.LineStrips2D(
            [pts[ln["id"]] for ln in lanes],
            radii=0.04,
            colors=[(240, 210, 80, 110)],
            labels=[ln["id"] for ln in lanes],
            show_labels=False,
            draw_order=1.1,
        ),
        static=True,
    )


def _log_areas(rec: Any, w: str, all_areas: list[dict[str, Any]]) -> None:
    """Buildings and vegetation as closed outlines, faint when disabled."""
    import rerun as rr

    for kind, color in (("building", (120, 100, 90)), ("vegetation", (40, 140, 50))):
        areas = [
            a for a in all_areas if a.get("kind") == kind and len(a.get("polygon", [])) >= 3
        ]
        if not areas:
            continue
        strips = [np.vstack([a["polygon"], a["polygon"][:1]]) for a in areas]
        colors = [(*color, 255 if a.get("enabled", True) else 90) for a in areas]
        labels = [a["id"] + ("" if a.get("enabled", True) else " (disabled)") for a in areas]
        plural = "buildings" if kind == "building" else kind
        rec.log(
            f"{w}/areas/{plural}",
            rr.LineStrips2D(strips, radii=0.35, colors=colors, labels=labels, draw_order=2.0),
            static=True,
        )


def _log_objects(rec: Any, w: str, objects: list[dict[str, Any]]) -> None:
    """Cones and boxes: their outlines and a marker each."""
    import rerun as rr

    xy = np.array([o["position"] for o in objects], dtype=np.float64)
    yaw = np.radians([float(o.get("yaw_deg", 0.0)) for o in objects])
    size = np.array([OBJECT_DIMENSIONS.get(o.get("kind"), (1.0, 1.0, 1.0))[:2] for o in objects])
    colors = [(250, 120, 20) if o.get("kind") == "cone" else (150, 105, 60) for o in objects]
    rec.log(
        f"{w}/objects",
        rr.LineStrips2D(
            box_outline(xy, yaw, size),
            radii=0.1,
            colors=colors,
            labels=[o["id"] for o in objects],
            show_labels=False,
            draw_order=4.0,
        ),
        static=True,
    )
    rec.log(
        f"{w}/objects/markers", rr.Points2D(xy, radii=0.3, colors=colors, draw_order=4.1), static=True
    )


#: Labels near a light keep off the road within this distance of it [m], where stop lines and
#: queued cars are; the road is tested in squares this far apart along each lane [m].
ROAD_CLEAR_RADIUS_M, ROAD_PATCH_STEP_M = 25.0, 1.5


def road_patches(
    lanes: list[dict[str, Any]], pts: dict[str, np.ndarray], near: list[tuple[float, float]],
    radius_m: float = ROAD_CLEAR_RADIUS_M, step_m: float = ROAD_PATCH_STEP_M,
) -> list[tuple[float, float, float, float]]:
    """Squares (x0, y0, x1, y1) [m] covering the lanes' surface within ``radius_m`` of any point
    of ``near``: one square of the lane's width every ``step_m`` along each lane."""
    if not near:
        return []
    centers = np.asarray(near, dtype=np.float64).reshape(-1, 2)
    out: list[tuple[float, float, float, float]] = []
    for ln in lanes:
        line = pts[ln["id"]]
        if len(line) < 2:
            continue
        half = float(ln.get("width_m", 3.5)) / 2
        seg = np.linalg.norm(np.diff(line, axis=0), axis=1)
        cum = np.concatenate([[0.0], np.cumsum(seg)])
        s = np.arange(0.0, cum[-1] + step_m / 2, step_m)
        xy = np.column_stack([np.interp(s, cum, line[:, 0]), np.interp(s, cum, line[:, 1])])
        d = np.min(np.linalg.norm(xy[:, None, :] - centers[None, :, :], axis=2), axis=1)
        out += [(x - half, y - half, x + half, y + half) for x, y in xy[d <= radius_m + half]]
    return out


def _log_lights(
    rec: Any, w: str, lights: list[dict[str, Any]], pts: dict[str, np.ndarray], duration_s: float,
    dt_s: float, road: Sequence[tuple[float, float, float, float]] = (),
) -> None:
    import rerun as rr

    lines, heads = [], np.array([tl["position"] for tl in lights], dtype=np.float64)
    for tl in lights:
        lane = pts[tl["stop_lane"]]
        x, y, h = _point_at(lane, float(tl.get("stop_s_m", 0.0)))
        nx, ny = -math.sin(h) * 1.75, math.cos(h) * 1.75
        lines.append(np.array([[x - nx, y - ny], [x + nx, y + ny]]))
    # colour changes only: one row at 0 and one per change
    steps = np.arange(0.0, max(duration_s, dt_s) + dt_s / 2, max(dt_s, 1e-3))
    times, states = [], []
    prev = None
    for t in steps:
        state = tuple(
            light_color_at(tl.get("policy", {}), bool(tl.get("enabled", True)), float(t)) for tl in lights
        )
        if state != prev:
            times.append(float(t))
            states.append(state)
            prev = state
    n = len(lights)
    colors = [LIGHT_RGB.get(c, LIGHT_RGB["off"]) for s in states for c in s]
    labels = [f"{tl['id']}: {c}" for s in states for tl, c in zip(lights, s, strict=True)]
    over_time(rec, f"{w}/stop_lines", rr.LineStrips2D(lines, radii=0.3, draw_order=3.0), times,
               rr.LineStrips2D.columns(colors=colors).partition([n] * len(times)))
    over_time(rec, f"{w}/traffic_lights", rr.Points2D(heads, radii=0.9, draw_order=9.5,
                                                       show_labels=False), times,
               rr.Points2D.columns(colors=colors, labels=labels).partition([n] * len(times)))
    # the labels beside the lights, clear of them, of each other and of the road around them
    # (stop lines, queued cars; rocas.viz.labels), at a spot chosen once for each light's
    # longest text
    from rocas.viz.labels import LabelItem, label_anchors, place_labels

    items = [LabelItem(f"{tl['id']}: yellow", (float(x), float(y)), 1.2)
             for tl, (x, y) in zip(lights, heads, strict=True)]
    anchors = np.asarray(label_anchors(items, place_labels(items, obstacles=road)), dtype=np.float64)
    over_time(rec, f"{w}/traffic_light_labels",
               rr.Points2D(anchors, radii=0.05, draw_order=13.0, show_labels=True), times,
               rr.Points2D.columns(colors=colors, labels=labels).partition([n] * len(times)))


def _log_world_highlight(
    rec: Any, w: str, world: dict[str, Any], pts: dict[str, np.ndarray], highlight: frozenset[str]
) -> None:
    import rerun as rr

    if not highlight:
        return
    strips, labels = [], []
    for a in world.get("areas", []):
        if a["id"] in highlight:
            strips.append(np.vstack([a["polygon"], a["polygon"][:1]]))
            labels.append(f"mutated: {a['id']}")
    for o in world.get("objects", []):
        if o["id"] in highlight:
            x, y = o["position"]
            strips.append(box_outline(np.array([[x, y]]), np.zeros(1), np.array([[2.0, 2.0]]))[0])
            labels.append(f"mutated: {o['id']}")
    for tl in world.get("traffic_lights", []):
        if tl["id"] in highlight:
            x, y = tl["position"]
            strips.append(box_outline(np.array([[x, y]]), np.zeros(1), np.array([[3.0, 3.0]]))[0])
            labels.append(f"mutated: {tl['id']}")
    for ln in world.get("lanes", []):
        if ln["id"] in highlight and ln["id"] in pts:
            strips.append(pts[ln["id"]])
            labels.append(f"mutated: {ln['id']}")
    if strips:
        rec.log(
            f"{w}/highlight",
            rr.LineStrips2D(strips, radii=0.6, colors=[HIGHLIGHT_COLOR], labels=labels, draw_order=8.5),
            static=True,
        )


__all__ = ["light_color_at", "log_world", "road_patches"]
