"""Load and validate scenario files (TOML) into :class:`rocas.scenarios.model.Scenario`.

Errors name the file, the key path and the reason, e.g.
``scenario.toml: actors[1].speed_profile[0]: expected a [time_s, speed_mps] pair``.
The format is documented in ``docs/scenarios.md``; :func:`scenario_to_dict` writes the same
format back (used for the world attachment of recordings).
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from rocas.errors import ScenarioError
from rocas.geometry import point_at, polyline_length
from rocas.scenarios.model import (
    ACTOR_KINDS,
    AREA_KINDS,
    COLORS,
    DEFAULT_STACK,
    LIGHT_COLORS,
    LIGHT_MODES,
    OBJECT_KINDS,
    VEHICLE_MODELS,
    Actor,
    Area,
    Ego,
    Lane,
    LightPolicy,
    Scenario,
    StaticObject,
    TrafficLight,
    Weather,
)

FORMAT_VERSION = 1
#: Keys printed as they are in error messages; any other key is quoted.
_PLAIN_KEY = re.compile(r"[A-Za-z0-9_-]+")


class _Ctx:
    """Where we are in the file, for error messages."""

    def __init__(self, source: str, ranges: bool = True) -> None:
        self.source = source
        self.ranges = ranges  # whether numbers are checked against their ranges

    def fail(self, key: str, reason: str) -> ScenarioError:
        return ScenarioError(f"{self.source}: {key}: {reason}")


def _table(ctx: _Ctx, data: Any, key: str, allowed: set[str], required: set[str] = frozenset()
           ) -> dict[str, Any]:
    if not isinstance(data, Mapping):
        raise ctx.fail(key, f"expected a table, got {type(data).__name__}")
    for k in data:
        if k not in allowed:
            k = k if _PLAIN_KEY.fullmatch(str(k)) else repr(k)
            raise ctx.fail(f"{key}.{k}" if key else k,
                           f"unknown key (allowed: {', '.join(sorted(allowed))})")
    for k in required:
        if k not in data:
            raise ctx.fail(f"{key}.{k}" if key else k, "required key is missing")
    return dict(data)


def _num(ctx: _Ctx, value: Any, key: str, lo: float | None = None, hi: float | None = None
         ) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ctx.fail(key, f"expected a number, got {type(value).__name__} {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ctx.fail(key, "must be finite")
    if ctx.ranges and ((lo is not None and v < lo) or (hi is not None and v > hi)):
        raise ctx.fail(key, f"{v:g} is out of range [{lo if lo is not None else '-inf'}, "
                            f"{hi if hi is not None else 'inf'}]")
    return v


def _int(ctx: _Ctx, value: Any, key: str, lo: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ctx.fail(key, f"expected an integer, got {type(value).__name__} {value!r}")
    if lo is not None and value < lo:
        raise ctx.fail(key, f"{value} is out of range [{lo}, inf]")
    return int(value)


def _str(ctx: _Ctx, value: Any, key: str, choices: tuple[str, ...] | None = None) -> str:
    if not isinstance(value, str):
        raise ctx.fail(key, f"expected a string, got {type(value).__name__} {value!r}")
    if choices is not None and value not in choices:
        raise ctx.fail(key, f"{value!r} is not one of {', '.join(choices)}")
    return value


def _bool(ctx: _Ctx, value: Any, key: str) -> bool:
    if not isinstance(value, bool):
        raise ctx.fail(key, f"expected true or false, got {type(value).__name__} {value!r}")
    return value


def _list(ctx: _Ctx, value: Any, key: str) -> list[Any]:
    if not isinstance(value, list):
        raise ctx.fail(key, f"expected a list, got {type(value).__name__}")
    return value


def _point(ctx: _Ctx, value: Any, key: str) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise ctx.fail(key, "expected a point [x, y]")
    return (_num(ctx, value[0], f"{key}[0]"), _num(ctx, value[1], f"{key}[1]"))


def _points(ctx: _Ctx, value: Any, key: str, min_len: int) -> tuple[tuple[float, float], ...]:
    items = _list(ctx, value, key)
    if len(items) < min_len:
        raise ctx.fail(key, f"expected at least {min_len} points, got {len(items)}")
    return tuple(_point(ctx, p, f"{key}[{i}]") for i, p in enumerate(items))


def _arc(ctx: _Ctx, value: Any, key: str) -> tuple[tuple[float, float], ...]:
    t = _table(ctx, value, key, {"center", "radius", "start_deg", "end_deg"},
               {"center", "radius", "start_deg", "end_deg"})
    cx, cy = _point(ctx, t["center"], f"{key}.center")
    r = _num(ctx, t["radius"], f"{key}.radius", 0.5)
    a0 = math.radians(_num(ctx, t["start_deg"], f"{key}.start_deg"))
    a1 = math.radians(_num(ctx, t["end_deg"], f"{key}.end_deg"))
    if a0 == a1:
        raise ctx.fail(key, "start_deg and end_deg must differ")
    n = max(2, int(math.ceil(abs(a1 - a0) * r / 1.0)) + 1)
    return tuple(
        (round(cx + r * math.cos(a0 + (a1 - a0) * i / (n - 1)), 6),
         round(cy + r * math.sin(a0 + (a1 - a0) * i / (n - 1)), 6))
        for i in range(n)
    )


_LANE_KEYS = {"id", "points", "arc", "width_m", "speed_limit_mps", "successors", "junction"}


def _lane(ctx: _Ctx, d: Any, key: str) -> Lane:
    t = _table(ctx, d, key, _LANE_KEYS, {"id"})
    if ("points" in t) == ("arc" in t):
        raise ctx.fail(key, "give exactly one of 'points' or 'arc'")
    pts = (_points(ctx, t["points"], f"{key}.points", 2) if "points" in t
           else _arc(ctx, t["arc"], f"{key}.arc"))
    if polyline_length(pts) < 0.5:
        raise ctx.fail(f"{key}.points", "lane is shorter than 0.5 m")
    succ = tuple(_str(ctx, s, f"{key}.successors[{i}]")
                 for i, s in enumerate(_list(ctx, t.get("successors", []), f"{key}.successors")))
    return Lane(
        id=_str(ctx, t["id"], f"{key}.id"),
        centerline=pts,
        width_m=_num(ctx, t.get("width_m", 3.5), f"{key}.width_m", 2.0, 10.0),
        speed_limit_mps=_num(ctx, t.get("speed_limit_mps", 13.9), f"{key}.speed_limit_mps",
                             1.0, 40.0),
        successors=succ,
        is_junction=_bool(ctx, t.get("junction", False), f"{key}.junction"),
    )


def _policy(ctx: _Ctx, d: Any, key: str) -> LightPolicy:
    t = _table(ctx, d, key, {"mode", "color", "green_s", "yellow_s", "red_s", "offset_s"})
    return LightPolicy(
        mode=_str(ctx, t.get("mode", "fixed"), f"{key}.mode", LIGHT_MODES),
        color=_str(ctx, t.get("color", "green"), f"{key}.color", LIGHT_COLORS),
        green_s=_num(ctx, t.get("green_s", 10.0), f"{key}.green_s", 0.5, 600.0),
        yellow_s=_num(ctx, t.get("yellow_s", 3.0), f"{key}.yellow_s", 0.0, 60.0),
        red_s=_num(ctx, t.get("red_s", 10.0), f"{key}.red_s", 0.5, 600.0),
        offset_s=_num(ctx, t.get("offset_s", 0.0), f"{key}.offset_s", 0.0, 1200.0),
    )


def _light(ctx: _Ctx, d: Any, key: str, lanes: Mapping[str, Lane]) -> TrafficLight:
    t = _table(ctx, d, key, {"id", "stop_lane", "stop_s_m", "position", "facing_deg", "policy",
                             "enabled"}, {"id", "stop_lane", "stop_s_m"})
    lane_id = _str(ctx, t["stop_lane"], f"{key}.stop_lane")
    if lane_id not in lanes:
        raise ctx.fail(f"{key}.stop_lane", f"no lane {lane_id!r}")
    pts = lanes[lane_id].centerline
    s = _num(ctx, t["stop_s_m"], f"{key}.stop_s_m", 0.0, polyline_length(pts))
    x, y, h = point_at(pts, s)
    if "position" in t:
        pos = _point(ctx, t["position"], f"{key}.position")
    else:  # on the right of the lane, just beyond the stop line
        w = lanes[lane_id].width_m
        pos = (x + 2.0 * math.cos(h) + (w / 2 + 1.0) * math.sin(h),
               y + 2.0 * math.sin(h) - (w / 2 + 1.0) * math.cos(h))
    # a derived facing is kept at the precision the file format writes, so that a written
    # scenario reads back equal
    facing = math.radians(_num(ctx, t["facing_deg"], f"{key}.facing_deg", -360.0, 360.0)
                          if "facing_deg" in t else _r(math.degrees(_wrap(h + math.pi))))
    return TrafficLight(
        id=_str(ctx, t["id"], f"{key}.id"), position=pos, facing_rad=facing, stop_lane=lane_id,
        stop_s_m=s, policy=_policy(ctx, t.get("policy", {}), f"{key}.policy"),
        enabled=_bool(ctx, t.get("enabled", True), f"{key}.enabled"),
    )


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def _object(ctx: _Ctx, d: Any, key: str) -> StaticObject:
    t = _table(ctx, d, key, {"id", "kind", "position", "yaw_deg"}, {"id", "kind", "position"})
    return StaticObject(
        id=_str(ctx, t["id"], f"{key}.id"), kind=_str(ctx, t["kind"], f"{key}.kind", OBJECT_KINDS),
        position=_point(ctx, t["position"], f"{key}.position"),
        yaw_rad=math.radians(_num(ctx, t.get("yaw_deg", 0.0), f"{key}.yaw_deg", -360.0, 360.0)),
    )


def _area(ctx: _Ctx, d: Any, key: str) -> Area:
    t = _table(ctx, d, key, {"id", "kind", "polygon", "enabled", "height_m"},
               {"id", "kind", "polygon"})
    return Area(
        id=_str(ctx, t["id"], f"{key}.id"), kind=_str(ctx, t["kind"], f"{key}.kind", AREA_KINDS),
        polygon=_points(ctx, t["polygon"], f"{key}.polygon", 3),
        enabled=_bool(ctx, t.get("enabled", True), f"{key}.enabled"),
        height_m=_num(ctx, t.get("height_m", 8.0), f"{key}.height_m", 0.1, 300.0),
    )


def _weather(ctx: _Ctx, d: Any) -> Weather:
    t = _table(ctx, d, "weather", {"cloudiness", "precipitation", "fog_density",
                                   "sun_azimuth_deg", "sun_altitude_deg"})
    return Weather(
        cloudiness=_num(ctx, t.get("cloudiness", 0.0), "weather.cloudiness", 0.0, 100.0),
        precipitation=_num(ctx, t.get("precipitation", 0.0), "weather.precipitation", 0.0, 100.0),
        fog_density=_num(ctx, t.get("fog_density", 0.0), "weather.fog_density", 0.0, 100.0),
        sun_azimuth_deg=_num(ctx, t.get("sun_azimuth_deg", 0.0), "weather.sun_azimuth_deg",
                             0.0, 360.0),
        sun_altitude_deg=_num(ctx, t.get("sun_altitude_deg", 45.0), "weather.sun_altitude_deg",
                              -90.0, 90.0),
    )


def _route(ctx: _Ctx, value: Any, key: str, lanes: Mapping[str, Lane]) -> tuple[str, ...]:
    route = tuple(_str(ctx, r, f"{key}[{i}]") for i, r in enumerate(_list(ctx, value, key)))
    for i, lane_id in enumerate(route):
        if lane_id not in lanes:
            raise ctx.fail(f"{key}[{i}]", f"no lane {lane_id!r}")
        if i and lane_id not in lanes[route[i - 1]].successors:
            raise ctx.fail(f"{key}[{i}]", f"lane {lane_id!r} is not a successor of {route[i - 1]!r}")
    return route


def route_length(route: tuple[str, ...], lanes: Mapping[str, Lane]) -> float:
    return sum(polyline_length(lanes[r].centerline) for r in route)


def _actor(ctx: _Ctx, d: Any, key: str, lanes: Mapping[str, Lane]) -> Actor:
    t = _table(ctx, d, key, {"id", "kind", "model", "color", "route", "waypoints", "start_s_m",
                             "lateral_offset_m", "speed_profile", "speed_mps", "reactive",
                             "reactive_gap_m"}, {"id"})
    if ("route" in t) == ("waypoints" in t):
        raise ctx.fail(key, "give exactly one of 'route' or 'waypoints'")
    route = _route(ctx, t["route"], f"{key}.route", lanes) if "route" in t else ()
    if "route" in t and not route:
        raise ctx.fail(f"{key}.route", "route is empty")
    waypoints = _points(ctx, t["waypoints"], f"{key}.waypoints", 2) if "waypoints" in t else ()
    length = route_length(route, lanes) if route else polyline_length(waypoints)
    if "speed_profile" in t and "speed_mps" in t:
        raise ctx.fail(key, "give at most one of 'speed_profile' or 'speed_mps'")
    if "speed_profile" in t:
        knots = []
        for i, k in enumerate(_list(ctx, t["speed_profile"], f"{key}.speed_profile")):
            if not isinstance(k, list) or len(k) != 2:
                raise ctx.fail(f"{key}.speed_profile[{i}]", "expected a [time_s, speed_mps] pair")
            knots.append((_num(ctx, k[0], f"{key}.speed_profile[{i}][0]", 0.0),
                          _num(ctx, k[1], f"{key}.speed_profile[{i}][1]", 0.0, 40.0)))
        if not knots:
            raise ctx.fail(f"{key}.speed_profile", "needs at least one knot")
        if any(b[0] <= a[0] for a, b in zip(knots, knots[1:], strict=False)):
            raise ctx.fail(f"{key}.speed_profile", "times must increase strictly")
        profile = tuple(knots)
    else:
        profile = ((0.0, _num(ctx, t.get("speed_mps", 0.0), f"{key}.speed_mps", 0.0, 40.0)),)
    return Actor(
        id=_str(ctx, t["id"], f"{key}.id"),
        kind=_str(ctx, t.get("kind", "vehicle"), f"{key}.kind", ACTOR_KINDS),
        model=_str(ctx, t.get("model", "sedan"), f"{key}.model", VEHICLE_MODELS),
        color=_str(ctx, t.get("color", "white"), f"{key}.color", tuple(COLORS)),
        route=route, waypoints=waypoints,
        start_s_m=_num(ctx, t.get("start_s_m", 0.0), f"{key}.start_s_m", 0.0, length),
        lateral_offset_m=_num(ctx, t.get("lateral_offset_m", 0.0), f"{key}.lateral_offset_m",
                              -10.0, 10.0),
        speed_profile=profile,
        reactive=_bool(ctx, t.get("reactive", False), f"{key}.reactive"),
        reactive_gap_m=_num(ctx, t.get("reactive_gap_m", 4.0), f"{key}.reactive_gap_m", 0.5, 50),
    )


def _params(ctx: _Ctx, d: Any, key: str) -> tuple[tuple[str, float], ...]:
    """``[ego.params.MODULE]`` tables -> sorted ``(("module.name", value), ...)``: numbers only;
    whether they are the stack's parameters, in range, is the rollout's to check
    (:func:`rocas.rollout.check_params`), which knows the stacks."""
    if not isinstance(d, Mapping):
        raise ctx.fail(key, "expected a table of module tables")
    flat: dict[str, float] = {}
    for module, table in d.items():
        if not isinstance(table, Mapping):
            raise ctx.fail(f"{key}.{module}", "expected a table like [ego.params.planning]")
        for name, value in table.items():
            flat[f"{module}.{name}"] = _num(ctx, value, f"{key}.{module}.{name}")
    return tuple(sorted(flat.items()))


def _ego(ctx: _Ctx, d: Any, lanes: Mapping[str, Lane]) -> Ego:
    t = _table(ctx, d, "ego", {"route", "start_s_m", "start_lateral_m", "start_speed_mps",
                               "destination_s_m", "params", "stack"}, {"route"})
    route = _route(ctx, t["route"], "ego.route", lanes)
    if not route:
        raise ctx.fail("ego.route", "route is empty")
    length = route_length(route, lanes)
    dest = t.get("destination_s_m")
    stack = t.get("stack", DEFAULT_STACK)
    if not isinstance(stack, str) or not stack:
        raise ctx.fail("ego.stack", "expected the name of a registered stack")
    return Ego(
        route=route,
        start_s_m=_num(ctx, t.get("start_s_m", 0.0), "ego.start_s_m", 0.0, length),
        start_lateral_m=_num(ctx, t.get("start_lateral_m", 0.0), "ego.start_lateral_m", -5, 5),
        start_speed_mps=_num(ctx, t.get("start_speed_mps", 0.0), "ego.start_speed_mps", 0, 40),
        destination_s_m=None if dest is None else _num(ctx, dest, "ego.destination_s_m", 0,
                                                       length),
        params=_params(ctx, t.get("params", {}), "ego.params"),
        stack=stack,
    )


def _unique(ctx: _Ctx, items: list[Any], key: str) -> None:
    seen: set[str] = set()
    for i, item in enumerate(items):
        if item.id in seen:
            raise ctx.fail(f"{key}[{i}].id", f"duplicate id {item.id!r}")
        seen.add(item.id)


def scenario_from_dict(data: Mapping[str, Any], source: str = "<scenario>", *,
                       check_ranges: bool = True) -> Scenario:
    """Validate a parsed scenario document and build the :class:`Scenario`.

    ``check_ranges=False`` keeps every check but the numbers' ranges: a scenario rocas made
    by mutation (:mod:`rocas.pipeline.physical`) may start an actor past the end of its
    replayed track, which the simulator takes (the actor stands at the end), and an external
    stack must read back exactly what rocas simulates."""
    ctx = _Ctx(source, check_ranges)
    top = _table(ctx, data, "", {"format", "scenario", "weather", "lanes", "traffic_lights",
                                 "objects", "areas", "actors", "ego"}, {"scenario", "lanes", "ego"})
    if "format" in top and _int(ctx, top["format"], "format") != FORMAT_VERSION:
        raise ctx.fail("format", f"unsupported format {top['format']} (this rocas reads "
                                 f"{FORMAT_VERSION})")
    head = _table(ctx, top["scenario"], "scenario",
                  {"name", "description", "duration_s", "dt_s", "seed"}, {"name"})
    lanes = [_lane(ctx, d, f"lanes[{i}]") for i, d in enumerate(_list(ctx, top["lanes"], "lanes"))]
    if not lanes:
        raise ctx.fail("lanes", "a map needs at least one lane")
    _unique(ctx, lanes, "lanes")
    by_id = {lane.id: lane for lane in lanes}
    for i, lane in enumerate(lanes):
        for j, succ in enumerate(lane.successors):
            if succ not in by_id:
                raise ctx.fail(f"lanes[{i}].successors[{j}]", f"no lane {succ!r}")
    lights = [_light(ctx, d, f"traffic_lights[{i}]", by_id)
              for i, d in enumerate(_list(ctx, top.get("traffic_lights", []), "traffic_lights"))]
    objects = [_object(ctx, d, f"objects[{i}]")
               for i, d in enumerate(_list(ctx, top.get("objects", []), "objects"))]
    areas = [_area(ctx, d, f"areas[{i}]")
             for i, d in enumerate(_list(ctx, top.get("areas", []), "areas"))]
    actors = [_actor(ctx, d, f"actors[{i}]", by_id)
              for i, d in enumerate(_list(ctx, top.get("actors", []), "actors"))]
    for items, key in ((lights, "traffic_lights"), (objects, "objects"), (areas, "areas"),
                       (actors, "actors")):
        _unique(ctx, items, key)
    dt = _num(ctx, head.get("dt_s", 0.05), "scenario.dt_s", 0.01, 0.1)
    return Scenario(
        name=_str(ctx, head["name"], "scenario.name"),
        description=_str(ctx, head.get("description", ""), "scenario.description"),
        duration_s=_num(ctx, head.get("duration_s", 30.0), "scenario.duration_s", dt, 600.0),
        dt_s=dt,
        seed=_int(ctx, head.get("seed", 0), "scenario.seed", 0),
        lanes=tuple(lanes), traffic_lights=tuple(lights), objects=tuple(objects),
        areas=tuple(areas), actors=tuple(actors),
        weather=_weather(ctx, top.get("weather", {})),
        ego=_ego(ctx, top["ego"], by_id),
    )


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file (a catalog file's ``[ground_truth]`` table is
    left out)."""
    from rocas._limits import MAX_DEPTH, check_depth, read_text_limited
    from rocas.errors import InputError

    p = Path(path)
    try:  # bounded: a scenario may come from someone else (or be /dev/zero)
        text = read_text_limited(p, what="scenario file")
    except InputError as exc:
        raise ScenarioError(exc.message, exc.hint) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{p}: not valid TOML: {exc}") from None
    except RecursionError:
        raise ScenarioError(f"{p}: nested more than {MAX_DEPTH} levels deep") from None
    try:
        check_depth(data, origin=str(p))
    except InputError as exc:
        raise ScenarioError(exc.message, exc.hint) from None
    # a catalog entry is a scenario file plus the known answer, which is no part of the
    # scenario (rocas.catalog reads and checks it)
    if isinstance(data.get("ground_truth"), dict):
        del data["ground_truth"]
    return scenario_from_dict(data, source=str(p))


