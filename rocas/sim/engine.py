"""The simulation loop, in its two modes with one semantics.

- :func:`simulate_batch` steps N variants of one scenario together (arrays of shape (N, ...)),
  records nothing and returns trajectories and oracle outcomes.
- :func:`simulate` runs one variant through the very same loop and, when given an output path,
  publishes every module's messages to an MCAP recording.

Both are pure functions of picklable inputs: (scenario, parameter overrides, seed) -> result.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence, Set
from dataclasses import dataclass

import numpy as np

from rocas.ads.params import ParamSet, stack_params
from rocas.ads.stack import AdsStack, TickOutputs, output_digest
from rocas.scenarios.model import Scenario
from rocas.sim.actors import initial_actors, step_actors
from rocas.sim.dynamics import VehicleState, bicycle_step
from rocas.sim.oracles import Oracles, Outcome
from rocas.sim.world import BatchWorld, compile_batch, reference_at, road_friction

MODULE_ORDER = ("localization", "canbus", "perception", "prediction", "planning", "control")
ParamsLike = Mapping[str, float] | ParamSet | None
#: modules publishing ground truth: one set of names for every variant, or one set per variant
OracleModules = Set[str] | Sequence[Set[str]]


@dataclass(frozen=True, eq=False)
class BatchResult:
    """Results of N variants.

    Attributes:
        times: (T + 1,) [s].
        ego: (N, T + 1, 5) x [m], y [m], yaw [rad], speed [m/s], acceleration [m/s^2].
        actors: (N, T + 1, A, 4) x, y, yaw, speed.
        min_gap: (N, T + 1) smallest ego-to-obstacle box gap at each step [m].
        outcomes: one :class:`Outcome` per variant.
        digests: (N, 6) per-module output fingerprints (MODULE_ORDER), or None.
        actor_ids: actor ids in array order.
    """

    times: np.ndarray
    ego: np.ndarray
    actors: np.ndarray
    min_gap: np.ndarray
    outcomes: list[Outcome]
    digests: np.ndarray | None
    actor_ids: tuple[str, ...]


@dataclass(frozen=True, eq=False)
class RunResult:
    """One run (recording mode). Arrays as in :class:`BatchResult` without the batch axis."""

    outcome: Outcome
    times: np.ndarray
    ego: np.ndarray
    actors: np.ndarray
    min_gap: np.ndarray
    recording: str | None
    messages: int


Publisher = Callable[[int, float, TickOutputs], None]


def resolve_params(scenario: Scenario, params: ParamsLike) -> ParamSet:
    """Scenario overrides, then the caller's overrides on top."""
    merged = dict(scenario.ego.params)
    if isinstance(params, ParamSet):
        merged.update(params.overrides())
    elif params:
        merged.update(params)
    return ParamSet(merged, source=f"scenario {scenario.name}")


def initial_ego(world: BatchWorld, scenarios: Sequence[Scenario]) -> VehicleState:
    """The ego's start state per variant (start lateral offset and speed may differ)."""
    s = np.array([sc.ego.start_s_m for sc in scenarios])
    x, y, h, _ = reference_at(world.road, s)
    d = np.array([sc.ego.start_lateral_m for sc in scenarios])
    return VehicleState(x - d * np.sin(h), y + d * np.cos(h), h, h.copy(),
                        np.array([sc.ego.start_speed_mps for sc in scenarios], dtype=float))


