"""The ADS stack: modules wired by their channels, each run at its channel's rate.

Per simulation step: localization and chassis publish; every perception period, perception
(obstacles, traffic lights, brake signal), prediction and planning run in that order; control
runs every step on the latest plan; canbus turns the command into actuation.

Module substitution: ``oracle_modules`` names, per variant, modules whose output is replaced by
ground truth (:mod:`rocas.stacks.ads.oracle`); with none named the stack runs exactly as without it.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Sequence, Set
from dataclasses import dataclass

import numpy as np

from rocas.errors import UsageError
from rocas.sim.actors import ActorState
from rocas.sim.dynamics import VehicleState
from rocas.sim.world import BatchWorld, light_state
from rocas.stacks.ads.control import Control, ControlOutput
from rocas.stacks.ads.localization import Canbus, ChassisOutput, Localization, LocalizationOutput
from rocas.stacks.ads.oracle import SUBSTITUTABLE, PerfectPerception, PerfectPrediction
from rocas.stacks.ads.perception import Perception, PerceptionOutput, ground_truth
from rocas.stacks.ads.planning import Planning, PlanningOutput
from rocas.stacks.ads.prediction import Prediction, PredictionOutput

PERCEPTION_PERIOD_S = 0.1


@dataclass(frozen=True, eq=False)
class TickOutputs:
    """What the modules published in one step (None: the module did not run)."""

    localization: LocalizationOutput
    chassis: ChassisOutput
    perception: PerceptionOutput | None
    prediction: PredictionOutput | None
    planning: PlanningOutput | None
    control: ControlOutput


OracleModules = Set[str] | Sequence[Set[str]]


def oracle_masks(oracle_modules: OracleModules, n: int) -> dict[str, np.ndarray]:
    """Per substitutable module, (N,) bool: which variants publish its ground truth.

    Args:
        oracle_modules: one set of module names for every variant, or one set per variant.
        n: the batch size.
    """
    if isinstance(oracle_modules, Set):
        per_variant: Sequence[Set[str]] = [oracle_modules] * n
    else:
        per_variant = list(oracle_modules)
        if any(isinstance(x, str) for x in per_variant):
            raise UsageError("oracle_modules: expected a set of module names or one set per "
                             "variant, got a sequence of strings",
                             'write frozenset({"perception"}), not ("perception",)')
    if len(per_variant) != n:
        raise UsageError(f"oracle_modules: got {len(per_variant)} sets for {n} variants")
    for names in per_variant:
        unknown = sorted(set(names) - set(SUBSTITUTABLE))
        if unknown:
            raise UsageError(f"oracle_modules: {unknown[0]!r} has no ground-truth substitute",
                             f"substitutable: {', '.join(SUBSTITUTABLE)}")
    return {m: np.array([m in names for names in per_variant], dtype=bool)
            for m in SUBSTITUTABLE}


def _merge(mask: np.ndarray, oracle: object, real: object | None) -> object:
    """Rows of ``oracle`` where ``mask`` (N,) holds, of ``real`` elsewhere (same dataclass)."""
    if real is None or mask.all():
        return oracle
    fields = {}
    for f in dataclasses.fields(real):
        a, b = getattr(oracle, f.name), getattr(real, f.name)
        if isinstance(b, np.ndarray):
            fields[f.name] = np.where(mask.reshape(-1, *(1,) * (b.ndim - 1)), a, b)
        else:
            fields[f.name] = b  # the input both were computed from
    return type(real)(**fields)


class AdsStack:
    """All modules of the built-in ADS for N variants (``params``: name -> (N,) array).

    ``oracle_modules``: modules whose output is replaced by ground truth, one set for every
    variant or one set per variant (:func:`oracle_masks`); empty by default.
    """

    def __init__(self, world: BatchWorld, params: dict[str, np.ndarray],
                 oracle_modules: OracleModules = frozenset()) -> None:
        self.world = world
        self.period_ticks = max(1, int(round(PERCEPTION_PERIOD_S / world.dt_s)))
        period = self.period_ticks * world.dt_s
        self.localization = Localization(world, params)
        self.canbus = Canbus(world, params)
        self.perception = Perception(world, params, period)
        self.prediction = Prediction(world, params)
        self.planning = Planning(world, params)
        self.control = Control(world, params)
        self.plan: PlanningOutput | None = None
        self.plan_time = 0.0
        self.oracle = {m: mask for m, mask in oracle_masks(oracle_modules,
                                                           world.batch_size).items()
                       if mask.any()}
        self.perfect_perception = (PerfectPerception(world, params)
                                   if "perception" in self.oracle else None)
        self.perfect_prediction = (PerfectPrediction(world, params)
                                   if "prediction" in self.oracle else None)

    def step(self, tick: int, ego: VehicleState, ego_accel: np.ndarray, actors: VehicleState,
             actor_state: ActorState | None = None) -> TickOutputs:
        """One simulation step. ``actors`` are the actors' bodies; ``actor_state`` their full
        state, which only the ground-truth prediction reads (it rolls the actors forward)."""
        t = tick * self.world.dt_s
        loc = self.localization.step(tick, ego, ego_accel)
        chassis = self.canbus.feedback(tick, ego)
        if self.perfect_perception is not None:
            self.perfect_perception.observe(actors)
        per = pred = plan = None
        if tick % self.period_ticks == 0 or self.plan is None:
            gt = ground_truth(self.world, actors.x, actors.y, actors.yaw)
            lights = light_state(self.world, t)
            mask = self.oracle.get("perception")
            if mask is None or not mask.all():
                per = self.perception.step(tick, ego.x, ego.y, ego.yaw, gt, lights, loc)
            if mask is not None:
                per = _merge(mask, self.perfect_perception.step(t, ego, actors, gt, lights, loc),
                             per)
            mask = self.oracle.get("prediction")
            if mask is None or not mask.all():
                pred = self.prediction.step(per, loc)
            if mask is not None:
                if actor_state is None:
                    raise UsageError("the ground-truth prediction needs the actors' full state "
                                     "(actor_state)")
                pred = _merge(mask, self.perfect_prediction.step(tick, per, actor_state, ego),
                              pred)
            plan = self.planning.step(pred, per, loc, chassis)
            self.plan, self.plan_time = plan, t
        ctrl = self.control.step(t, self.plan, self.plan_time, loc, chassis)
        return TickOutputs(loc, chassis, per, pred, plan, ctrl)

    def actuate(self, ctrl: ControlOutput) -> tuple[np.ndarray, np.ndarray]:
        return self.canbus.actuate(ctrl.throttle, ctrl.brake, ctrl.steering_target, ctrl.estop)


@functools.cache
def _digest_weights(count: int) -> np.ndarray:
    """1.0001**i for i < count, by repeated multiplication (``**`` would go through a SIMD
    ``power`` kernel whose last bit depends on the CPU)."""
    return np.cumprod(np.concatenate([[1.0], np.full(max(count - 1, 0), 1.0001)]))[:count]


def output_digest(out: TickOutputs) -> dict[str, np.ndarray]:
    """A per-variant fingerprint (N,) of what each module published this step; summed over a
    run it shows whether a parameter changed a module's output."""
    def fp(obj: object, names: tuple[str, ...]) -> np.ndarray:
        total = 0.0
        for name in names:
            a = np.asarray(getattr(obj, name), dtype=np.float64)
            a = np.where(np.isfinite(a), a, 0.0)
            flat = a.reshape(a.shape[0], -1)
            total = total + (flat * _digest_weights(flat.shape[1])).sum(axis=1)
        return total

    d = {
        "localization": fp(out.localization, ("x", "y", "heading", "speed", "lane", "lane_s")),
        "canbus": fp(out.chassis, ("speed", "throttle", "brake", "steering")),
        "control": fp(out.control, ("throttle", "brake", "steering_target", "acceleration",
                                    "estop", "lateral_error", "station_error")),
    }
    if out.perception is not None:
        per = out.perception
        pub = per.published
        d["perception"] = fp(per, ("brake_probability", "brake", "tl_color", "tl_selected",
                                   "tl_confidence", "tl_detected")) + sum(
            (np.where(pub, getattr(per, f), 0.0) * (1 + np.arange(pub.shape[1]))).sum(1)
            for f in ("track_id", "type", "sub_type", "color", "x", "y", "theta", "vx", "vy",
                      "length", "width", "confidence"))
        d["prediction"] = fp(out.prediction, ("is_static", "intent", "probability", "horizon")) + (
            np.where(out.prediction.traj_valid[:, None, :] & pub[..., None],
                     out.prediction.traj_x + 0.7 * out.prediction.traj_y, 0.0).sum((1, 2)))
        d["planning"] = fp(out.planning, ("decision", "main", "reason", "estop", "cruise_speed",
                                          "nudge_offset", "stop_distance")) + np.where(
            out.planning.valid, out.planning.x + out.planning.v, 0.0).sum(1)
    return d
