"""Closed-loop replay of a reconstruction and its fidelity against the recording."""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rocas._fs import refuse_overwriting
from rocas.replay.reconstruction import (
    AccidentInfo,
    Reconstruction,
    reconstruct,
    unexpected_stop_time,
)
from rocas.sim.oracles import Outcome

#: Largest difference of accident times that still counts as the same accident [s].
TIME_TOLERANCE_S = 0.5


@dataclass(frozen=True, eq=False)
class ReplayReport:
    """How a replay went and how faithful it was.

    Attributes:
        reproduced: the replay had an accident of the original's kind, with the same other
            party (collisions) and within :data:`TIME_TOLERANCE_S` of its time; for a clean
            recording, the replay was clean too; or (``only_emergency``) the recorded run
            braked hard or stopped in an emergency before its collision, and the replay did
            the same within :data:`TIME_TOLERANCE_S` of that time without the collision.
        only_emergency: the replay reproduced the emergency that preceded the recorded
            collision, not the collision (a collision by a few centimetres that the replay's
            reconstructed actors miss): the accident a later analysis explains is the
            emergency.
        accident: the replay's accident (None when clean); original: the recorded one.
        outcome: the replay's full oracle outcome.
        ego_rmse_m, ego_max_error_m: ego position error against the recorded pose up to
            ``compared_until_s`` (the original accident, else the whole run) [m].
        time_error_s: replay minus original accident time [s] (None unless both have one).
        params: the ``--set`` overrides replayed with (on top of the recorded ones).
        output: the replay's recording, or None.
        wall_time_s: seconds spent simulating.
        ego: (T+1, 5) the replay's ego trajectory; times: (T+1,) [s].
        actors: (T+1, A, 4) the replay's actor trajectories (x, y, yaw, speed).
        reconstruction: what was replayed.
    """

    reproduced: bool
    accident: AccidentInfo | None
    original: AccidentInfo | None
    outcome: Outcome
    ego_rmse_m: float
    ego_max_error_m: float
    compared_until_s: float
    time_error_s: float | None
    params: dict[str, float] = field(default_factory=dict)
    output: str | None = None
    wall_time_s: float = 0.0
    ego: np.ndarray | None = None
    times: np.ndarray | None = None
    reconstruction: Reconstruction | None = None
    only_emergency: bool = False
    actors: np.ndarray | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        rec = self.reconstruction
        return {
            "recording": rec.path if rec else None,
            "scenario": rec.scenario.name if rec else None,
            "reproduced": self.reproduced,
            "only_emergency": self.only_emergency,
            "accident": self.accident.to_dict() if self.accident else None,
            "original_accident": self.original.to_dict() if self.original else None,
            "time_error_s": self.time_error_s,
            "ego_rmse_m": self.ego_rmse_m,
            "ego_max_error_m": self.ego_max_error_m,
            "compared_until_s": self.compared_until_s,
            "outcome": self.outcome.summary(),
            "original_outcome": rec.original_summary if rec else "",
            "actors": [a.id for a in rec.scenario.actors] if rec else [],
            "params": dict(self.params),
            "output": self.output,
            "wall_time_s": self.wall_time_s,
            "notes": list(rec.notes) if rec else [],
            "warnings": list(rec.warnings) if rec else [],
            "complete": rec.complete if rec else True,
        }


def accident_of(outcome: Outcome, times: np.ndarray, ego: np.ndarray) -> AccidentInfo | None:
    """The accident of a simulated run in replay terms (None when clean).

    An emergency's time is the earliest of the hard brake and the estop; an unexpected stop
    alone is timed from the ego's speed (2 s of standing after having moved).
    """
    if outcome.collided:
        return AccidentInfo("collision", outcome.collision_time_s, outcome.collision_with)
    if outcome.emergency:
        ts = [t for t in (outcome.hard_brake_time_s, outcome.estop_time_s) if t is not None]
        return AccidentInfo("emergency", min(ts) if ts else unexpected_stop_time(times, ego))
    return None


