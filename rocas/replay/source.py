"""Read what replay needs from a recording: the static world, the ego's mission and pose
series, the perception obstacles (converted to world coordinates) and the recorded outcome.

One streaming pass over ``/localization/pose`` and ``/perception/obstacles`` plus one pass for
the attachment; nothing else is decoded.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas.errors import RecordingError, UsageError
from rocas.msgs import localization_pb2, perception_pb2
from rocas.recording.formats import open_recording
from rocas.recording.model import ChannelInfo
from rocas.recording.topology import (
    EGO_METADATA,
    RUN_METADATA,
    STACK_METADATA,
    WORLD_ATTACHMENT,
)
from rocas.replay.frames import ego_to_world, ego_vector_to_world, interpolate_pose, wrap
from rocas.scenarios.model import DEFAULT_STACK
from rocas.stacks.registry import get_stack

#: rocas's standard channels, which replay reads without a stack's help: the ego's pose and
#: the perceived obstacles in the ego's frame (rocas.msgs; the built-in ADS publishes them)
TOPIC_POSE = "/localization/pose"
TOPIC_OBSTACLES = "/perception/obstacles"

_NS = 1e-9
#: PerceptionObstacle.Type codes (perception.proto).
TYPE_UNKNOWN_MOVABLE, TYPE_UNKNOWN_UNMOVABLE, TYPE_PEDESTRIAN, TYPE_BICYCLE, TYPE_VEHICLE = (
    1, 2, 3, 4, 5)


@dataclass(frozen=True, eq=False)
class Detections:
    """Every published perception obstacle of a recording in world coordinates, K rows.

    Attributes:
        times: (K,) message time [s].
        track_id: (K,) perception track id.
        xy: (K, 2) centre [m]; heading: (K,) [rad]; velocity: (K, 2) [m/s] (world axes).
        size: (K, 3) length, width, height [m].
        type, sub_type: (K,) PerceptionObstacle enum codes.
        color: K colour names ("unknown" when not recognised).
    """

    times: np.ndarray
    track_id: np.ndarray
    xy: np.ndarray
    heading: np.ndarray
    velocity: np.ndarray
    size: np.ndarray
    type: np.ndarray
    sub_type: np.ndarray
    color: tuple[str, ...]

    def __len__(self) -> int:
        return int(self.times.shape[0])


@dataclass(frozen=True, eq=False)
class RecordedRun:
    """What a recording tells replay.

    Attributes:
        path: the recording.
        world: the ``rocas/world.json`` attachment (scenario format, no actors, no ego).
        ego_meta: the ``rocas.ego`` metadata record, or None.
        run_meta: the ``rocas.run`` outcome record, or None.
        ego_times: (T,) pose times [s]; ego_track: (T, 5) x, y, yaw, speed, acceleration.
        ego_lanes: T matched lane ids ("" when unmatched).
        detections: the perception obstacles.
        perception_period_s: median time between perception frames [s].
        warnings: the reader's warnings (truncation, skipped damage, undecodable messages).
        stack: the stack that made the recording (its ``rocas.stack`` record; the scenario
            format's default stack without).
    """

    path: str
    world: dict[str, Any]
    ego_meta: dict[str, str] | None
    run_meta: dict[str, str] | None
    ego_times: np.ndarray
    ego_track: np.ndarray
    ego_lanes: tuple[str, ...]
    detections: Detections
    perception_period_s: float
    warnings: tuple[str, ...] = ()
    stack: str = DEFAULT_STACK


def read_recording(path: str | os.PathLike[str]) -> RecordedRun:
    """Read a recording made by rocas (or any stack writing the same channels + attachment).

    Raises:
        RecordingError: the file lacks the world attachment, the pose or the obstacle channel.
    """
    path = str(path)
    rec = open_recording(path)  # refuses a missing file, a directory, an empty or non-MCAP one
    pose_rows: list[tuple[float, ...]] = []
    lanes: list[str] = []
    frames: list[tuple[float, Any, tuple[float, float, float] | None]] = []
    checked: set[int] = set()  # channel ids whose type has been checked
    for m in rec.decoded({TOPIC_POSE, TOPIC_OBSTACLES}):
        if m.channel.id not in checked:
            _check_type(path, m.channel)
            checked.add(m.channel.id)
        t = m.log_time_ns * _NS
        msg = m.message
        if m.channel.topic == TOPIC_POSE:
            p = msg.pose
            vx, vy = p.linear_velocity.x, p.linear_velocity.y
            h = p.heading
            pose_rows.append((t, p.position.x, p.position.y, h, float(np.hypot(vx, vy)),
                              p.linear_acceleration.x * np.cos(h)
                              + p.linear_acceleration.y * np.sin(h)))
            lanes.append(getattr(msg, "lane_id", ""))
        else:
            embedded = None
            if msg.HasField("ego_position"):
                embedded = (msg.ego_position.x, msg.ego_position.y, msg.ego_heading)
            frames.append((t, list(msg.perception_obstacle), embedded))
    stack = dict(rec.metadata).get(STACK_METADATA, {}).get("name", DEFAULT_STACK)
    foreign = False  # read through the stack's own channels (its declared read_motion)
    if not pose_rows:
        reader = _motion_reader(path, stack)
        if reader is not None:
            pose_rows, lanes, frames = _stack_motion(path, rec, stack, reader)
            foreign = True
    topics = rec.topics()
    damage = tuple(rec.report.warnings(path))
    missing = [t for t in (TOPIC_POSE, TOPIC_OBSTACLES) if t not in topics]
    if missing and not foreign:
        raise RecordingError(
            f"{path}: replay needs channel(s) {', '.join(missing)}, which the recording lacks"
            + (f"; {damage[0].removeprefix(path + ': ')}" if damage else ""),
            "replay rebuilds the ego from /localization/pose and every other actor from "
            "/perception/obstacles")
    if not pose_rows:
        raise RecordingError(f"{path}: no decodable message on {TOPIC_POSE}",
                             "the ego's pose series is what replay transforms obstacles with")
    world, damage = _world(path, rec)
    meta = dict(rec.metadata)
    pose = np.asarray(pose_rows, dtype=np.float64)
    order = np.argsort(pose[:, 0], kind="stable")
    pose, lanes = pose[order], [lanes[i] for i in order]
    ego_times = pose[:, 0]
    detections = (_agent_detections(frames) if foreign
                  else _detections(frames, ego_times, pose[:, 1:4]))
    ftimes = np.unique([f[0] for f in frames]) if foreign else np.array([f[0] for f in frames])
    period = float(np.median(np.diff(ftimes))) if len(ftimes) > 1 else 0.1
    return RecordedRun(path=path, world=world, ego_meta=meta.get(EGO_METADATA),
                       run_meta=meta.get(RUN_METADATA), ego_times=ego_times,
                       ego_track=pose[:, 1:6], ego_lanes=tuple(lanes), detections=detections,
                       perception_period_s=period if period > 0 else 0.1, warnings=damage,
                       stack=stack)


def _world(path: str, rec: Any) -> tuple[dict[str, Any], tuple[str, ...]]:
    """The static world of the ``rocas/world.json`` attachment (checked to hold a map) and
    the damage both passes over the file found."""
    world_bytes = rec.attachment(WORLD_ATTACHMENT)
    damage = tuple(rec.warnings(path))  # the message pass's and the attachment pass's
    if world_bytes is None:
        raise RecordingError(
            f"{path}: no {WORLD_ATTACHMENT} attachment (the static world: map, entities, weather)"
            + (f"; {damage[-1].removeprefix(path + ': ')}" if damage else ""),
            "replay needs it; recordings made by 'rocas simulate' carry it, "
            "'rocas annotate' does not add it")
    try:
        world = json.loads(world_bytes)
    except ValueError as exc:
        raise RecordingError(f"{path}: {WORLD_ATTACHMENT} is not valid JSON ({exc})") from exc
    lanes_ok = isinstance(world, dict) and isinstance(world.get("lanes"), list) and all(
        isinstance(ln, dict) and "id" in ln and "points" in ln for ln in world["lanes"])
    if not lanes_ok or not world["lanes"]:
        raise RecordingError(
            f"{path}: {WORLD_ATTACHMENT} holds no map (a JSON object with a non-empty 'lanes' "
            "list of lanes with 'id' and 'points')",
            "replay needs the world in rocas's scenario format (docs/scenarios.md), as "
            "'rocas simulate' writes it")
    return world, damage


_KIND_TYPES = {"vehicle": TYPE_VEHICLE, "bicycle": TYPE_BICYCLE, "pedestrian": TYPE_PEDESTRIAN}


def _motion_reader(path: str, name: str) -> Any:
    """The ``read_motion`` the registered stack ``name`` declares (:mod:`rocas.stacks.base`),
    or None when it declares none (its recordings carry the standard channels)."""
    try:
        stack = get_stack(name)
    except UsageError as exc:
        raise RecordingError(f"{path}: recorded by stack {name!r}, which is not registered here",
                             exc.hint) from None
    return getattr(stack, "read_motion", None)


def _stack_motion(path: str, rec: Any, name: str, reader: Any
                  ) -> tuple[list[tuple[float, ...]], list[str], list[Any]]:
    """The ego's pose rows and the agents of a recording made by the stack ``name``, read by
    its own ``reader``."""
    poses, agents = reader(rec)
    if not poses:
        raise RecordingError(f"{path}: no ego pose on stack {name!r}'s channels",
                             "replay rebuilds the ego from the stack's pose channel")
    return [tuple(p) for p in poses], [""] * len(poses), list(agents)


def _agent_detections(rows: list[Any]) -> Detections:
    """Detections from a stack's agent rows (:data:`rocas.stacks.base.AgentRow`, world frame)."""
    a = np.asarray([(*r[:10], _KIND_TYPES[r[10]], 0) for r in rows],
                   dtype=np.float64).reshape(-1, 12)
    return Detections(times=a[:, 0], track_id=a[:, 1].astype(np.int64), xy=a[:, 2:4],
                      heading=a[:, 4], velocity=a[:, 5:7], size=a[:, 7:10],
                      type=a[:, 10].astype(np.int64), sub_type=a[:, 11].astype(np.int64),
                      color=tuple(r[11] for r in rows))


_REPLAY_TYPES = {TOPIC_POSE: localization_pb2.LocalizationEstimate.DESCRIPTOR.full_name,
                 TOPIC_OBSTACLES: perception_pb2.PerceptionObstacles.DESCRIPTOR.full_name}


def _check_type(path: str, channel: ChannelInfo) -> None:
    """Refuse a replay channel that carries another message type than rocas's own."""
    want = _REPLAY_TYPES[channel.topic]
    if channel.message_encoding != "protobuf" or channel.schema_name != want:
        found = f"{channel.message_encoding}:{channel.schema_name or '<no schema>'}"
        raise RecordingError(
            f"{path}: replay reads {channel.topic} as protobuf:{want}, but the recording's "
            f"channel carries {found}",
            "replay rebuilds a scenario from rocas's own channel types; 'rocas diff' works on "
            "any types")


def _detections(frames: list[tuple[float, Any, tuple[float, float, float] | None]],
                pose_times: np.ndarray, pose: np.ndarray) -> Detections:
    """Obstacles of every frame, transformed with the ego pose the frame refers to: the
    pose embedded in the message when present, else the pose channel interpolated."""
    rows: list[tuple[float, ...]] = []
    colors: list[str] = []
    for t, obstacles, embedded in frames:
        if not obstacles:
            continue
        ex, ey, eh = embedded if embedded is not None else interpolate_pose(
            pose_times, pose, np.array([t]))[0]
        for o in obstacles:
            wx, wy = ego_to_world(ex, ey, eh, o.position.x, o.position.y)
            vx, vy = ego_vector_to_world(eh, o.velocity.x, o.velocity.y)
            rows.append((t, o.id, wx, wy, float(wrap(eh + o.theta)), vx, vy, o.length, o.width,
                         o.height, o.type, o.sub_type))
            colors.append(o.color or "unknown")
    a = np.asarray(rows, dtype=np.float64).reshape(-1, 12)
    return Detections(times=a[:, 0], track_id=a[:, 1].astype(np.int64), xy=a[:, 2:4],
                      heading=a[:, 4], velocity=a[:, 5:7], size=a[:, 7:10],
                      type=a[:, 10].astype(np.int64), sub_type=a[:, 11].astype(np.int64),
                      color=tuple(colors))


__all__ = ["Detections", "RecordedRun", "read_recording"]