def _run(world: BatchWorld, scenarios: Sequence[Scenario], param_sets: Sequence[ParamSet], *,
         publish: Publisher | None = None, track_outputs: bool = False,
         on_tick: Callable[[int], None] | None = None,
         oracle_modules: OracleModules = frozenset()) -> BatchResult:
    n = world.batch_size
    scenario = scenarios[0]  # the structure (route, start arc length) all variants share
    stack = AdsStack(world, stack_params(param_sets), oracle_modules)
    ego = initial_ego(world, scenarios)
    actors = initial_actors(world)
    friction = road_friction(world.weather[:, 1])
    oracles = Oracles(world, np.full(n, scenario.ego.start_s_m))
    steps = world.num_ticks
    na = len(world.actor_ids)
    ego_tr = np.zeros((n, steps + 1, 5))
    act_tr = np.zeros((n, steps + 1, na, 4))
    gap_tr = np.zeros((n, steps + 1))
    accel = np.zeros(n)
    digests = np.zeros((n, len(MODULE_ORDER))) if track_outputs else None
    reason = np.zeros(n, dtype=np.int64)
    oracles.update(0, ego, accel, actors.body, np.zeros(n, dtype=bool), reason)

    def record(i: int) -> None:
        for j, a in enumerate((ego.x, ego.y, ego.yaw, ego.speed, accel)):
            ego_tr[:, i, j] = a
        b = actors.body
        for j, a in enumerate((b.x, b.y, b.yaw, b.speed)):
            act_tr[:, i, :, j] = a
        gap_tr[:, i] = oracles.last_gap

    record(0)
    for tick in range(steps):
        t = tick * world.dt_s
        out = stack.step(tick, ego, accel, actors.body, actors)
        if publish is not None:
            publish(tick, t, out)
        if digests is not None:
            for name, value in output_digest(out).items():
                digests[:, MODULE_ORDER.index(name)] += value
        a_dem, curvature = stack.actuate(out.control)
        if out.planning is not None:
            reason = out.planning.reason
        prev = ego
        ego, accel = bicycle_step(ego, a_dem, curvature, friction, np.ones(n), world.dt_s)
        stack.canbus.advance_odometer(np.hypot(ego.x - prev.x, ego.y - prev.y))
        actors = step_actors(world, actors, t, prev, friction)
        oracles.update(tick + 1, ego, accel, actors.body,
                       out.control.estop | stack.plan.estop, reason)
        record(tick + 1)
        if on_tick is not None:
            on_tick(tick)
    oracles.finish_route(ego_tr[..., :2])
    return BatchResult(
        times=np.arange(steps + 1) * world.dt_s, ego=ego_tr, actors=act_tr, min_gap=gap_tr,
        outcomes=oracles.outcomes(), digests=digests, actor_ids=world.actor_ids,
    )


def simulate_batch(
    scenarios: Scenario | Sequence[Scenario],
    params: Sequence[ParamsLike] | None = None,
    seeds: Sequence[int] | None = None,
    *,
    track_outputs: bool = False,
    oracle_modules: OracleModules = frozenset(),
) -> BatchResult:
    """Simulate N variants together (batch mode; records nothing).

    Args:
        scenarios: one scenario (repeated to match ``params``/``seeds``) or N variants of one
            structure (same map, ego route and entity ids; properties may differ).
        params: N parameter override mappings (or ParamSets), applied on top of each
            scenario's own ``ego.params``; None means none.
        seeds: N seeds; None means each scenario's seed.
        track_outputs: also return per-module output fingerprints (``digests``).
        oracle_modules: modules whose output is replaced by ground truth (module
            substitution, :mod:`rocas.ads.oracle`): one set of names for every variant, or N
            sets; empty (the default) runs the ADS as it is.

    Returns:
        :class:`BatchResult`; variant i is identical to ``simulate(scenarios[i], params[i],
        seeds[i])`` whatever N is.
    """
    if isinstance(scenarios, Scenario):
        count = len(params) if params is not None else len(seeds) if seeds is not None else 1
        scenarios = [scenarios] * count
    scenarios = list(scenarios)
    n = len(scenarios)
    params = list(params) if params is not None else [None] * n
    if len(params) != n:
        from rocas.errors import UsageError
        raise UsageError(f"got {n} scenarios but {len(params)} parameter sets")
    seeds = [s.seed for s in scenarios] if seeds is None else list(seeds)
    world = compile_batch(scenarios, seeds)
    sets = [resolve_params(s, p) for s, p in zip(scenarios, params, strict=True)]
    return _run(world, scenarios, sets, track_outputs=track_outputs,
                oracle_modules=oracle_modules)


def simulate(
    scenario: Scenario,
    params: ParamsLike = None,
    seed: int | None = None,
    *,
    output: str | os.PathLike[str] | None = None,
    on_tick: Callable[[int], None] | None = None,
) -> RunResult:
    """Simulate one run (recording mode): with ``output``, write an MCAP recording with every
    module's messages, the topology metadata and the static world attachment."""
    seed = scenario.seed if seed is None else seed
    world = compile_batch([scenario], [seed])
    pset = resolve_params(scenario, params)
    if output is None:
        res = _run(world, [scenario], [pset], on_tick=on_tick)
        path, count = None, 0
    else:
        from rocas.sim.recorder import ScenarioRecorder

        with ScenarioRecorder(output, scenario, pset, seed) as rec:
            res = _run(world, [scenario], [pset], publish=rec.publish, on_tick=on_tick)
            rec.finish(res.outcomes[0])
        path, count = str(output), rec.count
    return RunResult(outcome=res.outcomes[0], times=res.times, ego=res.ego[0],
                     actors=res.actors[0], min_gap=res.min_gap[0], recording=path,
                     messages=count)
