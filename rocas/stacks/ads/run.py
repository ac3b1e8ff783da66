"""The built-in ADS in the simulator: its run behind :mod:`rocas.sim.protocol`, and the
``simulate``/``simulate_batch`` the pipeline, the CLI and the tests call.

:class:`AdsRun` steps :class:`rocas.stacks.ads.stack.AdsStack` for the engine: it turns the modules'
control command into an actuation, tells the oracles whether the held plan names a traffic
reason to stand (:data:`rocas.stacks.ads.planning.STOP_JUSTIFIED`), publishes the channels
(:class:`rocas.stacks.ads.recorder.AdsPublisher`) and fingerprints each module's output.
:func:`simulate` and :func:`simulate_batch` resolve parameter overrides against the ADS's
inventory and hand the engine (:mod:`rocas.sim.engine`) a factory of :class:`AdsRun`.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from rocas.stacks.ads.params import ParamSet, stack_params
from rocas.stacks.ads.planning import STOP_JUSTIFIED
from rocas.stacks.ads.recorder import AdsPublisher
from rocas.stacks.ads.stack import AdsStack, OracleModules, TickOutputs, output_digest
from rocas.stacks.ads.topics import CHANNELS
from rocas.scenarios.model import Scenario
from rocas.sim import engine
from rocas.sim.engine import BatchResult, RunResult
from rocas.sim.protocol import Actuation, MessageSink, Observation
from rocas.sim.world import BatchWorld

#: the columns of :attr:`BatchResult.digests` for the built-in ADS
MODULE_ORDER = ("localization", "canbus", "perception", "prediction", "planning", "control")
ParamsLike = Mapping[str, float] | ParamSet | None


class AdsRun:
    """The ADS's modules for N variants, stepped through :class:`rocas.sim.protocol.StackRun`.

    Args:
        world: the compiled batch.
        params: every parameter as an (N,) array, one value per variant
            (:func:`rocas.stacks.ads.params.stack_params` of one full assignment per variant).
        oracle_modules: modules whose output is replaced by ground truth (module
            substitution, :mod:`rocas.stacks.ads.oracle`): one set for every variant or one per
            variant; empty runs the ADS as it is.
    """

    def __init__(self, world: BatchWorld, params: Mapping[str, np.ndarray],
                 oracle_modules: OracleModules = frozenset()) -> None:
        self.stack = AdsStack(world, dict(params), oracle_modules)
        self.out: TickOutputs | None = None
        self._prev_xy: tuple[np.ndarray, np.ndarray] | None = None
        self._publishers: dict[int, AdsPublisher] = {}
        self._world = world

    def step(self, obs: Observation) -> Actuation:
        if self._prev_xy is not None:  # the odometer advances by what the ego really moved
            self.stack.canbus.advance_odometer(np.hypot(obs.ego_x - self._prev_xy[0],
                                                        obs.ego_y - self._prev_xy[1]))
        self._prev_xy = (obs.ego_x, obs.ego_y)
        d = obs.detail
        out = self.stack.step(obs.tick, d["ego"], obs.ego_accel, d["actors"], d["actor_state"])
        self.out = out
        accel, curvature = self.stack.actuate(out.control)
        plan = self.stack.plan  # the latest plan, held between planning steps
        assert plan is not None  # planning runs on the first step
        return Actuation(accel, curvature, out.control.estop | plan.estop,
                         STOP_JUSTIFIED[plan.reason])

    def publish(self, sink: MessageSink, tick: int, t_ns: int, variant: int = 0) -> None:
        publisher = self._publishers.get(variant)
        if publisher is None:
            publisher = self._publishers[variant] = AdsPublisher(self._world, variant)
        assert self.out is not None
        publisher.publish(sink, tick, t_ns, self.out)

    def digest(self) -> dict[str, np.ndarray]:
        assert self.out is not None
        return output_digest(self.out)


def resolve_params(scenario: Scenario, params: ParamsLike) -> ParamSet:
    """Scenario overrides, then the caller's overrides on top."""
    merged = dict(scenario.ego.params)
    if isinstance(params, ParamSet):
        merged.update(params.overrides())
    elif params:
        merged.update(params)
    return ParamSet(merged, source=f"scenario {scenario.name}")


def simulate_batch(
    scenarios: Scenario | Sequence[Scenario],
    params: Sequence[ParamsLike] | None = None,
    seeds: Sequence[int] | None = None,
    *,
    track_outputs: bool = False,
    oracle_modules: OracleModules = frozenset(),
    outputs: Mapping[int, str | os.PathLike[str]] | None = None,
) -> BatchResult:
    """Simulate N variants together with the built-in ADS (batch mode; records only the
    variants named in ``outputs``).

    Args:
        scenarios: one scenario (repeated to match ``params``/``seeds``) or N variants of one
            structure (same map, ego route and entity ids; properties may differ).
        params: N parameter override mappings (or ParamSets), applied on top of each
            scenario's own ``ego.params``; None means none.
        seeds: N seeds; None means each scenario's seed.
        track_outputs: also return per-module output fingerprints (``digests``, columns in
            :data:`MODULE_ORDER`).
        oracle_modules: modules whose output is replaced by ground truth (module
            substitution, :mod:`rocas.stacks.ads.oracle`): one set of names for every variant, or N
            sets; empty (the default) runs the ADS as it is.

        outputs: variant -> MCAP file: that variant is also recorded, the very file
            :func:`simulate` with ``output`` writes for it alone.

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
    sets = [resolve_params(s, p) for s, p in zip(scenarios, params, strict=True)]
    return engine.simulate_batch(scenarios, ads_factory(sets, oracle_modules), seeds,
                                 digest_modules=MODULE_ORDER if track_outputs else None,
                                 outputs=outputs, channels=CHANNELS,
                                 param_overrides=[p.overrides() for p in sets] if outputs else None)


def simulate(
    scenario: Scenario,
    params: ParamsLike = None,
    seed: int | None = None,
    *,
    output: str | os.PathLike[str] | None = None,
    on_tick: Callable[[int], None] | None = None,
) -> RunResult:
    """Simulate one run with the built-in ADS (recording mode): with ``output``, write an MCAP
    recording with every module's messages, the topology metadata and the static world
    attachment."""
    pset = resolve_params(scenario, params)
    return engine.simulate(scenario, ads_factory([pset]), seed, output=output,
                           channels=CHANNELS, param_overrides=pset.overrides(), on_tick=on_tick)


def ads_factory(param_sets: Sequence[ParamSet], oracle_modules: OracleModules = frozenset()
                ) -> Callable[[BatchWorld], AdsRun]:
    """A :data:`rocas.sim.protocol.StackFactory` of the built-in ADS with one parameter set
    per variant."""
    return lambda world: AdsRun(world, stack_params(param_sets), oracle_modules)


__all__ = ["MODULE_ORDER", "AdsRun", "BatchResult", "ParamsLike", "RunResult", "ads_factory",
           "resolve_params", "simulate", "simulate_batch"]
