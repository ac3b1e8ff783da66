"""A highway-env scene as frozen, typed data: which environment, which vehicles where.

A scene fixes everything highway-env would otherwise draw at random: the environment and the
subset of its configuration rocas may set, each vehicle's lane, position on it, speed, target
speed, class, destination and driver constants, and the duration. With a seed
(:func:`rocas.stacks.highway.world.build`) it builds the same simulation every time.
Lanes are highway-env lane indices written ``"from>to>id"`` (``"0>1>2"``: the third lane of the
straight highway's first segment).
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from rocas.errors import ScenarioError
from rocas.stacks.highway.params import parameters

#: the environments a scene may name
ENVIRONMENTS = ("highway-v0", "merge-v0", "roundabout-v0", "intersection-v0")
#: vehicle classes: highway-env's behaviour models, and "still" (kinematics only, no driver)
KINDS = ("idm", "linear", "aggressive", "defensive", "still")
#: environment configuration keys a scene may set (integers or reals)
CONFIG_KEYS = ("lanes_count",)
#: driver constants another vehicle may override (the ego's planning constants)
DRIVER_CONSTANTS = tuple(p.name for p in parameters() if p.module == "planning")

Lane = tuple[str, str, int]


def parse_lane(text: str) -> Lane:
    """``"a>b>1"`` -> ``("a", "b", 1)``."""
    parts = str(text).split(">")
    if len(parts) != 3 or not parts[2].lstrip("-").isdigit():
        raise ScenarioError(f"lane {text!r}: expected 'from>to>id'", "e.g. '0>1>2'")
    return parts[0], parts[1], int(parts[2])


def lane_text(lane: Lane) -> str:
    return f"{lane[0]}>{lane[1]}>{lane[2]}"


@dataclass(frozen=True)
class VehicleSpec:
    """One vehicle's initial state and behaviour.

    Attributes:
        lane: highway-env lane index.
        s_m: longitudinal position on that lane [m].
        speed_mps: initial speed [m/s].
        target_speed_mps: the speed its driver wants [m/s] (None: its initial speed).
        kind: one of :data:`KINDS` (the ego is always the IDM driver under test).
        destination: road-network node to route to ("" keeps highway-env's lane following).
        driver: constant overrides for this vehicle's driver, ``((name, value), ...)``.
        lane_change: whether MOBIL may change its lane.
    """

    lane: Lane
    s_m: float
    speed_mps: float
    target_speed_mps: float | None = None
    kind: str = "idm"
    destination: str = ""
    driver: tuple[tuple[str, float], ...] = ()
    lane_change: bool = True

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ScenarioError(f"vehicle kind {self.kind!r} is not one of {', '.join(KINDS)}")
        for name, _ in self.driver:
            if name not in DRIVER_CONSTANTS:
                raise ScenarioError(f"driver constant {name!r} is not one of "
                                    f"{', '.join(DRIVER_CONSTANTS)}")
        if not -1.0 <= self.speed_mps <= 60.0:
            raise ScenarioError(f"vehicle speed {self.speed_mps:g} m/s is out of [-1, 60]")

    def with_driver(self, name: str, value: float) -> VehicleSpec:
        """The same vehicle with one driver constant set."""
        rest = tuple((n, v) for n, v in self.driver if n != name)
        return replace(self, driver=tuple(sorted((*rest, (name, float(value))))))


@dataclass(frozen=True)
class Scene:
    """A complete highway-env scene.

    Attributes:
        name: a short identifier.
        env_id: one of :data:`ENVIRONMENTS`.
        ego: the vehicle the stack drives.
        others: every other vehicle, in id order (id 1, 2, ...).
        duration_s: simulated time [s].
        frequency_hz: highway-env's simulation frequency [Hz] (one tick = one message).
        config: environment configuration, ``((key, value), ...)`` over :data:`CONFIG_KEYS`.
    """

    name: str
    env_id: str
    ego: VehicleSpec
    others: tuple[VehicleSpec, ...] = ()
    duration_s: float = 15.0
    frequency_hz: float = 15.0
    config: tuple[tuple[str, float], ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        if self.env_id not in ENVIRONMENTS:
            raise ScenarioError(f"environment {self.env_id!r} is not one of "
                                f"{', '.join(ENVIRONMENTS)}")
        for key, _ in self.config:
            if key not in CONFIG_KEYS:
                raise ScenarioError(f"config key {key!r} is not one of {', '.join(CONFIG_KEYS)}")
        if not 0.5 <= self.duration_s <= 120.0:
            raise ScenarioError(f"duration {self.duration_s:g} s is out of [0.5, 120]")
        if not 5.0 <= self.frequency_hz <= 50.0:
            raise ScenarioError(f"frequency {self.frequency_hz:g} Hz is out of [5, 50]")

    @property
    def ticks(self) -> int:
        """Simulation steps in the scene."""
        return int(round(self.duration_s * self.frequency_hz))

    def with_other(self, index: int, vehicle: VehicleSpec) -> Scene:
        others = list(self.others)
        others[index] = vehicle
        return replace(self, others=tuple(others))


def vehicle_from_dict(d: Mapping[str, Any], where: str) -> VehicleSpec:
    known = {"lane", "s", "speed", "target_speed", "kind", "destination", "driver", "lane_change"}
    unknown = set(d) - known
    if unknown:
        raise ScenarioError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}")
    try:
        return VehicleSpec(
            lane=parse_lane(d["lane"]), s_m=float(d["s"]), speed_mps=float(d["speed"]),
            target_speed_mps=None if d.get("target_speed") is None else float(d["target_speed"]),
            kind=str(d.get("kind", "idm")), destination=str(d.get("destination", "")),
            driver=tuple(sorted((str(k), float(v)) for k, v in d.get("driver", {}).items())),
            lane_change=bool(d.get("lane_change", True)))
    except KeyError as exc:
        raise ScenarioError(f"{where}: missing key {exc}") from None
    except (TypeError, ValueError) as exc:
        raise ScenarioError(f"{where}: {exc}") from None


def vehicle_to_dict(v: VehicleSpec) -> dict[str, Any]:
    d: dict[str, Any] = {"lane": lane_text(v.lane), "s": v.s_m, "speed": v.speed_mps,
                         "kind": v.kind, "lane_change": v.lane_change}
    if v.target_speed_mps is not None:
        d["target_speed"] = v.target_speed_mps
    if v.destination:
        d["destination"] = v.destination
    if v.driver:
        d["driver"] = dict(v.driver)
    return d


def scene_from_dict(d: Mapping[str, Any], where: str = "scene") -> Scene:
    """A scene from its TOML/JSON form (``[ego]``, ``[[others]]``, ``[config]``)."""
    try:
        return Scene(
            name=str(d["name"]), env_id=str(d["env"]),
            ego=vehicle_from_dict(d["ego"], f"{where}: ego"),
            others=tuple(vehicle_from_dict(o, f"{where}: others[{i}]")
                         for i, o in enumerate(d.get("others", []))),
            duration_s=float(d.get("duration", 15.0)),
            frequency_hz=float(d.get("frequency", 15.0)),
            config=tuple(sorted((str(k), float(v)) for k, v in d.get("config", {}).items())))
    except KeyError as exc:
        raise ScenarioError(f"{where}: missing key {exc}") from None


def scene_to_dict(s: Scene) -> dict[str, Any]:
    return {"name": s.name, "env": s.env_id, "duration": s.duration_s,
            "frequency": s.frequency_hz, "config": dict(s.config),
            "ego": vehicle_to_dict(s.ego), "others": [vehicle_to_dict(o) for o in s.others]}


def load_scene(path: str | Path) -> Scene:
    """Read a scene from a TOML file (a catalog entry's ``[scene]`` table or a whole file)."""
    try:
        data = tomllib.loads(Path(path).read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ScenarioError(f"{path}: {exc}") from None
    return scene_from_dict(data.get("scene", data), str(path))
