"""Build a scene into a highway-env environment, step it, judge it.

highway-env's environment class builds the road network (and, for merge, its obstacle);
rocas then replaces the randomly drawn vehicles with the scene's, seeds the road's random
generator from rocas's seed, and steps highway-env's own road (``road.act()`` then
``road.step(dt)``, what ``AbstractEnv._simulate`` does per simulation frame) until the
duration ends or the ego crashes. Collisions are highway-env's own check.
"""

from __future__ import annotations

import hashlib
import importlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas.errors import ScenarioError, UsageError
from rocas.stacks.base import StackParams
from rocas.stacks.highway.driver import DecisionFrame, ego_class
from rocas.stacks.highway.hwenv import require
from rocas.stacks.highway.ideal import SUBSTITUTES, ideal_control_class
from rocas.stacks.highway.params import constant_name, parameters
from rocas.stacks.highway.scene import Scene, VehicleSpec

_ENV_CLASSES = {"highway-v0": ("highway_env.envs.highway_env", "HighwayEnv"),
                "merge-v0": ("highway_env.envs.merge_env", "MergeEnv"),
                "roundabout-v0": ("highway_env.envs.roundabout_env", "RoundaboutEnv"),
                "intersection-v0": ("highway_env.envs.intersection_env", "IntersectionEnv")}
_KIND_CLASSES = {"idm": ("highway_env.vehicle.behavior", "IDMVehicle"),
                 "linear": ("highway_env.vehicle.behavior", "LinearVehicle"),
                 "aggressive": ("highway_env.vehicle.behavior", "AggressiveVehicle"),
                 "defensive": ("highway_env.vehicle.behavior", "DefensiveVehicle"),
                 "still": ("highway_env.vehicle.kinematics", "Vehicle")}
#: added to rocas's seed for the road's generator (routes at junctions, lane choices)
ROAD_SEED_STREAM = 39


@dataclass
class Simulation:
    """A built scene: highway-env's environment, its road, the ego and the others (id order)."""

    scene: Scene
    env: Any
    road: Any
    ego: Any
    others: list[Any]
    dt_s: float


@dataclass(frozen=True)
class RunResult:
    """One simulated run.

    Attributes:
        scene: the scene simulated; seed: rocas's seed; params: the ego driver's parameters.
        times: (K,) tick times [s] (K ticks simulated; the last is the crash tick, if any).
        ego: (K, 5) ego x, y [m], heading [rad], speed [m/s], acceleration command [m/s^2]
            at each tick's start.
        others: (K, A, 4) other vehicles' x, y [m], heading [rad], speed [m/s].
        collided: the ego crashed (highway-env's collision check).
        collision_t_s: when the crash was detected [s] (None without one).
        collided_with: id of the vehicle or object it hit (-1 none, 0 an object on the road).
        off_road: the ego left the road (highway-env's ``on_road``) before any crash.
        off_road_t_s: when [s] (None if never).
        min_ttc_s: smallest time to collision with the front vehicle in the ego's lane [s]
            (inf when it never closed in).
        min_margin_m: smallest clearance between the ego's box and another vehicle's or a road
            object's, in the ego's frame (:func:`_margin`) [m].
        steering: (K,) the ego's steering command [rad] at each tick (for the view; not in
            :meth:`digest`, which the trajectories it steers already determine).
    """

    scene: Scene
    seed: int
    params: StackParams
    times: np.ndarray
    ego: np.ndarray
    others: np.ndarray
    collided: bool
    collision_t_s: float | None
    collided_with: int
    off_road: bool
    off_road_t_s: float | None
    min_ttc_s: float
    min_margin_m: float
    steering: np.ndarray

    @property
    def accident(self) -> bool:
        """A collision or leaving the road."""
        return self.collided or self.off_road

    @property
    def accident_t_s(self) -> float | None:
        ts = [t for t in (self.collision_t_s, self.off_road_t_s) if t is not None]
        return min(ts) if ts else None

    def digest(self) -> str:
        """SHA-256 of the trajectories' bytes (bit-for-bit comparison)."""
        h = hashlib.sha256()
        for a in (self.times, self.ego, self.others):
            h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
        return h.hexdigest()

    def constraint(self) -> float:
        """Graded "accident" for a search: > 0 an accident (larger the earlier), <= 0 safe
        (more negative the wider the smallest margin, capped at 5 m)."""
        t = self.accident_t_s
        if t is not None:
            return 1.0 + (self.scene.duration_s - t) / self.scene.duration_s
        return -0.01 - min(max(self.min_margin_m, 0.0), 5.0) / 5.0


