"""The built-in ADS (:mod:`rocas.ads`) as a registered stack (``ads``).

Its inventory and channels are the ADS's own; :meth:`AdsStackAdapter.build` drives the same
:class:`rocas.ads.stack.AdsStack` the simulator's engine does, through the stack protocol.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rocas.stacks.base import Actuation, ChannelSpec, MessageSink, Observation, ParamSpec


class AdsStackAdapter:
    name = "ads"

    def __init__(self) -> None:
        from rocas.ads import params, topics

        self.modules: tuple[str, ...] = params.MODULES
        self.parameters: tuple[ParamSpec, ...] = tuple(params.parameters())  # ads Param is ParamSpec
        self.channels: tuple[ChannelSpec, ...] = topics.CHANNELS  # ads Channel is ChannelSpec

    def build(self, world: object, params: Mapping[str, np.ndarray]) -> AdsRun:
        return AdsRun(world, params)


class AdsRun:
    """The ADS's modules for N variants, stepped through the protocol."""

    def __init__(self, world: object, params: Mapping[str, np.ndarray]) -> None:
        from rocas.ads.stack import AdsStack

        self.stack = AdsStack(world, dict(params))  # type: ignore[arg-type]
        self.out = None
        self.prev_xy: tuple[np.ndarray, np.ndarray] | None = None

    def step(self, obs: Observation) -> Actuation:
        from rocas.ads.planning import R_BLOCKED, R_COLL, R_CRUISE, R_FALLBACK, R_PBRAKE

        if self.prev_xy is not None:  # the odometer advances by what the ego really moved
            self.stack.canbus.advance_odometer(np.hypot(obs.ego_x - self.prev_xy[0],
                                                        obs.ego_y - self.prev_xy[1]))
        self.prev_xy = (obs.ego_x, obs.ego_y)
        d = obs.detail
        out = self.stack.step(obs.tick, d["ego"], obs.ego_accel, d["actors"], d["actor_state"])
        self.out = out
        accel, curvature = self.stack.actuate(out.control)
        reason = self.stack.plan.reason
        unjust = np.isin(reason, (R_CRUISE, R_BLOCKED, R_PBRAKE, R_COLL, R_FALLBACK))
        return Actuation(accel, curvature, out.control.estop | self.stack.plan.estop, ~unjust)

    def publish(self, sink: MessageSink, tick: int, t_ns: int) -> None:
        from rocas.errors import UsageError

        raise UsageError("the built-in ADS records through rocas.ads.run.simulate",
                         "use 'rocas simulate' for ADS recordings")

    def digest(self) -> dict[str, np.ndarray]:
        from rocas.ads.stack import output_digest

        return output_digest(self.out)


def ads_stack() -> AdsStackAdapter:
    return AdsStackAdapter()
