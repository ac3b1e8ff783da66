"""One simulate path for every registered stack (see :mod:`rocas.rollout`).

A stack is either built into rocas's world (:meth:`rocas.stacks.base.Stack.build`, stepped by
:mod:`rocas.sim.engine`) or simulates itself (:class:`rocas.stacks.base.SelfSimulating`: an
external command); which one is what the stack declares, never its name.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Collection, Mapping, Sequence

from rocas.errors import ScenarioError, UsageError
from rocas.scenarios.model import Scenario
from rocas.sim import engine
from rocas.sim.engine import BatchResult, RunResult
from rocas.sim.world import BatchWorld
from rocas.stacks.base import SelfSimulating, Stack, StackParams, batch_params
from rocas.stacks.registry import get_stack

#: parameter overrides as callers give them: a mapping of full names, a full assignment, None
ParamsLike = Mapping[str, float] | StackParams | None
#: module substitution: modules whose output is replaced by ground truth, one set for every
#: variant or one per variant (a stack declares which it can substitute: ``substitutable``)
OracleModules = Collection[str] | Sequence[Collection[str]]


def resolve(stack: Stack, scenario: Scenario, params: ParamsLike = None) -> StackParams:
    """``scenario``'s own overrides with ``params`` on top (of a full assignment, what differs
    from the defaults), validated against ``stack``'s inventory."""
    if isinstance(params, StackParams):
        params = params.overrides()
    merged = {**scenario.ego.overrides, **dict(params or {})}
    return StackParams(stack.parameters, merged, source=f"scenario {scenario.name}")


def check_params(scenario: Scenario, source: str | None = None) -> Scenario:
    """Refuse a scenario whose stack is unknown or whose ``[ego.params]`` are not its stack's
    (unknown name, out of range, not an integer); returns the scenario."""
    try:
        stack = get_stack(scenario.ego.stack)
    except UsageError as exc:
        raise ScenarioError(f"{source or scenario.name}: ego.stack: {exc.message}",
                            exc.hint) from None
    StackParams(stack.parameters, scenario.ego.overrides,
                source=f"{source or scenario.name}: ego.params")
    return scenario


def load_scenario(spec: str) -> Scenario:
    """A scenario file or example name (:func:`rocas.scenarios.resolve_scenario`), refused at
    once when its parameters are not its stack's (:func:`check_params`)."""
    from rocas.scenarios import resolve_scenario

    return check_params(resolve_scenario(spec), spec)


def _in_our_world(stack: Stack) -> None:
    """Refuse a stack that declares another simulator's world (it has its own rollout)."""
    world = getattr(stack, "world", None)
    if world:
        raise UsageError(f"stack {stack.name!r} drives in {world}'s world, not rocas's own",
                         f"run it with its own tools (python -m {type(stack).__module__.rsplit('.', 1)[0]})")


def _factory(stack: Stack, sets: Sequence[StackParams], oracle_modules: OracleModules
             ) -> Callable[[BatchWorld], object]:
    """What the engine builds the stack with: every parameter as an (N,) array, and the
    modules to substitute when the stack declares that it can."""
    _in_our_world(stack)
    params = batch_params(sets)
    if not oracle_modules:
        return lambda world: stack.build(world, params)
    if not getattr(stack, "substitutable", ()):
        raise UsageError(f"stack {stack.name!r} cannot substitute its modules",
                         "module substitution needs a stack that declares 'substitutable'")
    return lambda world: stack.build(world, params, oracle_modules=oracle_modules)  # type: ignore[call-arg]


def rollout(stack: Stack, scenario: Scenario, params: ParamsLike = None,
            seed: int | None = None, *, output: str | os.PathLike[str] | None = None,
            on_tick: Callable[[int], None] | None = None) -> RunResult:
    """One run of ``scenario`` with ``stack``; with ``output``, every channel of the stack
    written to an MCAP file with the topology, the static world, the stack's name, the
    parameter overrides and the outcome."""
    pset = resolve(stack, scenario, params)
    if isinstance(stack, SelfSimulating):
        return stack.simulate_one(scenario, pset, seed, output=output)
    return engine.simulate(scenario, _factory(stack, [pset], ()), seed, output=output,
                           channels=stack.channels, param_overrides=pset.overrides(),
                           on_tick=on_tick, stack_name=stack.name)


