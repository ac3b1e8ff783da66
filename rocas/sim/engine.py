"""The simulation loop that joins a world and a stack, in two modes with one semantics.

- :func:`simulate_batch` steps N variants of one scenario together (arrays of shape (N, ...)),
  records nothing and returns trajectories and oracle outcomes.
- :func:`simulate` runs one variant through the very same loop and, when given an output path,
  lets the stack publish its messages to an MCAP recording.

The stack is the caller's: a :data:`rocas.sim.protocol.StackFactory` that builds a
:class:`rocas.sim.protocol.StackRun` for the compiled world. Per step the stack observes and
decides, the ego integrates its actuation, the actors move, the oracles judge. Both functions
are pure functions of their inputs: (scenario, stack, seed) -> result. A registered stack is
wired in by :mod:`rocas.rollout`, whose ``simulate``/``simulate_batch`` take parameter overrides.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rocas.scenarios.model import Scenario
from rocas.sim.actors import initial_actors, step_actors
from rocas.sim.dynamics import VehicleState, bicycle_step
from rocas.sim.oracles import Oracles, Outcome
from rocas.sim.protocol import Channel, MessageSink, Observation, StackFactory, StackRun
from rocas.sim.world import BatchWorld, compile_batch, reference_at, road_friction

_NS = 1_000_000_000


@dataclass(frozen=True, eq=False)
class BatchResult:
    """Results of N variants.

    Attributes:
        times: (T + 1,) [s].
        ego: (N, T + 1, 5) x [m], y [m], yaw [rad], speed [m/s], acceleration [m/s^2].
        actors: (N, T + 1, A, 4) x, y, yaw, speed.
        min_gap: (N, T + 1) smallest ego-to-obstacle box gap at each step [m].
        outcomes: one :class:`Outcome` per variant.
        digests: (N, M) per-module output fingerprints summed over the run, in the order of
            the ``digest_modules`` asked for, or None.
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


def initial_ego(world: BatchWorld, scenarios: Sequence[Scenario]) -> VehicleState:
    """The ego's start state per variant (start lateral offset and speed may differ)."""
    s = np.array([sc.ego.start_s_m for sc in scenarios])
    x, y, h, _ = reference_at(world.road, s)
    d = np.array([sc.ego.start_lateral_m for sc in scenarios])
    return VehicleState(x - d * np.sin(h), y + d * np.cos(h), h, h.copy(),
                        np.array([sc.ego.start_speed_mps for sc in scenarios], dtype=float))


def rollout(world: BatchWorld, scenarios: Sequence[Scenario], run: StackRun, *,
            sink: MessageSink | None = None, digest_modules: Sequence[str] | None = None,
            on_tick: Callable[[int], None] | None = None,
            sinks: Mapping[int, MessageSink] | None = None) -> BatchResult:
    """Step the compiled ``world`` (N variants of ``scenarios``) with the stack ``run``.

    Args:
        world: the compiled batch (:func:`rocas.sim.world.compile_batch`).
        scenarios: the N scenarios it was compiled from (start states).
        run: the stack, built for ``world``.
        sink: recording mode: the stack publishes variant 0's messages here each step.
        sinks: recording mode for several rows: variant i's messages go to ``sinks[i]`` (the
            stack's ``publish`` must take ``variant=i`` for i > 0, as the built-in ADS's does);
            the others run as in batch mode. A row's messages are those of its run alone.
        digest_modules: sum the stack's per-module output digests over the run, one column per
            named module (:attr:`BatchResult.digests`); None: skip them.
        on_tick: called with the step index after each step.
    """
    n = world.batch_size
    scenario = scenarios[0]  # the structure (route, start arc length) all variants share
    ego = initial_ego(world, scenarios)
    actors = initial_actors(world)
    friction = road_friction(world.weather[:, 1])
    oracles = Oracles(world, np.full(n, scenario.ego.start_s_m))
    steps = world.num_ticks
    na = len(world.actor_ids)
    # time-major buffers, so that a step writes contiguous rows; made batch-major at the end
    ego_tm = np.zeros((steps + 1, 5, n))
    act_tm = np.zeros((steps + 1, 4, n, na))
    gap_tm = np.zeros((steps + 1, n))
    accel = np.zeros(n)
    columns = {m: i for i, m in enumerate(digest_modules)} if digest_modules is not None else None
    digests = np.zeros((n, len(columns))) if columns is not None else None
    oracles.update(0, ego, accel, actors.body, np.zeros(n, dtype=bool), np.zeros(n, dtype=bool))

    def record(i: int) -> None:
        e, b = ego_tm[i], act_tm[i]
        e[0], e[1], e[2], e[3], e[4] = ego.x, ego.y, ego.yaw, ego.speed, accel
        body = actors.body
        b[0], b[1], b[2], b[3] = body.x, body.y, body.yaw, body.speed
        gap_tm[i] = oracles.last_gap

    record(0)
    dt_ns = round(world.dt_s * _NS)
    publish = sorted((({0: sink} if sink is not None else {}) | dict(sinks or {})).items())
    for tick in range(steps):
        t = tick * world.dt_s
        b = actors.body
        act = run.step(Observation(tick, t, ego.x, ego.y, ego.yaw, ego.speed, accel, b.x, b.y,
                                   b.yaw, b.speed, {"ego": ego, "actors": b,
                                                    "actor_state": actors}))
        for i, row_sink in publish:
            if i == 0:
                run.publish(row_sink, tick, tick * dt_ns)
            else:
                run.publish(row_sink, tick, tick * dt_ns, variant=i)  # type: ignore[call-arg]
        if digests is not None and columns is not None:
            for name, value in run.digest().items():
                digests[:, columns[name]] += value
        prev = ego
        ego, accel = bicycle_step(ego, act.accel_mps2, act.curvature_1pm, friction, np.ones(n),
                                  world.dt_s)
        actors = step_actors(world, actors, t, prev, friction)
        oracles.update(tick + 1, ego, accel, actors.body, act.estop, act.stop_justified)
        record(tick + 1)
        if on_tick is not None:
            on_tick(tick)
    ego_tr = np.ascontiguousarray(ego_tm.transpose(2, 0, 1))  # (N, T + 1, 5)
    act_tr = np.ascontiguousarray(act_tm.transpose(2, 0, 3, 1))  # (N, T + 1, A, 4)
    gap_tr = np.ascontiguousarray(gap_tm.T)  # (N, T + 1)
    oracles.finish_route(ego_tr[..., :2])
    return BatchResult(
        times=np.arange(steps + 1) * world.dt_s, ego=ego_tr, actors=act_tr, min_gap=gap_tr,
        outcomes=oracles.outcomes(), digests=digests, actor_ids=world.actor_ids,
    )