def same_accident(original: AccidentInfo | None, replayed: AccidentInfo | None) -> bool:
    """Same kind, same other party (collisions), times within :data:`TIME_TOLERANCE_S`."""
    if original is None or replayed is None:
        return original is None and replayed is None
    if original.kind != replayed.kind:
        return False
    if original.kind == "collision" and original.other != replayed.other:
        return False
    if original.time_s is None or replayed.time_s is None:
        return original.time_s is None and replayed.time_s is None
    return abs(original.time_s - replayed.time_s) <= TIME_TOLERANCE_S + 1e-9


def emergency_before_collision(rec: Reconstruction, replayed: AccidentInfo | None) -> bool:
    """Whether the replay, without the recorded collision, had the emergency that preceded
    it in the recording (within :data:`TIME_TOLERANCE_S`)."""
    t = rec.original_emergency_s
    return (t is not None and replayed is not None and replayed.kind == "emergency"
            and replayed.time_s is not None and abs(replayed.time_s - t) <= TIME_TOLERANCE_S + 1e-9)


def trajectory_error(rec_times: np.ndarray, rec_ego: np.ndarray, sim_times: np.ndarray,
                     sim_ego: np.ndarray, until_s: float) -> tuple[float, float]:
    """(RMSE, max) of the ego position distance at the recorded times <= ``until_s`` [m].

    Args:
        rec_times: (T,) recorded pose times; rec_ego: (T, >=2) recorded x, y.
        sim_times: (S,) replay times; sim_ego: (S, >=2) replay x, y.
    """
    sel = rec_times <= until_s + 1e-9
    if not sel.any():
        return 0.0, 0.0
    t = rec_times[sel]
    x = np.interp(t, sim_times, sim_ego[:, 0])
    y = np.interp(t, sim_times, sim_ego[:, 1])
    d = np.hypot(x - rec_ego[sel, 0], y - rec_ego[sel, 1])
    return float(np.sqrt(np.mean(d * d))), float(d.max())


def replay(source: Reconstruction | str | os.PathLike[str],
           params: Mapping[str, float] | None = None,
           output: str | os.PathLike[str] | None = None) -> ReplayReport:
    """Re-run a recording's scenario closed-loop and judge the reproduction.

    Args:
        source: a :class:`Reconstruction` or a recording path.
        params: ADS parameter overrides on top of the recorded ones (a what-if).
        output: write the replay's recording here (atomically), or None.

    Raises:
        UsageError: ``output`` is the recording being replayed.
    """
    from rocas.rollout import simulate

    if output is not None and not isinstance(source, Reconstruction):
        refuse_overwriting(source, output)
    rec = source if isinstance(source, Reconstruction) else reconstruct(source)
    params = dict(params or {})
    start = time.perf_counter()
    run = simulate(rec.scenario, params or None, output=output)
    wall = time.perf_counter() - start
    accident = accident_of(run.outcome, run.times, run.ego)
    until = rec.original.time_s if rec.original and rec.original.time_s is not None \
        else float(rec.times[-1])
    rmse, worst = trajectory_error(rec.times, rec.ego_track, run.times, run.ego, until)
    terr = None
    if rec.original and accident and rec.original.time_s is not None \
            and accident.time_s is not None:
        terr = accident.time_s - rec.original.time_s
    reproduced = same_accident(rec.original, accident)
    only_emergency = not reproduced and emergency_before_collision(rec, accident)
    return ReplayReport(
        reproduced=reproduced or only_emergency, only_emergency=only_emergency,
        accident=accident,
        original=rec.original, outcome=run.outcome, ego_rmse_m=rmse, ego_max_error_m=worst,
        compared_until_s=until, time_error_s=terr, params=params,
        output=run.recording, wall_time_s=wall, ego=run.ego, times=run.times,
        reconstruction=rec, actors=run.actors)


__all__ = ["ReplayReport", "TIME_TOLERANCE_S", "accident_of", "emergency_before_collision",
           "replay", "same_accident",
           "trajectory_error"]
