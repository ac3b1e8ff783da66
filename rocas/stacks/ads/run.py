"""The built-in ADS in the simulator: its run behind :mod:`rocas.sim.protocol`.

:class:`AdsRun` steps :class:`rocas.stacks.ads.stack.AdsStack` for the engine: it turns the
modules' control command into an actuation, tells the oracles whether the held plan names a
traffic reason to stand (:data:`rocas.stacks.ads.planning.STOP_JUSTIFIED`), publishes the
channels (:class:`rocas.stacks.ads.recorder.AdsPublisher`, any row of a batch) and fingerprints
each module's output. The rollout (:mod:`rocas.rollout`) builds it through the registered
stack (:mod:`rocas.stacks.ads.adapter`), as it builds every stack.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rocas.sim.protocol import Actuation, MessageSink, Observation
from rocas.sim.world import BatchWorld
from rocas.stacks.ads.planning import STOP_JUSTIFIED
from rocas.stacks.ads.recorder import AdsPublisher
from rocas.stacks.ads.stack import AdsStack, OracleModules, TickOutputs, output_digest


class AdsRun:
    """The ADS's modules for N variants, stepped through :class:`rocas.sim.protocol.StackRun`.

    Args:
        world: the compiled batch.
        params: every parameter as an (N,) array, one value per variant
            (:func:`rocas.stacks.base.batch_params` of one full assignment per variant).
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


__all__ = ["AdsRun"]
