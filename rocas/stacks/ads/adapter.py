"""The built-in ADS as a registered stack (``ads``), declared like any other.

Its inventory and channels are the ADS's own (:mod:`rocas.stacks.ads.params`,
:mod:`rocas.stacks.ads.topics`); :meth:`AdsStackAdapter.build` makes the
:class:`rocas.stacks.ads.run.AdsRun` the engine steps. What it declares besides the protocol
(:data:`rocas.stacks.base.CAPABILITIES`): its tracker (replay undoes it), the parameters the
cyber search must not lower or raise, module substitution (the confidence phase's second
opinion), recording several rows of a batch in one pass, and its catalog folder. Replay reads
its motion from rocas's standard pose and obstacle channels, which it publishes.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rocas.sim.world import BatchWorld
from rocas.stacks.ads import params, topics
from rocas.stacks.ads.oracle import SUBSTITUTABLE
from rocas.stacks.ads.perception import POSITION_GAIN
from rocas.stacks.ads.run import AdsRun
from rocas.stacks.ads.stack import OracleModules
from rocas.stacks.base import AlphaBetaTracker, ChannelSpec, ParamSpec


class AdsStackAdapter:
    """The built-in ADS behind :class:`rocas.stacks.base.Stack`."""

    name = "ads"
    catalog = "ads"
    recordings = ""  # the catalog's recordings sit at the top of recordings/
    variant_families = True
    records_rows = True
    braking_limits: frozenset[str] = params.BRAKING_LIMITS
    sensing_limits: frozenset[str] = params.SENSING_LIMITS
    pace_limits: frozenset[str] = params.PACE_LIMITS
    substitutable: tuple[str, ...] = SUBSTITUTABLE

    def __init__(self) -> None:
        self.modules: tuple[str, ...] = params.MODULES
        self.parameters: tuple[ParamSpec, ...] = tuple(params.parameters())
        self.channels: tuple[ChannelSpec, ...] = topics.CHANNELS

    def tracker(self, values: Mapping[str, float]) -> AlphaBetaTracker:
        """The perception module's alpha-beta tracker with ``values`` (full names; missing
        ones at their defaults)."""

        def value(name: str) -> float:
            return float(values.get(name, params.PARAMETERS[name].default))

        return AlphaBetaTracker(POSITION_GAIN, value("perception.velocity_filter_alpha"),
                                int(value("perception.track_min_hits")) - 1)

    def build(self, world: BatchWorld, values: Mapping[str, np.ndarray],
              oracle_modules: OracleModules = frozenset()) -> AdsRun:
        return AdsRun(world, values, oracle_modules)


def ads_stack() -> AdsStackAdapter:
    return AdsStackAdapter()
