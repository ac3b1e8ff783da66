"""Recording -> scenario: the static world from the attachment, the ego from its metadata (or
its pose channel), every other actor from the perception obstacles, and the recorded accident.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas._limits import MAX_DEPTH, check_depth
from rocas.errors import InputError, RecordingError, ScenarioError, UsageError
from rocas.replay.lanes import project
from rocas.replay.paths import actor_from_track
from rocas.replay.source import RecordedRun, read_recording
from rocas.replay.tracks import Track, build_tracks
from rocas.scenarios.loader import scenario_from_dict
from rocas.scenarios.model import EGO_LENGTH_M, EGO_WIDTH_M, Ego, Scenario
from rocas.sim.geometry import box_gap
from rocas.sim.oracles import HARD_BRAKE_MPS2, MOVED_MPS, STANDSTILL_MPS, UNEXPECTED_STOP_S
from rocas.stacks.base import AlphaBetaTracker

#: How far (s) a track is extrapolated past its ends when naming a collision partner.
PARTNER_EXTRAPOLATION_S = 1.0
#: Largest distance [m] and speed difference [m/s] between the start the ``rocas.ego`` record
#: describes and the first recorded pose that still count as the same start (the recorded
#: pose carries localization noise: at most 0.04 m and 0.04 m/s over the shipped catalog).
START_TOLERANCE_M = 0.5
START_TOLERANCE_MPS = 0.5


@dataclass(frozen=True)
class AccidentInfo:
    """An accident: ``kind`` "collision" or "emergency", when [s] and with whom.

    ``other`` is the collision partner's id in the replayed scenario (``obstacle_<track>`` for
    actors, the map id for cones, boxes and buildings); None for emergencies.
    """

    kind: str
    time_s: float | None
    other: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "time_s": self.time_s, "other": self.other}


@dataclass(frozen=True, eq=False)
class Reconstruction:
    """A recording turned into a scenario.

    Attributes:
        scenario: the replayable scenario (world, ego mission and parameters, actors).
        original: the recorded accident, or None for a clean recording.
        ego_track: (T, 5) recorded ego x [m], y [m], yaw [rad], speed [m/s], acc [m/s^2].
        times: (T,) times of ``ego_track`` [s].
        tracks: the obstacle tracks the actors were built from.
        original_summary: the recorder's one-line outcome ("" when absent).
        recorded_partner: the recorder's name of the collision partner (simulator id).
        notes: assumptions made (missing metadata, unrecognised colours, ...), and the
            recording's damage (the lines of ``warnings`` come first).
        path: the recording.
        original_emergency_s: when the recorded run, which ended in a collision, had braked
            hard or stopped in an emergency before it (the earlier of the two) [s]; None
            otherwise.
        warnings: what the reader found: damage (truncation, skipped chunks, counts that
            disagree with the summary section), undecodable messages, and parts of the
            recording that disagree (the start the ``rocas.ego`` record describes is not where
            the first recorded pose is), one line each. Empty when the whole recording was read
            and agrees with itself; a reconstruction with warnings may differ from the one the
            whole, undamaged file would give.
    """

    scenario: Scenario
    original: AccidentInfo | None
    ego_track: np.ndarray
    times: np.ndarray
    tracks: tuple[Track, ...] = ()
    original_summary: str = ""
    recorded_partner: str | None = None
    notes: tuple[str, ...] = ()
    path: str = ""
    original_emergency_s: float | None = None
    warnings: tuple[str, ...] = ()

    @property
    def complete(self) -> bool:
        """Whether the reconstruction used the whole recording (no :attr:`warnings`)."""
        return not self.warnings


def _ego_from_meta(meta: dict[str, str]) -> dict[str, Any]:
    try:
        ego = json.loads(meta["ego"]) if meta.get("ego") else {
            "route": [r for r in meta["route"].split(",") if r],
            "start_s_m": float(meta["start_s_m"]),
            "start_lateral_m": float(meta.get("start_lateral_m") or 0.0),
            "start_speed_mps": float(meta.get("start_speed_mps") or 0.0)}
        if not isinstance(ego, dict):
            raise ValueError("not a JSON object")
        if meta.get("destination_s_m"):
            ego["destination_s_m"] = float(meta["destination_s_m"])
        flat = json.loads(meta["params"]) if meta.get("params") else None
        check_depth(ego, origin="rocas.ego metadata")
        check_depth(flat, origin="rocas.run params")
        if flat is not None and not isinstance(flat, dict):
            raise ValueError("params: not a JSON object")
    except (KeyError, ValueError) as exc:
        raise RecordingError(f"rocas.ego metadata is malformed ({exc})") from exc
    except RecursionError:
        raise RecordingError(f"rocas.ego metadata is malformed (nested more than {MAX_DEPTH} "
                             "levels deep)") from None
    except InputError as exc:
        raise RecordingError(f"rocas.ego metadata is malformed ({exc.message})") from None
    if flat is not None:  # the overrides in force in the recorded run (scenario's + --set)
        nested: dict[str, dict[str, float]] = {}
        for name, value in flat.items():
            module, _, short = name.partition(".")
            nested.setdefault(module, {})[short] = value
        ego["params"] = nested
    return ego


def _ego_from_pose(rec: RecordedRun, scenario_dict: dict[str, Any]) -> dict[str, Any]:
    """Mission from the pose channel alone: the sequence of matched lanes, the first pose."""
    route: list[str] = []
    for lane in rec.ego_lanes:
        if lane and (not route or route[-1] != lane):
            route.append(lane)
    if not route:
        raise RecordingError(
            f"{rec.path}: no rocas.ego metadata and no lane ids on /localization/pose",
            "replay needs the ego's route: record with 'rocas simulate'")
    lanes = {ln["id"]: ln for ln in scenario_dict["lanes"]}
    route = [r for r in route if r in lanes]
    if not route:
        raise RecordingError(
            f"{rec.path}: none of the lanes /localization/pose names is in the map of "
            "rocas/world.json", "the pose's lane_id must name lanes of the recorded world")
    pts = np.vstack([np.asarray(lanes[r]["points"], dtype=np.float64) for r in route])
    p = rec.ego_track[0, :2]
    s, lat, _ = project(pts, p)
    return {"route": route, "start_s_m": s, "start_lateral_m": float(np.clip(lat, -5, 5)),
            "start_speed_mps": float(rec.ego_track[0, 3]), "params": {}}


_TIME_RE = {"hard_brake": re.compile(r"hard brake at t=([0-9.]+) s"),
            "estop": re.compile(r"estop at t=([0-9.]+) s")}


def unexpected_stop_time(times: np.ndarray, ego: np.ndarray) -> float | None:
    """When the ego had stood still for the oracle's 2 s after having moved (speed only; the
    oracle also asks that planning gave no traffic reason)."""
    moved = np.maximum.accumulate(ego[:, 3] > MOVED_MPS)
    standing = (ego[:, 3] < STANDSTILL_MPS) & moved
    start = None
    for i, s in enumerate(standing.tolist()):
        if not s:
            start = None
            continue
        start = times[i] if start is None else start
        if times[i] - start >= UNEXPECTED_STOP_S - 1e-9:
            return float(times[i])
    return None


def _original_accident(rec: RecordedRun, notes: list[str]) -> tuple[str, float | None, str | None,
                                                                     str]:
    """(kind or "", time, recorder's partner name, summary) of the recorded run."""
    run = rec.run_meta
    if run is not None:
        summary = run.get("outcome", "")
        if run.get("collided") == "true":
            t = run.get("collision_time_s")
            return "collision", float(t) if t else None, run.get("collision_with") or None, summary
        if run.get("emergency") == "true":
            times = [float(run[k]) for k in ("hard_brake_time_s", "estop_time_s") if run.get(k)]
            if "hard_brake_time_s" not in run:  # recorded before the times were kept as fields
                times = [float(m.group(1)) for r in _TIME_RE.values() if (m := r.search(summary))]
            t = min(times) if times else unexpected_stop_time(rec.ego_times, rec.ego_track)
            return "emergency", t, None, summary
        return "", None, None, summary
    notes.append("no rocas.run record: the original accident is judged from the pose channel "
                 "(hard braking only; collisions cannot be seen)")
    hard = np.flatnonzero(-rec.ego_track[:, 4] > HARD_BRAKE_MPS2)
    if len(hard):
        return "emergency", float(rec.ego_times[hard[0]]), None, ""
    return "", None, None, ""


def _emergency_before_collision(rec: RecordedRun, kind: str, collision_s: float | None
                                ) -> float | None:
    """The recorded run's emergency time (hard brake or estop, the earlier) when it came
    before its collision; None otherwise (or without the recorder's times)."""
    run = rec.run_meta
    if kind != "collision" or run is None or collision_s is None:
        return None
    times = [float(run[k]) for k in ("hard_brake_time_s", "estop_time_s") if run.get(k)]
    t = min(times) if times else None
    return t if t is not None and t < collision_s else None


def collision_partner(tracks: tuple[Track, ...], ego_pose: np.ndarray, t: float) -> str | None:
    """The track whose box was nearest the ego's box at time ``t`` (None if none was near).

    Args:
        tracks: reconstructed tracks.
        ego_pose: (3,) ego x, y, yaw at ``t``.
        t: collision time [s].
    """
    best, best_gap = None, np.inf
    for tr in tracks:
        p = tr.position_at(t, PARTNER_EXTRAPOLATION_S)
        if p is None:
            continue
        g = float(box_gap(ego_pose[0], ego_pose[1], ego_pose[2], EGO_LENGTH_M / 2,
                          EGO_WIDTH_M / 2, p[0], p[1], tr.heading_at(t), tr.size[0] / 2,
                          tr.size[1] / 2))
        if g < best_gap:
            best, best_gap = tr.name, g
    return best if best_gap < 5.0 else None


def reconstruct(path: str | os.PathLike[str]) -> Reconstruction:
    """Rebuild the scenario of a recording (see the module docstring).

    Raises:
        RecordingError: the recording lacks the world attachment or the pose/obstacle channels.
    """
    rec = read_recording(path)
    notes: list[str] = list(rec.warnings)
    world = dict(rec.world)
    head = dict(world.get("scenario", {}))
    meta = rec.ego_meta
    if meta is not None:
        ego = _ego_from_meta(meta)
        for key, conv in (("seed", int), ("dt_s", float), ("duration_s", float)):
            if meta.get(key):
                head[key] = conv(meta[key])
    else:
        notes.append("no rocas.ego metadata: the ego's route and start come from "
                     "/localization/pose and its parameters are the defaults")
        ego = _ego_from_pose(rec, world)
    ego["stack"] = rec.stack  # the stack that made the recording drives the replay
    world["scenario"] = head
    try:
        base = scenario_from_dict({**world, "ego": ego}, source=f"{rec.path}:{'rocas/world.json'}")
    except ScenarioError as exc:
        raise RecordingError(f"the recording's world does not load: {exc.message}",
                             exc.hint) from exc
    last = float(rec.ego_times[-1]) + base.dt_s
    if meta is None or not meta.get("duration_s"):
        base = dataclasses.replace(base, duration_s=round(last, 6))
    tracks = tuple(build_tracks(rec.detections, rec.perception_period_s, base.lanes,
                                _tracker(rec.stack, meta)))
    actors = tuple(actor_from_track(tr, base.lanes, base.dt_s, base.duration_s) for tr in tracks)
    for tr in tracks:
        notes.extend(f"{tr.name}: {n}" for n in tr.notes)
    scenario = dataclasses.replace(base, actors=actors, ego=_sorted_params(base.ego))
    warnings = list(rec.warnings)
    if meta is not None:
        mismatch = _start_mismatch(scenario, rec)
        if mismatch is not None:
            warnings.append(f"{rec.path}: {mismatch}")
            notes.insert(len(rec.warnings), warnings[-1])
    kind, t, partner, summary = _original_accident(rec, notes)
    original = None
    if kind:
        other = None
        if kind == "collision" and partner is not None:
            map_ids = {o.id for o in scenario.objects} | {a.id for a in scenario.areas}
            if partner in map_ids:
                other = partner
            elif t is not None:
                idx = int(np.argmin(np.abs(rec.ego_times - t)))
                other = collision_partner(tracks, rec.ego_track[idx, :3], t)
                if other is None:
                    notes.append(f"recorded partner {partner!r}: no perception track near the "
                                 f"ego at t={t:.2f} s")
        original = AccidentInfo(kind, t, other)
    return Reconstruction(scenario=scenario, original=original, ego_track=rec.ego_track,
                          times=rec.ego_times, tracks=tracks, original_summary=summary,
                          recorded_partner=partner, notes=tuple(notes), path=rec.path,
                          warnings=tuple(warnings),
                          original_emergency_s=_emergency_before_collision(rec, kind, t))


def _tracker(stack: str, meta: dict[str, str] | None) -> AlphaBetaTracker | None:
    """The obstacle tracker of the stack that made the recording, with the recorded
    parameters in force (defaults without ``rocas.ego``); None when the stack declares none."""
    from rocas.stacks.registry import get_stack

    try:
        declare = getattr(get_stack(stack), "tracker", None)
    except UsageError:
        return None
    if declare is None:
        return None
    # malformed params were refused already, when the ego's record was read
    params = json.loads(meta["params"]) if meta and meta.get("params") else {}
    return declare({str(k): float(v) for k, v in params.items()})


def _start_mismatch(scenario: Scenario, rec: RecordedRun) -> str | None:
    """How the ego's start in ``scenario`` (from the ``rocas.ego`` record) misses the first
    recorded pose, or None when they agree (or the pose series does not begin at the start)."""
    if rec.ego_times[0] > scenario.dt_s + 1e-9:  # the first poses were lost: nothing to compare
        return None
    ego = scenario.ego
    lanes = scenario.lane_by_id
    pts = np.vstack([np.asarray(lanes[r].centerline, dtype=np.float64) for r in ego.route])
    s, lat, _ = project(pts, rec.ego_track[0, :2])
    off = float(np.hypot(s - ego.start_s_m, lat - ego.start_lateral_m))
    dv = abs(float(rec.ego_track[0, 3]) - ego.start_speed_mps)
    if off <= START_TOLERANCE_M and dv <= START_TOLERANCE_MPS:
        return None
    return (f"the ego's start in the rocas.ego record (s={ego.start_s_m:.2f} m, lateral "
            f"{ego.start_lateral_m:.2f} m, {ego.start_speed_mps:.2f} m/s) is {off:.2f} m and "
            f"{dv:.2f} m/s from the first recorded pose: the record does not describe this run "
            "(damaged?), so the replayed scenario may not be the recorded one")


def _sorted_params(ego: Ego) -> Ego:
    return dataclasses.replace(ego, params=tuple(sorted(ego.params)))


__all__ = ["AccidentInfo", "Reconstruction", "collision_partner", "reconstruct",
           "unexpected_stop_time"]