def example_names() -> list[str]:
    """Names of the example scenarios shipped with rocas."""
    root = resources.files("rocas.scenarios") / "examples"
    return sorted(f.name[:-5] for f in root.iterdir() if f.name.endswith(".toml"))


def load_example(name: str) -> Scenario:
    """Load a shipped example scenario by name (see :func:`example_names`)."""
    root = resources.files("rocas.scenarios") / "examples"
    f = root / f"{name}.toml"
    if not f.is_file():
        raise ScenarioError(f"no example scenario {name!r}",
                            f"available: {', '.join(example_names())}")
    return scenario_from_dict(tomllib.loads(f.read_text(encoding="utf-8")),
                              source=f"examples/{name}.toml")


def resolve_scenario(spec: str) -> Scenario:
    """A path to a TOML file, or the name of a shipped example."""
    p = Path(spec)
    if p.suffix == ".toml" or p.exists():
        return load_scenario(p)
    return load_example(spec)


def _r(x: float) -> float:
    return float(round(x, 9))


def scenario_to_dict(s: Scenario) -> dict[str, Any]:
    """The scenario in the file format (points spelled out), for JSON/TOML output."""
    def obj(o: StaticObject) -> dict[str, Any]:
        return {"id": o.id, "kind": o.kind, "position": list(o.position),
                "yaw_deg": _r(math.degrees(o.yaw_rad))}

    def actor(a: Actor) -> dict[str, Any]:
        d: dict[str, Any] = {"id": a.id, "kind": a.kind, "model": a.model, "color": a.color}
        if a.route:
            d["route"] = list(a.route)
        else:
            d["waypoints"] = [list(p) for p in a.waypoints]
        d.update(start_s_m=a.start_s_m, lateral_offset_m=a.lateral_offset_m,
                 speed_profile=[list(k) for k in a.speed_profile], reactive=a.reactive,
                 reactive_gap_m=a.reactive_gap_m)
        return d

    params: dict[str, dict[str, float]] = {}
    for name, value in s.ego.params:
        module, _, pname = name.partition(".")
        params.setdefault(module, {})[pname] = value
    ego: dict[str, Any] = {"route": list(s.ego.route), "start_s_m": s.ego.start_s_m,
                           "start_lateral_m": s.ego.start_lateral_m,
                           "start_speed_mps": s.ego.start_speed_mps, "params": params}
    if s.ego.destination_s_m is not None:
        ego["destination_s_m"] = s.ego.destination_s_m
    if s.ego.stack != DEFAULT_STACK:  # the format's default is left out (files hash as before)
        ego["stack"] = s.ego.stack
    w = s.weather
    return {
        "format": FORMAT_VERSION,
        "scenario": {"name": s.name, "description": s.description, "duration_s": s.duration_s,
                     "dt_s": s.dt_s, "seed": s.seed},
        "weather": {"cloudiness": w.cloudiness, "precipitation": w.precipitation,
                    "fog_density": w.fog_density, "sun_azimuth_deg": w.sun_azimuth_deg,
                    "sun_altitude_deg": w.sun_altitude_deg},
        "lanes": [{"id": ln.id, "points": [list(p) for p in ln.centerline], "width_m": ln.width_m,
                   "speed_limit_mps": ln.speed_limit_mps, "successors": list(ln.successors),
                   "junction": ln.is_junction} for ln in s.lanes],
        "traffic_lights": [
            {"id": tl.id, "stop_lane": tl.stop_lane, "stop_s_m": tl.stop_s_m,
             "position": list(tl.position), "facing_deg": _r(math.degrees(tl.facing_rad)),
             "enabled": tl.enabled,
             "policy": {"mode": tl.policy.mode, "color": tl.policy.color,
                        "green_s": tl.policy.green_s, "yellow_s": tl.policy.yellow_s,
                        "red_s": tl.policy.red_s, "offset_s": tl.policy.offset_s}}
            for tl in s.traffic_lights],
        "objects": [obj(o) for o in s.objects],
        "areas": [{"id": a.id, "kind": a.kind, "polygon": [list(p) for p in a.polygon],
                   "enabled": a.enabled, "height_m": a.height_m} for a in s.areas],
        "actors": [actor(a) for a in s.actors],
        "ego": ego,
    }


def world_to_dict(s: Scenario) -> dict[str, Any]:
    """The static world only (map, map entities, weather): the ``rocas/world.json`` attachment."""
    d = scenario_to_dict(s)
    return {k: d[k] for k in ("format", "scenario", "weather", "lanes", "traffic_lights",
                              "objects", "areas")}


