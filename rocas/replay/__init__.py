"""Replay: a recording -> the scenario it came from -> the same accident again.

``rocas.replay`` is this package *and* callable: ``rocas.replay("accident.mcap")`` returns the
reconstructed :class:`~rocas.scenarios.Scenario` (what the search phases mutate). The pieces:

- :mod:`~rocas.replay.frames`: ego-frame <-> world transforms;
- :mod:`~rocas.replay.source`: what a recording tells (world attachment, ego metadata and
  pose, perception obstacles in world coordinates, the recorded outcome);
- :mod:`~rocas.replay.tracks`: stitched, gap-bridged, smoothed obstacle tracks with their
  kind, model and colour;
- :mod:`~rocas.replay.lanes` and :mod:`~rocas.replay.paths`: tracks -> actors (waypoints
  extended along the map, a speed profile designed for the simulator's actor model);
- :mod:`~rocas.replay.reconstruction`: :func:`reconstruct` -> :class:`Reconstruction`;
- :mod:`~rocas.replay.run`: :func:`replay` -> :class:`ReplayReport` (closed loop, fidelity).

Heavy modules load on first use, so ``import rocas`` stays cheap.
"""

from __future__ import annotations

import os
import sys
import types
from typing import TYPE_CHECKING

from rocas._lazy import lazy_exports

if TYPE_CHECKING:
    from rocas.replay.reconstruction import AccidentInfo, Reconstruction, reconstruct
    from rocas.replay.run import ReplayReport, replay
    from rocas.scenarios.model import Scenario

_LAZY = {
    "AccidentInfo": "rocas.replay.reconstruction",
    "Reconstruction": "rocas.replay.reconstruction",
    "reconstruct": "rocas.replay.reconstruction",
    "ReplayReport": "rocas.replay.run",
    "replay": "rocas.replay.run",
    "TIME_TOLERANCE_S": "rocas.replay.run",
}


__getattr__, __dir__ = lazy_exports(__name__, globals(), _LAZY)


class _CallableModule(types.ModuleType):
    """``rocas.replay(path)`` -> the reconstructed Scenario."""

    def __call__(self, path: str | os.PathLike[str]) -> Scenario:
        from rocas.replay.reconstruction import reconstruct

        return reconstruct(path).scenario


sys.modules[__name__].__class__ = _CallableModule

__all__ = ["AccidentInfo", "Reconstruction", "ReplayReport", "TIME_TOLERANCE_S", "reconstruct",
           "replay"]
