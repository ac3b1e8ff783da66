"""The loop that joins a world and a stack: batch mode (N variants, nothing recorded) and
recording mode (one variant, every channel written to MCAP), one semantics.

Per step: the stack observes and decides, the ego integrates the stack's actuation, the actors
move, the oracles judge. The world (map, actors, dynamics, oracles) is :mod:`rocas.sim`'s; the
stack is anything that satisfies :class:`rocas.stacks.base.Stack`.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas.errors import UsageError
from rocas.scenarios.model import Scenario
from rocas.sim.oracles import Outcome
from rocas.sim.world import BatchWorld, compile_batch
from rocas.stacks.base import (
    STACK_METADATA,
    MessageSink,
    Stack,
    StackParams,
    batch_params,
)

_NS = 1_000_000_000


@dataclass(frozen=True, eq=False)
class Rollout:
    """Results of N variants.

    Attributes:
        times: (T + 1,) [s].
        ego: (N, T + 1, 5) x [m], y [m], yaw [rad], speed [m/s], acceleration [m/s^2].
        actors: (N, T + 1, A, 4) x, y, yaw, speed.
        min_gap: (N, T + 1) smallest ego-to-obstacle box gap [m].
        outcomes: one :class:`Outcome` per variant.
        digests: per module, (N,) output fingerprints summed over the run.
        actor_ids: actor ids in array order.
        recording: the MCAP written (recording mode), else None; messages: how many.
    """

    times: np.ndarray
    ego: np.ndarray
    actors: np.ndarray
    min_gap: np.ndarray
    outcomes: list[Outcome]
    digests: dict[str, np.ndarray]
    actor_ids: tuple[str, ...]
    recording: str | None = None
    messages: int = 0


def resolve(stack: Stack, overrides: Mapping[str, float] | StackParams | None,
            source: str = "overrides") -> StackParams:
    """The stack's defaults with ``overrides`` on top, validated against its inventory."""
    if isinstance(overrides, StackParams):
        return overrides
    return StackParams(stack.parameters, overrides, source=source)


def _loop(stack: Stack, world: BatchWorld, scenarios: Sequence[Scenario],
          sets: Sequence[StackParams], sink: MessageSink | None) -> Rollout:
    """The simulator's own loop (:func:`rocas.sim.engine.rollout`) with ``stack`` built for
    ``world``; the digests summed per module of the stack (zero for one that never ran)."""
    from rocas.sim.engine import rollout as run_world

    res = run_world(world, scenarios, stack.build(world, batch_params(sets)), sink=sink,
                    digest_modules=stack.modules)
    assert res.digests is not None
    digests = {m: res.digests[:, k].copy() for k, m in enumerate(stack.modules)}
    return Rollout(times=res.times, ego=res.ego, actors=res.actors, min_gap=res.min_gap,
                   outcomes=res.outcomes, digests=digests, actor_ids=res.actor_ids)


def rollout_batch(stack: Stack, scenarios: Scenario | Sequence[Scenario],
                  params: Sequence[Mapping[str, float] | StackParams | None] | None = None,
                  seeds: Sequence[int] | None = None) -> Rollout:
    """Simulate N variants of one scenario structure with ``stack`` (nothing recorded).

    Variant i is bit-identical to ``rollout(stack, scenarios[i], params[i], seeds[i])``
    whatever N is (every stack computes per row; no computation mixes variants).
    """
    if isinstance(scenarios, Scenario):
        count = len(params) if params is not None else len(seeds) if seeds is not None else 1
        scenarios = [scenarios] * count
    scenarios = list(scenarios)
    params = list(params) if params is not None else [None] * len(scenarios)
    if len(params) != len(scenarios):
        raise UsageError(f"got {len(scenarios)} scenarios but {len(params)} parameter sets")
    seeds = [s.seed for s in scenarios] if seeds is None else list(seeds)
    world = compile_batch(scenarios, seeds)
    sets = [resolve(stack, p, f"scenario {s.name}") for s, p in zip(scenarios, params,
                                                                   strict=True)]
    return _loop(stack, world, scenarios, sets, None)


def rollout(stack: Stack, scenario: Scenario,
            params: Mapping[str, float] | StackParams | None = None, seed: int | None = None,
            *, output: str | os.PathLike[str] | None = None) -> Rollout:
    """Simulate one run; with ``output``, write every channel of ``stack`` to an MCAP file
    with the topology, the static world attachment, the stack's name and the outcome."""
    from rocas.sim.recorder import RunRecorder

    seed = scenario.seed if seed is None else seed
    world = compile_batch([scenario], [seed])
    pset = resolve(stack, params, f"scenario {scenario.name}")
    if output is None:
        return _loop(stack, world, [scenario], [pset], None)
    with RunRecorder(output, scenario, stack.channels, pset.overrides(), seed) as rec:
        rec.writer.add_metadata(STACK_METADATA, {"name": stack.name})
        res = _loop(stack, world, [scenario], [pset], rec.write)
        rec.finish(res.outcomes[0])
    return Rollout(times=res.times, ego=res.ego, actors=res.actors, min_gap=res.min_gap,
                   outcomes=res.outcomes, digests=res.digests, actor_ids=res.actor_ids,
                   recording=str(output), messages=rec.count)


# -- by the scenario's stack: what the pipeline calls ------------------------------------------