def simulate_batch(scenarios: Sequence[Scenario], stack: StackFactory,
                   seeds: Sequence[int] | None = None, *,
                   digest_modules: Sequence[str] | None = None,
                   outputs: Mapping[int, str | os.PathLike[str]] | None = None,
                   channels: Sequence[Channel] = (),
                   param_overrides: Sequence[Mapping[str, float]] | None = None,
                   stack_name: str | None = None) -> BatchResult:
    """Simulate N variants of one structure together (batch mode), recording the rows named in
    ``outputs``.

    Args:
        scenarios: N variants of one structure (same map, ego route and entity ids;
            properties may differ).
        stack: builds the system under test for the compiled world (its parameters per
            variant are the factory's business).
        seeds: N seeds; None means each scenario's seed.
        digest_modules: also return per-module output fingerprints, one column per name.
        outputs: row -> MCAP file: that row is written as :func:`simulate` writes a run alone
            (the same file, bit for bit), with ``channels`` and the row's
            ``param_overrides``; the stack must publish rows other than 0
            (:func:`rollout`'s ``sinks``).
        channels, param_overrides: what the recordings carry (one overrides mapping per row).
        stack_name: the stack's registered name, which the recordings carry.

    Returns:
        :class:`BatchResult`; variant i is identical to a run of ``scenarios[i]`` alone
        whatever N is (as long as the stack computes per row).
    """
    scenarios = list(scenarios)
    seeds = [s.seed for s in scenarios] if seeds is None else list(seeds)
    world = compile_batch(scenarios, seeds)
    if not outputs:
        return rollout(world, scenarios, stack(world), digest_modules=digest_modules)
    import contextlib

    from rocas.sim.recorder import RunRecorder

    with contextlib.ExitStack() as opened:
        recorders = {i: opened.enter_context(RunRecorder(
            path, scenarios[i], channels,
            param_overrides[i] if param_overrides is not None else {}, seeds[i], stack_name))
            for i, path in sorted(outputs.items())}
        res = rollout(world, scenarios, stack(world), digest_modules=digest_modules,
                      sinks={i: rec.write for i, rec in recorders.items()})
        for i, rec in recorders.items():
            rec.finish(res.outcomes[i])
    return res


def simulate(scenario: Scenario, stack: StackFactory, seed: int | None = None, *,
             output: str | os.PathLike[str] | None = None, channels: Sequence[Channel] = (),
             param_overrides: Mapping[str, float] | None = None,
             on_tick: Callable[[int], None] | None = None,
             stack_name: str | None = None) -> RunResult:
    """Simulate one run (recording mode).

    With ``output``, write an MCAP recording: the stack's ``channels`` with their topology,
    every message the stack publishes, the static world attachment, the mission with
    ``param_overrides`` (the stack's parameters that differ from its defaults) and the
    outcome (:class:`rocas.sim.recorder.RunRecorder`), and the stack's name (``stack_name``).
    """
    seed = scenario.seed if seed is None else seed
    world = compile_batch([scenario], [seed])
    if output is None:
        res = rollout(world, [scenario], stack(world), on_tick=on_tick)
        path, count = None, 0
    else:
        from rocas.sim.recorder import RunRecorder

        with RunRecorder(output, scenario, channels, param_overrides or {}, seed,
                         stack_name) as rec:
            res = rollout(world, [scenario], stack(world), sink=rec.write, on_tick=on_tick)
            rec.finish(res.outcomes[0])
        path, count = str(output), rec.count
    return RunResult(outcome=res.outcomes[0], times=res.times, ego=res.ego[0],
                     actors=res.actors[0], min_gap=res.min_gap[0], recording=path,
                     messages=count)