def _attr(table: Mapping[str, tuple[str, str]], key: str) -> Any:
    module, name = table[key]
    return getattr(importlib.import_module(module), name)


def _env_config(scene: Scene) -> dict[str, Any]:
    hz = int(scene.frequency_hz) if float(scene.frequency_hz).is_integer() else scene.frequency_hz
    cfg: dict[str, Any] = {"simulation_frequency": hz, "policy_frequency": 1,
                           "duration": scene.duration_s}
    if scene.env_id == "highway-v0":
        cfg.update(vehicles_count=0, lanes_count=4)
    if scene.env_id == "intersection-v0":
        cfg.update(initial_vehicle_count=0, spawn_probability=0.0)
    cfg.update({k: int(v) if float(v).is_integer() else v for k, v in scene.config})
    return cfg


def _place(road: Any, cls: type, spec: VehicleSpec, vid: int) -> Any:
    try:
        lane = road.network.get_lane(spec.lane)
    except (KeyError, IndexError):
        raise ScenarioError(f"vehicle {vid}: lane {spec.lane} is not on this road") from None
    kwargs: dict[str, Any] = {"heading": lane.heading_at(spec.s_m), "speed": spec.speed_mps}
    if spec.kind != "still" or vid == 0:
        kwargs["target_speed"] = (spec.speed_mps if spec.target_speed_mps is None
                                  else spec.target_speed_mps)
        kwargs["enable_lane_change"] = spec.lane_change
    v = cls(road, lane.position(spec.s_m, 0.0), **kwargs)
    if spec.destination and spec.kind != "still":  # a driverless vehicle keeps its lane
        v.plan_route_to(spec.destination)
    v.rocas_id = vid
    return v


def build(scene: Scene, params: StackParams, seed: int,
          substitute: str | None = None) -> Simulation:
    """The scene in highway-env, with the ego driven by ``params`` (full names -> values);
    ``substitute`` ``"control"``: with its control replaced by ideal control
    (:mod:`rocas.stacks.highway.ideal`)."""
    require()
    if substitute is not None and substitute not in SUBSTITUTES:
        raise UsageError(f"the highway ego has no ideal {substitute!r} module",
                         f"substitutable: {', '.join(SUBSTITUTES)}")
    env = _attr(_ENV_CLASSES, scene.env_id)(config=_env_config(scene))
    env.reset(seed=int(seed))
    road = env.road
    road.vehicles = []
    road.np_random = np.random.default_rng([int(seed), ROAD_SEED_STREAM])
    constants = {constant_name(n): params[n] for n in params}
    ego_cls = (ego_class(constants) if substitute is None
               else ideal_control_class(constants, 1.0 / scene.frequency_hz))
    ego = _place(road, ego_cls, scene.ego, 0)
    others = []
    for i, spec in enumerate(scene.others, start=1):
        base = _attr(_KIND_CLASSES, spec.kind)
        cls = type(f"{base.__name__}Rocas", (base,), dict(spec.driver)) if spec.driver else base
        others.append(_place(road, cls, spec, i))
    road.vehicles = [ego, *others]
    env.vehicle = ego
    return Simulation(scene, env, road, ego, others, 1.0 / scene.frequency_hz)


#: called each tick with (tick, t [s], simulation, the ego's decision) before the road steps
TickObserver = Callable[[int, float, Simulation, DecisionFrame], None]


