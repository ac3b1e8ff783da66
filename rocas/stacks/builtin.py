"""The built-in ADS (:mod:`rocas.stacks.ads`) as a registered stack (``ads``).

Its inventory and channels are the ADS's own; :meth:`AdsStackAdapter.build` drives the same
:class:`rocas.stacks.ads.stack.AdsStack` the simulator's engine does, through the stack protocol.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from rocas.stacks.base import AlphaBetaTracker, ChannelSpec, ParamSpec

if TYPE_CHECKING:
    from rocas.stacks.ads.run import AdsRun


class AdsStackAdapter:
    name = "ads"

    def __init__(self) -> None:
        from rocas.stacks.ads import params, topics

        self.modules: tuple[str, ...] = params.MODULES
        self.parameters: tuple[ParamSpec, ...] = tuple(params.parameters())  # ads Param is ParamSpec
        self.channels: tuple[ChannelSpec, ...] = topics.CHANNELS  # ads Channel is ChannelSpec

    def tracker(self, params: Mapping[str, float]) -> AlphaBetaTracker:
        """The perception module's alpha-beta tracker with ``params`` (full names; missing
        ones at their defaults)."""
        from rocas.stacks.ads.perception import POSITION_GAIN

        def value(name: str) -> float:
            spec = next(p for p in self.parameters if p.full_name == name)
            return float(params.get(name, spec.default))

        return AlphaBetaTracker(POSITION_GAIN, value("perception.velocity_filter_alpha"),
                                int(value("perception.track_min_hits")) - 1)

    def build(self, world: object, params: Mapping[str, np.ndarray]) -> AdsRun:
        from rocas.stacks.ads.run import AdsRun  # the one the simulator's engine drives

        return AdsRun(world, params)  # type: ignore[arg-type]


def ads_stack() -> AdsStackAdapter:
    return AdsStackAdapter()