@dataclass(frozen=True, eq=False)
class SingleRun:
    """One run of :func:`simulate`: the outcome, (T + 1,) times [s], (T + 1, 5) ego, (T + 1, A,
    4) actors, (T + 1,) min_gap [m], the recording written (or None) and its message count."""

    outcome: Outcome
    times: np.ndarray
    ego: np.ndarray
    actors: np.ndarray
    min_gap: np.ndarray
    recording: str | None
    messages: int


def _merged(scenario: Scenario, params: Mapping[str, float] | None) -> dict[str, float]:
    """The scenario's own overrides with ``params`` on top (as the engine merges them)."""
    return {**scenario.ego.overrides, **dict(params or {})}


def simulate(scenario: Scenario, params: Mapping[str, float] | None = None,
             seed: int | None = None, *, output: str | os.PathLike[str] | None = None
             ) -> SingleRun:
    """One run with the stack the scenario names (``scenario.ego.stack``): the built-in ADS
    through :func:`rocas.ads.run.simulate`, any other registered stack through
    :func:`rollout`; ``params`` go on top of the scenario's own overrides."""
    if scenario.ego.stack == "ads":
        from rocas.ads.run import simulate as simulate_ads

        r = simulate_ads(scenario, params or None, seed, output=output)
        return SingleRun(r.outcome, r.times, r.ego, r.actors, r.min_gap, r.recording,
                         r.messages)
    from rocas.stacks.external import external_for
    from rocas.stacks.registry import get_stack

    ext = external_for(scenario.ego.stack)
    if ext is not None:
        return _simulate_external(ext, scenario, _merged(scenario, params), seed, output)
    r = rollout(get_stack(scenario.ego.stack), scenario, _merged(scenario, params), seed,
                output=output)  # the recording writer writes atomically
    return SingleRun(r.outcomes[0], r.times, r.ego[0], r.actors[0], r.min_gap[0],
                     r.recording, r.messages)


def simulate_batch(scenarios: Sequence[Scenario], params: Sequence[Mapping[str, float]],
                   seeds: Sequence[int], *,
                   outputs: Mapping[int, str | os.PathLike[str]] | None = None) -> Rollout:
    """N variants of one scenario structure with the stack they name (all the same); the
    built-in ADS through :func:`rocas.ads.run.simulate_batch`. Returns the fields the
    searches read (times, ego, actors, min_gap, outcomes).

    ``outputs`` (row -> MCAP file) also records those rows, each the file :func:`simulate`
    with ``output`` writes for it alone: the built-in ADS records them inside the batch (one
    batch's fixed per-tick cost for all), any other stack runs each again alone."""
    stacks = {s.ego.stack for s in scenarios}
    if len(stacks) != 1:
        raise UsageError(f"one batch mixes stacks {sorted(stacks)}",
                         "batch variants of one scenario only")
    (name,) = stacks
    if name == "ads":
        from rocas.ads.run import simulate_batch as simulate_batch_ads

        r = simulate_batch_ads(list(scenarios), params=[dict(p) for p in params],
                               seeds=list(seeds), outputs=outputs)
        return Rollout(times=r.times, ego=r.ego, actors=r.actors, min_gap=r.min_gap,
                       outcomes=r.outcomes, digests={}, actor_ids=r.actor_ids)
    for i, path in sorted((outputs or {}).items()):
        simulate(scenarios[i], params[i], seeds[i], output=path)
    from rocas.stacks.external import external_for
    from rocas.stacks.registry import get_stack

    merged = [_merged(s, p) for s, p in zip(scenarios, params, strict=True)]
    ext = external_for(name)
    if ext is not None:
        return ext.simulate_batch(list(scenarios), merged, list(seeds))
    return rollout_batch(get_stack(name), list(scenarios), merged, list(seeds))


def _simulate_external(ext: Any, scenario: Scenario, params: Mapping[str, float],
                       seed: int | None, output: str | os.PathLike[str] | None) -> SingleRun:
    """:func:`simulate` through an external stack's command: the rows from its batch mode,
    the recording (when asked for) from its single-run mode, copied to ``output``."""
    import shutil

    seed = scenario.seed if seed is None else seed
    r = ext.simulate_batch([scenario], [params], [seed])
    recording, messages = None, 0
    if output is not None:
        from rocas.recording.formats import open_recording

        one = ext.run(scenario, params, seed)
        part = f"{os.fspath(output)}.part"
        shutil.copyfile(one.recording, part)
        os.replace(part, output)
        recording = os.fspath(output)
        messages = sum(1 for _ in open_recording(recording).messages())
    return SingleRun(r.outcomes[0], r.times, r.ego[0], r.actors[0], r.min_gap[0], recording,
                     messages)


def with_stack(scenario: Scenario, name: str) -> Scenario:
    """``scenario`` driven by the registered stack ``name`` (``--stack NAME``).

    Raises:
        UsageError: no such stack, or the scenario overrides parameters of another stack.
    """
    import dataclasses

    from rocas.stacks.registry import get_stack

    if name == scenario.ego.stack:
        return scenario
    get_stack(name)  # refuses an unknown name
    if scenario.ego.params:
        raise UsageError(f"scenario {scenario.name} sets parameters of stack "
                         f"{scenario.ego.stack!r}, which stack {name!r} does not have",
                         "remove its [ego.params] or give --stack its own scenario")
    return dataclasses.replace(scenario, ego=dataclasses.replace(scenario.ego, stack=name))
