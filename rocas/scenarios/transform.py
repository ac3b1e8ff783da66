"""Rigid motions of a whole scenario: rotate, mirror and translate the world.

A :class:`PlaneTransform` maps every coordinate of a scenario (lane centre lines, light heads,
objects, area polygons, actors' waypoints) and every world angle (light facings, object yaws,
the sun's azimuth) the same way, so distances, arc lengths and angles between things are kept:
the accident mechanism is the same, only the numbers differ. A mirror also flips every lateral
offset (positive is left of the direction of travel, and left becomes right), so a mirrored
world drives on the other side of the road.

```python
from rocas.scenarios.transform import PlaneTransform, transform_scenario
t = PlaneTransform.rotation(math.radians(37.0), about=(120.0, -40.0))
rotated = transform_scenario(scenario, t)
back = transform_scenario(rotated, t.inverse())   # equal to scenario within ~1e-12 m
```

What stays *not* invariant is the ADS's business, not the scenario's: localization noise is
drawn in world x/y (so a rotated run sees the same noise values along other road directions),
and the brake classifier's apparent-width feature reads a world yaw against an ego-frame bearing
(docs/ads.md, "Known bug"), so a rotated world can change what the camera classifier scores.
The variant generator (:mod:`rocas.catalog.variants`) keeps only variants that still crash as
documented, so these effects decide which rotations are kept, never what a kept one means.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rocas.scenarios.model import Actor, Area, Point, Scenario, StaticObject, TrafficLight

_TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class PlaneTransform:
    """``p' = R(angle) F p + offset``: F mirrors y (``y -> -y``) when ``mirror`` is true, R
    rotates by ``angle_rad`` counter-clockwise, then the result moves by ``offset`` [m].

    Headings map as ``h' = angle + (-h if mirror else h)``; lateral offsets (positive left)
    change sign under a mirror.
    """

    angle_rad: float = 0.0
    mirror: bool = False
    offset: Point = (0.0, 0.0)

    @classmethod
    def rotation(cls, angle_rad: float, about: Point = (0.0, 0.0)) -> PlaneTransform:
        """Rotation by ``angle_rad`` counter-clockwise about the point ``about``."""
        cx, cy = about
        c, s = math.cos(angle_rad), math.sin(angle_rad)
        return cls(angle_rad, False, (cx - (c * cx - s * cy), cy - (s * cx + c * cy)))

    @classmethod
    def reflection(cls, axis_angle_rad: float, through: Point = (0.0, 0.0)) -> PlaneTransform:
        """Mirror in the line through ``through`` at ``axis_angle_rad`` from +x.

        A reflection in a line at angle phi through the origin is ``R(2 phi) F``.
        """
        px, py = through
        two = 2.0 * axis_angle_rad
        c, s = math.cos(two), math.sin(two)
        # the line's points are fixed: offset = p - R(2 phi) F p
        return cls(two, True, (px - (c * px + s * py), py - (s * px - c * py)))

    @classmethod
    def translation(cls, dx: float, dy: float) -> PlaneTransform:
        return cls(0.0, False, (dx, dy))

    def point(self, p: Point) -> Point:
        x, y = p
        if self.mirror:
            y = -y
        c, s = math.cos(self.angle_rad), math.sin(self.angle_rad)
        return (c * x - s * y + self.offset[0], s * x + c * y + self.offset[1])

    def heading(self, h_rad: float) -> float:
        """A world heading [rad], wrapped to [-pi, pi] (an angle already there and an
        identity transform give it back exactly)."""
        return math.remainder((-h_rad if self.mirror else h_rad) + self.angle_rad, _TWO_PI)

    def heading_deg(self, h_deg: float) -> float:
        """A world heading in degrees (the sun's azimuth), wrapped to [0, 360)."""
        d = (-h_deg if self.mirror else h_deg) + math.degrees(self.angle_rad)
        return d % 360.0

    def lateral(self, offset_m: float) -> float:
        """A lateral offset from a path (positive left) [m]."""
        return -offset_m if self.mirror else offset_m

    def then(self, other: PlaneTransform) -> PlaneTransform:
        """This transform followed by ``other``."""
        # other(self(p)) = Ro Fo (Rs Fs p + ts) + to; Fo R(a) = R(-a) Fo
        a = other.angle_rad + (-self.angle_rad if other.mirror else self.angle_rad)
        tx, ty = other.point(self.offset)
        return PlaneTransform(a, self.mirror != other.mirror, (tx, ty))

    def inverse(self) -> PlaneTransform:
        """The transform that undoes this one."""
        # p = F R(-a) (p' - t); F R(-a) = R(a) F, so with a mirror the angle stays a
        a = self.angle_rad if self.mirror else -self.angle_rad
        undo = PlaneTransform(a, self.mirror, (0.0, 0.0))
        tx, ty = undo.point(self.offset)
        return PlaneTransform(a, self.mirror, (-tx, -ty))


def _points(t: PlaneTransform, pts: tuple[Point, ...]) -> tuple[Point, ...]:
    return tuple(t.point(p) for p in pts)


def _light(t: PlaneTransform, tl: TrafficLight) -> TrafficLight:
    return dataclasses.replace(tl, position=t.point(tl.position), facing_rad=t.heading(tl.facing_rad))


def _object(t: PlaneTransform, o: StaticObject) -> StaticObject:
    return dataclasses.replace(o, position=t.point(o.position), yaw_rad=t.heading(o.yaw_rad))


def _area(t: PlaneTransform, a: Area) -> Area:
    return dataclasses.replace(a, polygon=_points(t, a.polygon))


def _actor(t: PlaneTransform, a: Actor) -> Actor:
    return dataclasses.replace(a, waypoints=_points(t, a.waypoints),
                               lateral_offset_m=t.lateral(a.lateral_offset_m))


def transform_scenario(s: Scenario, t: PlaneTransform) -> Scenario:
    """The scenario with every coordinate and world angle mapped by ``t`` (arc lengths,
    speeds, timings, ids, routes and parameters are unchanged)."""
    return dataclasses.replace(
        s,
        lanes=tuple(dataclasses.replace(ln, centerline=_points(t, ln.centerline))
                    for ln in s.lanes),
        traffic_lights=tuple(_light(t, tl) for tl in s.traffic_lights),
        objects=tuple(_object(t, o) for o in s.objects),
        areas=tuple(_area(t, a) for a in s.areas),
        actors=tuple(_actor(t, a) for a in s.actors),
        weather=dataclasses.replace(s.weather,
                                    sun_azimuth_deg=t.heading_deg(s.weather.sun_azimuth_deg)),
        ego=dataclasses.replace(s.ego, start_lateral_m=t.lateral(s.ego.start_lateral_m)),
    )


def transform_change(change: Mapping[str, Any], t: PlaneTransform) -> dict[str, Any]:
    """A catalog mutation (``{"actor": id, field: value, ...}`` in the file format, see
    :func:`rocas.catalog.mutate`) mapped by ``t``: positions, waypoints, polygons,
    facings, yaws and lateral offsets move with the world; anything else is kept."""
    out: dict[str, Any] = {}
    for key, value in change.items():
        if key == "position":
            out[key] = list(t.point(tuple(value)))
        elif key in ("waypoints", "polygon"):
            out[key] = [list(t.point(tuple(p))) for p in value]
        elif key in ("facing_deg", "yaw_deg"):
            out[key] = math.degrees(t.heading(math.radians(value)))
        elif key in ("lateral_offset_m", "start_lateral_m"):
            out[key] = t.lateral(value)
        else:
            out[key] = value
    return out

