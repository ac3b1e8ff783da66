"""The registered stack ``highway``: highway-env's IDM/MOBIL ego behind rocas's stack shape.

It declares what every stack declares (modules, parameters, channels with their topology) so
``rocas params``, the diff and the CMG treat its recordings like any other. Its simulations run
in highway-env's world, not in :mod:`rocas.sim`: :func:`rocas.stacks.highway.world.simulate`
and :func:`rocas.stacks.highway.record.record` are that world's rollout, and ``build`` says so
when asked to drive rocas's own world.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rocas.errors import UsageError
from rocas.stacks.base import ChannelSpec, ParamSpec
from rocas.stacks.highway.params import MODULES, parameters


class HighwayStack:
    """highway-env's IDMVehicle as the system under test."""

    name = "highway"
    #: the world it drives in (rocas.stacks.base.CAPABILITIES): highway-env's, not rocas's
    world = "highway-env"
    modules: tuple[str, ...] = MODULES
    #: a cyber search may not lower this (a "fix" that brakes less only hides the accident)
    braking_limits: tuple[str, ...] = ("control.ACC_MAX",)
    #: ... nor IDM's gaps to the front vehicle (a "fix" that follows closer only hides the
    #: accident)
    margin_limits: tuple[str, ...] = ("planning.TIME_WANTED", "planning.DISTANCE_WANTED")
    #: ... nor shrink IDM's comfort accelerations (the ride's specification, not a tuning
    #: knob: a "fix" that asks for gentler acceleration or braking changes what the ride is
    #: allowed to feel, so the ego creeps up on the accident instead of avoiding it)
    comfort_limits: tuple[str, ...] = ("planning.COMFORT_ACC_MAX", "planning.COMFORT_ACC_MIN")

    @property
    def parameters(self) -> tuple[ParamSpec, ...]:
        return parameters()

    @property
    def channels(self) -> tuple[ChannelSpec, ...]:
        from rocas.stacks.highway.record import channels

        return channels()

    def analyze_recording(self, path: Path, out: Path, *, seed: int = 0,
                          workers: int | None = None, executor: str = "local") -> Any:
        """``rocas analyze`` of one of its recordings, in its own world
        (:func:`rocas.stacks.highway.analysis.analyze_recording`)."""
        from rocas.stacks.highway.analysis import analyze_recording

        return analyze_recording(path, out, seed=seed, workers=workers, executor=executor)

    def bench(self, ids: Sequence[str] | None, seeds: Sequence[int], *,
              workers: int | None = None, progress: Callable[[str], None] = lambda _: None
              ) -> dict[str, Any]:
        """``rocas bench --stack highway``: its catalog analysed and scored per seed
        (:func:`rocas.stacks.highway.analysis.bench`)."""
        from rocas.stacks.highway.analysis import bench

        return bench(ids, seeds, workers=workers, progress=progress)

    def build(self, world: Any, params: Mapping[str, np.ndarray]) -> Any:
        raise UsageError("the highway stack drives in highway-env's world, not rocas's own",
                         "simulate it with rocas.stacks.highway.world.simulate "
                         "(python -m rocas.stacks.highway)")


def highway_stack() -> HighwayStack:
    return HighwayStack()
