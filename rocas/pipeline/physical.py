"""Phase II: physical mutation (section 5.1, Table 1).

The mutation space of the paper's Table 1 over a scenario's entities:

| entity | properties |
|---|---|
| vehicles | model, colour, location (along / across its route), speed |
| cyclists, pedestrians | location (along / across), speed |
| cones, boxes | location (x, y), rotation |
| buildings, vegetation | enabled |
| traffic lights | policy, enabled |
| weather | cloudiness, precipitation, fog density, sun azimuth, sun altitude |

Actors follow their routes, so their rotation is the route's tangent and is not a free
property; a vehicle's "location" is its start position along the route and its lateral
offset. Its "speed" is ``speed_delta_mps``, added to every speed of its profile (negative
values slow it, to a stop at most; positive ones lift it, so an actor that creeps at 0.3 m/s can
drive at walking pace or faster, which no scaling of its profile could do).

The change holds from the start. A speed change from a later time was tried (2026-11-25) and
left out: an actor the ego can see that moves otherwise from some time on makes
/perception/obstacles the first channel to change, so Algorithm 1 names perception whatever
module decided the accident (A4 did so); changed from the start, the actor's difference is the
channels' baseline and the first change point is the ADS's decision.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rocas.scenarios.model import COLORS, VEHICLE_MODELS, LightPolicy, Scenario
from rocas.search.space import Mutation, MutationSpace, Value, Variable

#: traffic light policies a search may switch to ("original" keeps the scenario's)
LIGHT_POLICIES = ("original", "fixed_green", "fixed_red", "fixed_yellow", "off")
ALONG_M, ACROSS_M, OBJECT_SHIFT_M = 15.0, 2.0, 3.0
#: how far a speed may be lifted at least [m/s] (or half the actor's top speed, if more)
SPEED_LIFT_MPS = 3.0
#: the values of a real property the screening tries, as fractions of its range
SCREEN_FRACTIONS = (0.0, 0.25, 0.75, 1.0)
#: the words a documented property (Table 1's, as a catalog's ``trigger_property`` names it)
#: may use for each variable below, by the variable's last name part; a documented property
#: may also name the part itself (``lateral_offset_m``)
PROPERTY_WORDS: dict[str, tuple[str, ...]] = {
    "model": ("model",), "color": ("color", "colour"),
    "start_s_m": ("location", "position along"),
    "lateral_offset_m": ("location", "lateral position", "position across"),
    "speed_delta_mps": ("speed",),
    "x": ("location", "position"), "y": ("location", "position"),
    "yaw_deg": ("rotation", "heading"),
    "enabled": ("enabled",), "policy": ("policy",),
    "cloudiness": ("cloudiness",), "precipitation": ("precipitation",),
    "fog_density": ("fog density", "fog"), "sun_azimuth_deg": ("sun azimuth",),
    "sun_altitude_deg": ("sun altitude",),
}


def physical_space(scenario: Scenario) -> MutationSpace:
    """The mutation space of ``scenario``'s entities (Table 1)."""
    v: list[Variable] = []
    for a in scenario.actors:
        p = f"actor.{a.id}"
        if a.kind == "vehicle":
            v.append(Variable(f"{p}.model", a.id, "enum", a.model, choices=VEHICLE_MODELS))
            v.append(Variable(f"{p}.color", a.id, "enum", a.color, choices=tuple(COLORS)))
        v.append(Variable(f"{p}.start_s_m", a.id, "real", a.start_s_m,
                          low=max(0.0, a.start_s_m - ALONG_M), high=a.start_s_m + ALONG_M, unit="m"))
        v.append(Variable(f"{p}.lateral_offset_m", a.id, "real", a.lateral_offset_m,
                          low=a.lateral_offset_m - ACROSS_M, high=a.lateral_offset_m + ACROSS_M,
                          unit="m"))
        top = max(s for _, s in a.speed_profile)
        v.append(Variable(f"{p}.speed_delta_mps", a.id, "real", 0.0, low=-top,
                          high=max(SPEED_LIFT_MPS, 0.5 * top), unit="m/s"))
    for o in scenario.objects:
        p = f"object.{o.id}"
        x, y = o.position
        v.append(Variable(f"{p}.x", o.id, "real", x, low=x - OBJECT_SHIFT_M, high=x + OBJECT_SHIFT_M,
                          unit="m"))
        v.append(Variable(f"{p}.y", o.id, "real", y, low=y - OBJECT_SHIFT_M, high=y + OBJECT_SHIFT_M,
                          unit="m"))
        v.append(Variable(f"{p}.yaw_deg", o.id, "real", math.degrees(o.yaw_rad),
                          low=math.degrees(o.yaw_rad) - 180, high=math.degrees(o.yaw_rad) + 180,
                          unit="deg"))
    for ar in scenario.areas:
        v.append(Variable(f"area.{ar.id}.enabled", ar.id, "bool", ar.enabled))
    for tl in scenario.traffic_lights:
        v.append(Variable(f"light.{tl.id}.policy", tl.id, "enum", "original", choices=LIGHT_POLICIES))
        v.append(Variable(f"light.{tl.id}.enabled", tl.id, "bool", tl.enabled))
    w = scenario.weather
    for name, value, lo, hi in (("cloudiness", w.cloudiness, 0, 100),
                                ("precipitation", w.precipitation, 0, 100),
                                ("fog_density", w.fog_density, 0, 100),
                                ("sun_azimuth_deg", w.sun_azimuth_deg, 0, 360),
                                ("sun_altitude_deg", w.sun_altitude_deg, -90, 90)):
        v.append(Variable(f"weather.{name}", "weather", "real", float(value), low=lo, high=hi))
    return MutationSpace(tuple(v))