def simulate(scene: Scene, params: Mapping[str, float] | StackParams | None = None,
             seed: int = 0, observer: TickObserver | None = None,
             substitute: str | None = None) -> RunResult:
    """Run ``scene`` with the ego driver's parameters ``params`` (overrides of the defaults)
    and judge it; ``substitute`` as for :func:`build`."""
    p = params if isinstance(params, StackParams) else StackParams(parameters(), params or {})
    sim = build(scene, p, seed, substitute)
    road, ego, dt = sim.road, sim.ego, sim.dt_s
    a = len(sim.others)
    times, ego_rows, other_rows, steering = [], [], [], []
    collided, off_road = False, False
    t_collision = t_off = None
    hit = -1
    min_ttc, min_margin = math.inf, math.inf
    for tick in range(scene.ticks):
        t = tick * dt
        road.act()
        frame = ego.rocas_frame
        if observer is not None:
            observer(tick, t, sim, frame)
        times.append(t)
        ego_rows.append((ego.position[0], ego.position[1], ego.heading, ego.speed,
                         frame.acceleration_mps2))
        steering.append(frame.steering_rad)
        other_rows.append([(v.position[0], v.position[1], v.heading, v.speed)
                           for v in sim.others])
        min_ttc = min(min_ttc, _ttc(ego, frame, sim.others))
        min_margin = min(min_margin, _margin(ego, [*sim.others, *road.objects]))
        road.step(dt)
        if ego.crashed:
            collided, t_collision, hit = True, t + dt, _hit(ego, sim)
            break
        if not ego.on_road:
            off_road, t_off = True, t + dt
            break
    return RunResult(scene, int(seed), p, np.array(times),
                     np.array(ego_rows, dtype=np.float64).reshape(-1, 5),
                     np.array(other_rows, dtype=np.float64).reshape(len(times), a, 4),
                     collided, t_collision, hit, off_road, t_off, float(min_ttc), float(min_margin),
                     np.array(steering, dtype=np.float64))


def accident_kind(r: Any) -> tuple[bool, int] | None:
    """What a run's accident was: (off the road, partner id: -1 none, 0 a road object), None
    without one. ``r``: a :class:`RunResult` or anything with its accident fields."""
    if not r.accident:
        return None
    return (bool(r.off_road), -1 if r.off_road else int(r.collided_with))


def avoids(fixed: Any, unfixed: Any) -> bool:
    """``fixed`` avoids ``unfixed``'s accident: it has none, or another one (another kind or
    partner) no earlier than the unfixed one's time; a different drive may meet a different
    hazard later, which is not this accident. Both are :class:`RunResult`-like (module
    substitution's runs too), ``unfixed`` with an accident."""
    if not fixed.accident:
        return True
    return accident_kind(fixed) != accident_kind(unfixed) and (
        (fixed.accident_t_s or 0.0) >= (unfixed.accident_t_s or 0.0))


def _ttc(ego: Any, frame: DecisionFrame, others: list[Any]) -> float:
    f = frame.front
    if f.vid < 1 or ego.speed <= f.speed_mps:
        return math.inf
    other = others[f.vid - 1]
    gap = f.gap_m - (ego.LENGTH + other.LENGTH) / 2
    return max(gap, 0.0) / (ego.speed - f.speed_mps)


def _margin(ego: Any, others: list[Any]) -> float:
    """Separation of the ego's box from the nearest other's, in the ego's frame [m]: the larger
    of the longitudinal and lateral clearances (negative when the boxes overlap)."""
    best = math.inf
    c, s = math.cos(ego.heading), math.sin(ego.heading)
    for v in others:
        dx, dy = v.position[0] - ego.position[0], v.position[1] - ego.position[1]
        along, across = abs(dx * c + dy * s), abs(-dx * s + dy * c)
        best = min(best, max(along - (ego.LENGTH + v.LENGTH) / 2,
                             across - (ego.WIDTH + v.WIDTH) / 2))
    return best


def _hit(ego: Any, sim: Simulation) -> int:
    crashed = [v for v in sim.others if v.crashed]
    if not crashed:
        return 0  # an object on the road (merge's end-of-lane obstacle)
    return min(crashed, key=lambda v: math.hypot(v.position[0] - ego.position[0],
                                                 v.position[1] - ego.position[1])).rocas_id