def rollout_batch(stack: Stack, scenarios: Scenario | Sequence[Scenario],
                  params: Sequence[ParamsLike] | None = None,
                  seeds: Sequence[int] | None = None, *, track_outputs: bool = False,
                  oracle_modules: OracleModules = frozenset(),
                  outputs: Mapping[int, str | os.PathLike[str]] | None = None) -> BatchResult:
    """N variants of one scenario structure with ``stack`` (batch mode).

    Args:
        scenarios: one scenario (repeated to match ``params``/``seeds``) or N variants of one
            structure (same map, ego route and entity ids; properties may differ).
        params: N parameter overrides on top of each scenario's own; None: none.
        seeds: N seeds; None: each scenario's.
        track_outputs: also sum each module's output fingerprint over the run
            (:attr:`BatchResult.digests`, (N, M), columns in ``stack.modules`` order).
        oracle_modules: modules replaced by ground truth (module substitution), if the stack
            declares it can.
        outputs: row -> MCAP file: that row is also recorded, the very file :func:`rollout`
            with ``output`` writes for it alone.

    Returns:
        :class:`BatchResult`; variant i is identical to a run of ``scenarios[i]`` alone
        whatever N is (every stack computes per row).
    """
    if isinstance(scenarios, Scenario):
        count = len(params) if params is not None else len(seeds) if seeds is not None else 1
        scenarios = [scenarios] * count
    scenarios = list(scenarios)
    params = list(params) if params is not None else [None] * len(scenarios)
    if len(params) != len(scenarios):
        raise UsageError(f"got {len(scenarios)} scenarios but {len(params)} parameter sets")
    seeds = [s.seed for s in scenarios] if seeds is None else list(seeds)
    sets = [resolve(stack, s, p) for s, p in zip(scenarios, params, strict=True)]
    if isinstance(stack, SelfSimulating):
        for i, path in sorted((outputs or {}).items()):
            stack.simulate_one(scenarios[i], sets[i], seeds[i], output=path)
        return stack.simulate_batch(scenarios, sets, seeds)
    if outputs and not getattr(stack, "records_rows", False):
        for i, path in sorted(outputs.items()):  # a stack that records row 0 only: alone
            rollout(stack, scenarios[i], sets[i], seeds[i], output=path)
        outputs = None
    return engine.simulate_batch(
        scenarios, _factory(stack, sets, oracle_modules), seeds,
        digest_modules=stack.modules if track_outputs else None, outputs=outputs,
        channels=stack.channels, stack_name=stack.name,
        param_overrides=[p.overrides() for p in sets] if outputs else None)


def _stack_of(scenarios: Sequence[Scenario]) -> Stack:
    names = {s.ego.stack for s in scenarios}
    if len(names) != 1:
        raise UsageError(f"one batch mixes stacks {sorted(names)}",
                         "batch variants of one scenario only")
    return get_stack(names.pop())


def simulate(scenario: Scenario, params: ParamsLike = None, seed: int | None = None, *,
             output: str | os.PathLike[str] | None = None,
             on_tick: Callable[[int], None] | None = None) -> RunResult:
    """One run with the stack the scenario names (:func:`rollout`)."""
    return rollout(get_stack(scenario.ego.stack), scenario, params, seed, output=output,
                   on_tick=on_tick)


def simulate_batch(scenarios: Scenario | Sequence[Scenario],
                   params: Sequence[ParamsLike] | None = None,
                   seeds: Sequence[int] | None = None, *, track_outputs: bool = False,
                   oracle_modules: OracleModules = frozenset(),
                   outputs: Mapping[int, str | os.PathLike[str]] | None = None) -> BatchResult:
    """N variants with the stack they name (all the same; :func:`rollout_batch`)."""
    one = [scenarios] if isinstance(scenarios, Scenario) else list(scenarios)
    return rollout_batch(_stack_of(one), scenarios, params, seeds, track_outputs=track_outputs,
                         oracle_modules=oracle_modules, outputs=outputs)


def drive_with(scenario: Scenario, name: str) -> Scenario:
    """``scenario`` with the registered stack ``name`` standing in for the one it names, its
    parameter overrides kept (checked against ``name``'s inventory when it is simulated)."""
    get_stack(name)  # refuses an unknown name
    return dataclasses.replace(scenario, ego=dataclasses.replace(scenario.ego, stack=name))


def with_stack(scenario: Scenario, name: str) -> Scenario:
    """``scenario`` driven by the registered stack ``name`` (``--stack NAME``).

    Raises:
        UsageError: no such stack, or the scenario overrides parameters of another stack.
    """
    if name == scenario.ego.stack:
        return scenario
    get_stack(name)  # refuses an unknown name
    if scenario.ego.params:
        raise UsageError(f"scenario {scenario.name} sets parameters of stack "
                         f"{scenario.ego.stack!r}, which stack {name!r} does not have",
                         "remove its [ego.params] or give --stack its own scenario")
    return dataclasses.replace(scenario, ego=dataclasses.replace(scenario.ego, stack=name))


__all__ = ["BatchResult", "OracleModules", "ParamsLike", "RunResult", "check_params", "drive_with",
           "load_scenario", "resolve", "rollout", "rollout_batch", "simulate", "simulate_batch", "with_stack"]