def apply_physical(scenario: Scenario, mutation: Mutation) -> Scenario:
    """The scenario with ``mutation`` applied (the original is not changed)."""
    if not mutation.values:
        return scenario
    by_entity: dict[tuple[str, str], dict[str, Value]] = {}
    weather_changes: dict[str, float] = {}
    for name, value in mutation.values.items():
        kind, rest = name.split(".", 1)
        if kind == "weather":
            weather_changes[rest] = float(value)  # type: ignore[arg-type]
            continue
        ident, prop = rest.rsplit(".", 1)
        by_entity.setdefault((kind, ident), {})[prop] = value
    actors = []
    for a in scenario.actors:
        ch = by_entity.get(("actor", a.id), {})
        if ch:
            delta = float(ch.pop("speed_delta_mps", 0.0))
            if delta:
                ch["speed_profile"] = shifted_profile(a.speed_profile, delta)
            a = dataclasses.replace(a, **ch)
        actors.append(a)
    objects = []
    for o in scenario.objects:
        ch = by_entity.get(("object", o.id), {})
        if ch:
            x, y = o.position
            o = dataclasses.replace(
                o, position=(float(ch.get("x", x)), float(ch.get("y", y))),
                yaw_rad=math.radians(float(ch["yaw_deg"])) if "yaw_deg" in ch else o.yaw_rad)
        objects.append(o)
    areas = [dataclasses.replace(ar, **by_entity[("area", ar.id)]) if ("area", ar.id) in by_entity
             else ar for ar in scenario.areas]
    lights = []
    for tl in scenario.traffic_lights:
        ch = by_entity.get(("light", tl.id), {})
        if "policy" in ch and ch["policy"] != "original":
            if ch["policy"] == "off":
                tl = dataclasses.replace(tl, policy=LightPolicy(mode="fixed", color="off"))
            else:
                tl = dataclasses.replace(tl, policy=LightPolicy(mode="fixed",
                                                                color=str(ch["policy"])[6:]))
        if "enabled" in ch:
            tl = dataclasses.replace(tl, enabled=bool(ch["enabled"]))
        lights.append(tl)
    weather = dataclasses.replace(scenario.weather, **weather_changes)
    return dataclasses.replace(scenario, actors=tuple(actors), objects=tuple(objects),
                               areas=tuple(areas), traffic_lights=tuple(lights), weather=weather)


def shifted_profile(profile: tuple[tuple[float, float], ...], delta_mps: float
                    ) -> tuple[tuple[float, float], ...]:
    """``profile`` with ``delta_mps`` added to every speed (never below 0)."""
    return tuple((t, max(0.0, v + delta_mps)) for t, v in profile)


def screening_mutants(space: MutationSpace) -> list[Mutation]:
    """Every single-property mutant the physical screening simulates, in space order: each
    other enum choice, the flipped bool, each real at SCREEN_FRACTIONS of its range (values
    equal to the original are left out)."""
    out: list[Mutation] = []
    for var in space.variables:
        if var.kind == "enum":
            values: list[Value] = [c for c in var.choices if c != var.original]
        elif var.kind == "bool":
            values = [not var.original]
        else:
            values = list(dict.fromkeys(var.decode(f) for f in SCREEN_FRACTIONS))
            values = [x for x in values if var.change(x) > 0]
        out += [Mutation({var.name: x}) for x in values]
    return out


def is_weather(mutation: Mutation) -> bool:
    """Whether a mutation changes the weather (every channel at once)."""
    return any(n.startswith("weather.") for n in mutation.values)


def entity_positions(scenario: Scenario, actors_xy_at: np.ndarray
                     ) -> dict[str, tuple[float, float] | None]:
    """World position of each entity at the accident (None for weather), for f1.

    Args:
        actors_xy_at: (A, 2) actor positions at the accident tick.
    """
    pos: dict[str, tuple[float, float] | None] = {"weather": None}
    for i, a in enumerate(scenario.actors):
        pos[a.id] = (float(actors_xy_at[i, 0]), float(actors_xy_at[i, 1]))
    for o in scenario.objects:
        pos[o.id] = (float(o.position[0]), float(o.position[1]))
    for ar in scenario.areas:
        pts = np.asarray(ar.polygon, dtype=float)
        pos[ar.id] = (float(pts[:, 0].mean()), float(pts[:, 1].mean()))
    for tl in scenario.traffic_lights:
        pos[tl.id] = (float(tl.position[0]), float(tl.position[1]))
    return pos


def mutated_entities(space: MutationSpace, mutation: Mutation) -> list[str]:
    """Entities touched by a mutation, in space order."""
    names = set(mutation.values)
    return list(dict.fromkeys(v.entity for v in space.variables if v.name in names))


def describe(space: MutationSpace, mutation: Mutation) -> list[dict[str, Value]]:
    """``[{name, original, mutated}]`` for a report."""
    return [{"name": n, "original": space.variable(n).original, "mutated": mutation.values[n]}
            for n in mutation.names]


def entity_kinds(scenario: Scenario) -> dict[str, str]:
    kinds = {a.id: a.kind for a in scenario.actors}
    kinds |= {o.id: o.kind for o in scenario.objects}
    kinds |= {ar.id: ar.kind for ar in scenario.areas}
    kinds |= {tl.id: "traffic_light" for tl in scenario.traffic_lights}
    kinds["weather"] = "weather"
    return kinds
