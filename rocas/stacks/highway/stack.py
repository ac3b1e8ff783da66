"""The registered stack ``highway``: highway-env's IDM/MOBIL ego behind rocas's stack shape.

It declares what every stack declares (modules, parameters, channels with their topology) so
``rocas params``, the diff and the CMG treat its recordings like any other. Its simulations run
in highway-env's world, not in :mod:`rocas.sim`: :func:`rocas.stacks.highway.world.simulate`
and :func:`rocas.stacks.highway.record.record` are that world's rollout, and ``build`` says so
when asked to drive rocas's own world. Its catalog, its analysis and its bench run there too,
reached through the capabilities it declares (:data:`rocas.stacks.base.CAPABILITIES`):
``catalog_entries`` and ``record_catalog`` (``rocas catalog list|record --stack highway``),
``analyze_recording`` (``rocas analyze``) and ``bench`` (``rocas bench --stack highway``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
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
              workers: int | None = None, executor: str = "local",
              progress: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
        """``rocas bench --stack highway``: its catalog analysed and scored per seed, the
        simulations on ``executor`` (:func:`rocas.stacks.highway.bench.bench`)."""
        from rocas.stacks.highway.bench import bench

        return bench(ids, seeds, workers=workers, executor=executor, progress=progress)

    def catalog_entries(self) -> list[dict[str, Any]]:
        """``rocas catalog list --stack highway``: its catalog (``catalog/h*.toml``) with the
        ground truth, one JSON-ready row per entry (:func:`catalog_rows`)."""
        return catalog_rows()

    def record_catalog(self, ids: Sequence[str] | None, directory: Path
                       ) -> Iterator[dict[str, Any]]:
        """``rocas catalog record DIR --stack highway``: each entry's accident recorded to
        ``directory/<key>.mcap``, one row per recording as it is written
        (:func:`record_entries`)."""
        return record_entries(ids, directory)

    def build(self, world: Any, params: Mapping[str, np.ndarray]) -> Any:
        raise UsageError("the highway stack drives in highway-env's world, not rocas's own",
                         "simulate it with rocas.stacks.highway.world.simulate "
                         "(python -m rocas.stacks.highway)")


def highway_stack() -> HighwayStack:
    return HighwayStack()


def accident_text(run: Any) -> str:
    """What a run ended in: ``collision at 7.2 s``, ``off road at 3.0 s`` or ``no accident``."""
    what = "collision" if run.collided else "off road" if run.off_road else "no accident"
    return what + ("" if run.accident_t_s is None else f" at {run.accident_t_s:.1f} s")


def catalog_rows() -> list[dict[str, Any]]:
    """Every catalog entry as a row: ``id`` (``h01``), ``key``, ``title``, ``world`` (the
    highway-env environment), ``seed``, ``params`` (the overrides that make the accident),
    and its ground truth: ``module``, ``parameters`` and ``fix`` (parameter -> value; empty
    when no configuration avoids it), ``fixable``."""
    from rocas.stacks.highway.accidents import entries

    return [{"id": e.key.split("_", 1)[0], "key": e.key, "title": e.title,
             "world": e.scene.env_id, "seed": e.seed, "params": dict(e.params),
             "module": e.module or None, "parameters": [e.parameter] if e.parameter else [],
             "fix": {e.parameter: e.fix} if e.parameter else {}, "fixable": bool(e.parameter)}
            for e in entries()]


def record_entries(ids: Sequence[str] | None, directory: Path) -> Iterator[dict[str, Any]]:
    """Record the entries ``ids`` (default all) with their misconfiguration at their seed to
    ``directory/<key>.mcap``; per recording, once written: ``id``, ``key``, ``path``,
    ``outcome`` (:func:`accident_text`) and ``documented`` (it ends in an accident, as the
    entry documents).

    Raises:
        ScenarioError: an unknown entry (before anything is recorded).
    """
    from rocas.stacks.highway.accidents import entries, entry
    from rocas.stacks.highway.record import record

    chosen = [entry(i) for i in ids] if ids else entries()
    for e in chosen:
        path = directory / f"{e.key}.mcap"
        run = record(e.scene, path, dict(e.params), e.seed)
        yield {"id": e.key.split("_", 1)[0], "key": e.key, "path": str(path),
               "outcome": accident_text(run), "documented": run.accident}
