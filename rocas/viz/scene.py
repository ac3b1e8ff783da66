"""The top-down scene of one execution: read a recording once, log it on the ``sim_time`` timeline.

What is shown is learnt from the file, not from topic names: a channel whose messages carry a
``pose`` (``position`` + ``heading``) is the ego pose; a repeated field whose elements carry an id
(``id``/``uid``/``track_id``) and a position (``position``/``pos``/``center``) is an obstacle list
(in the ego frame when the message also carries ``ego_position``/``ego_heading``); a repeated field
of ``x``/``y`` points at the top level is the ego's planned trajectory, nested deeper it is a
predicted trajectory. rocas's own recordings also carry the static world (``rocas/world.json``)
and the outcome (``rocas.run`` metadata).

Entities, under ``<prefix>`` (e.g. ``executions/accident``)::

    world/roads, world/lane_edges, world/centerlines   lanes (static)
    world/areas/buildings, world/areas/vegetation       map areas (static)
    world/objects                                       cones and boxes (static)
    world/stop_lines, world/traffic_lights              coloured by the light state over time
    world/highlight                                     the mutated map entity (static)
    ego/box, ego/trail, ego/plan                        ego outline, fading trail, plan
    actors/boxes, actors/trails, actors/predictions     every obstacle, per frame
    actors/highlight                                    the mutated actor, per frame
    accident                                            where and when the accident happens
    events                                              the outcome as a text log line
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rocas.scenarios.model import (
    COLORS,
    CYCLIST_DIMENSIONS,
    EGO_LENGTH_M,
    EGO_WIDTH_M,
    OBJECT_DIMENSIONS,
    PEDESTRIAN_DIMENSIONS,
    VEHICLE_DIMENSIONS,
)

TIMELINE = "sim_time"
WORLD_ATTACHMENT = "rocas/world.json"
RUN_METADATA = "rocas.run"
EGO_METADATA = "rocas.ego"

EGO_COLOR = (0, 190, 255)
HIGHLIGHT_COLOR = (255, 215, 0)
ACCIDENT_COLOR = (230, 20, 20)
LIGHT_RGB = {"red": (230, 30, 30), "yellow": (250, 200, 0), "green": (40, 200, 60), "off": (60, 60, 60)}
ROAD_RGB = (62, 64, 70)
BACKGROUND_RGB = (176, 186, 168)
TRAIL_S = 3.0  # how far back a trail reaches [s]
TRAIL_STEP_S = 0.1  # spacing of trail points [s]
_PALETTE = [
    (230, 25, 75),
    (60, 180, 75),
    (255, 225, 25),
    (0, 130, 200),
    (245, 130, 48),
    (145, 30, 180),
    (70, 240, 240),
    (240, 50, 230),
    (210, 245, 60),
    (250, 190, 212),
]
_SUBTYPE_TO_MODEL = {
    "CAR": "sedan",
    "SUV": "suv",
    "TRUCK": "truck",
    "BUS": "bus",
    "CYCLIST": "cyclist",
    "PEDESTRIAN": "pedestrian",
}

_ID_FIELDS = ("id", "uid", "track_id", "object_id")
_POS_FIELDS = ("position", "pos", "center", "location")
_HEADING_FIELDS = ("heading", "theta", "yaw")
_NUMERIC = {1, 2, 3, 4, 5, 6, 7, 8, 13, 14, 15, 16, 17, 18}  # FieldDescriptor.TYPE_* (no string/bytes/msg)
_TYPE_MESSAGE = 11
_TYPE_ENUM = 14


# --------------------------------------------------------------------------------------------
# data read from a recording


@dataclass
class ObstacleFrame:
    """Obstacles seen at one time, world frame.

    Attributes:
        t: time since the recording's start [s].
        ids: track ids as strings, (k,).
        xy: centres (k, 2) [m]; heading: (k,) [rad]; size: (k, 2) length, width [m].
        kinds: e.g. "truck", "cyclist"; colors: colour names ("" when unknown).
    """

    t: float
    ids: list[str]
    xy: np.ndarray
    heading: np.ndarray
    size: np.ndarray
    kinds: list[str]
    colors: list[str]


@dataclass
class ChannelSeries:
    """Numeric fields of one channel over time: ``values`` (n, k) for ``names`` (k,)."""

    topic: str
    times_s: np.ndarray
    names: list[str]
    values: np.ndarray


@dataclass
class Execution:
    """What one recording shows (one pass over the file).

    Attributes:
        path: the recording.
        t0_ns: log time taken as ``sim_time`` 0 (the first message) [ns].
        duration_s: last message time relative to ``t0_ns`` [s].
        world: the ``rocas/world.json`` attachment, or None.
        run: the ``rocas.run`` metadata (outcome), or {}.
        actors: the scenario's actors from ``rocas.ego`` metadata (id, kind, model, colour).
        ego_t, ego_xy, ego_heading: ego pose series (n,), (n, 2), (n,) (empty without a pose).
        obstacles: obstacle frames in time order.
        plans: (t, points (k, 2)) of the ego's planned trajectory.
        predictions: (t, owner ids, polylines) of predicted obstacle trajectories.
        channels: numeric series per channel topic.
        events: (t, channel, text) changes of enumerations and decisions.
        topology: topic -> (writers, readers, role).
        sources: what was interpreted as what, e.g. {"pose": "/localization/pose"}.
    """

    path: Path
    t0_ns: int = 0
    duration_s: float = 0.0
    world: dict[str, Any] | None = None
    run: dict[str, str] = field(default_factory=dict)
    actors: list[dict[str, Any]] = field(default_factory=list)
    ego_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    ego_xy: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    ego_heading: np.ndarray = field(default_factory=lambda: np.zeros(0))
    obstacles: list[ObstacleFrame] = field(default_factory=list)
    plans: list[tuple[float, np.ndarray]] = field(default_factory=list)
    predictions: list[tuple[float, list[str], list[np.ndarray]]] = field(default_factory=list)
    channels: dict[str, ChannelSeries] = field(default_factory=dict)
    events: list[tuple[float, str, str]] = field(default_factory=list)
    topology: dict[str, tuple[str, str, str]] = field(default_factory=dict)
    sources: dict[str, str] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)

    def ego_at(self, t: float) -> tuple[float, float, float] | None:
        """Ego (x, y, heading) at time ``t`` [s] (nearest pose), or None without a pose."""
        if len(self.ego_t) == 0:
            return None
        i = int(np.clip(np.searchsorted(self.ego_t, t), 0, len(self.ego_t) - 1))
        if i > 0 and abs(self.ego_t[i - 1] - t) < abs(self.ego_t[i] - t):
            i -= 1
        return float(self.ego_xy[i, 0]), float(self.ego_xy[i, 1]), float(self.ego_heading[i])

    def accident(self) -> tuple[float, str, tuple[float, float] | None] | None:
        """(time [s], description, position or None) of the recorded accident, if any."""
        outcome = self.run.get("outcome", "")
        if self.run.get("collided") == "true" and self.run.get("collision_time_s"):
            t = float(self.run["collision_time_s"])
            m = re.search(r"x=(-?[\d.]+) y=(-?[\d.]+)", outcome)
            pos = (float(m.group(1)), float(m.group(2))) if m else None
            return t, f"collision with {self.run.get('collision_with') or 'an obstacle'}", pos
        m = re.search(r"hard brake at t=([\d.]+) s", outcome)
        if m:
            return float(m.group(1)), "hard brake", None
        return None


# --------------------------------------------------------------------------------------------
# interpreting messages by their fields


def _fields(msg: Any) -> dict[str, Any]:
    return msg.DESCRIPTOR.fields_by_name


def _has_xy(desc: Any) -> bool:
    return "x" in desc.fields_by_name and "y" in desc.fields_by_name


def _point_getter(desc: Any) -> Any:
    """A function element -> (x, y) for an element type that is or holds a point, else None."""
    f = desc.fields_by_name
    if _has_xy(desc) and f["x"].type in _NUMERIC:
        return lambda e: (e.x, e.y)
    for name in _POS_FIELDS:
        if (
            name in f
            and f[name].type == _TYPE_MESSAGE
            and not f[name].is_repeated
            and _has_xy(f[name].message_type)
        ):
            return lambda e, n=name: (getattr(e, n).x, getattr(e, n).y)
    return None


def _first(f: dict[str, Any], names: Iterable[str], types: set[int] | None = None) -> str | None:
    for n in names:
        if n in f and not f[n].is_repeated and (types is None or f[n].type in types):
            return n
    return None


def _pose_path(desc: Any) -> tuple[str, ...] | None:
    """Field path to a message with a position and a heading (the ego pose), or None."""
    f = desc.fields_by_name
    if "pose" in f and f["pose"].type == _TYPE_MESSAGE:
        inner = _pose_path(f["pose"].message_type)
        if inner is not None:
            return ("pose", *inner)
    if _first(f, _POS_FIELDS, {_TYPE_MESSAGE}) and _first(f, _HEADING_FIELDS, _NUMERIC):
        pos = f[_first(f, _POS_FIELDS, {_TYPE_MESSAGE})]
        if _has_xy(pos.message_type):
            return ()
    return None


def _obstacle_field(desc: Any) -> str | None:
    """The repeated field whose elements are obstacles (an id and a position), or None."""
    for fd in desc.fields:
        if fd.is_repeated and fd.type == _TYPE_MESSAGE:
            ef = fd.message_type.fields_by_name
            if (
                _first(ef, _ID_FIELDS)
                and _point_getter(fd.message_type) is not None
                and not _has_xy(fd.message_type)
            ):
                return fd.name
    return None


def _polyline_paths(desc: Any, depth: int = 0) -> list[tuple[str, ...]]:
    """Paths of repeated fields (through repeated elements) whose elements are points."""
    out: list[tuple[str, ...]] = []
    if depth > 3:
        return out
    for fd in desc.fields:
        if fd.type != _TYPE_MESSAGE or "polygon" in fd.name:
            continue
        if fd.is_repeated:
            if _point_getter(fd.message_type) is not None and (
                _has_xy(fd.message_type) or not _first(fd.message_type.fields_by_name, _ID_FIELDS)
            ):
                out.append((fd.name,))
            else:
                out += [(fd.name, *p) for p in _polyline_paths(fd.message_type, depth + 1)]
    return out


def _numeric_paths(desc: Any, depth: int = 0) -> list[tuple[str, ...]]:
    """Paths of singular numeric/bool/enum fields (headers and stamps left out)."""
    out: list[tuple[str, ...]] = []
    for fd in desc.fields:
        if fd.is_repeated or fd.name in ("header", "stamp"):
            continue
        if fd.type in _NUMERIC:
            out.append((fd.name,))
        elif (
            fd.type == _TYPE_MESSAGE
            and depth < 2
            and fd.message_type.name not in ("Header", "Stamp", "Timestamp")
        ):
            out += [(fd.name, *p) for p in _numeric_paths(fd.message_type, depth + 1)]
    return out[:64]


def _enum_paths(desc: Any, depth: int = 0) -> list[tuple[str, ...]]:
    out: list[tuple[str, ...]] = []
    for fd in desc.fields:
        if fd.is_repeated or fd.name in ("header", "stamp"):
            continue
        if fd.type == _TYPE_ENUM:
            out.append((fd.name,))
        elif fd.type == _TYPE_MESSAGE and depth < 1:
            out += [(fd.name, *p) for p in _enum_paths(fd.message_type, depth + 1)]
    return out


def _get(msg: Any, path: tuple[str, ...]) -> Any:
    for name in path:
        msg = getattr(msg, name)
    return msg


def _enum_name(desc: Any, path: tuple[str, ...], value: int) -> str:
    for name in path[:-1]:
        desc = desc.fields_by_name[name].message_type
    ev = desc.fields_by_name[path[-1]].enum_type.values_by_number.get(value)
    return ev.name if ev is not None else str(value)


def _priority(topic: str, schema: str, words: tuple[str, ...]) -> int:
    text = f"{topic} {schema}".lower()
    return 0 if any(w in text for w in words) else 1


def _prefer(topic: str, schema: str, current: str | None, words: tuple[str, ...]) -> bool:
    """Whether ``topic`` should replace ``current`` as the source of one kind of data: the
    first candidate, or one whose name says it is that kind when the current one's does not."""
    return current is None or _priority(topic, schema, words) < _priority(current, "", words)


class _ChannelReader:
    """How one channel's messages are read (decided from the first message's descriptor)."""

    def __init__(self, topic: str, schema: str, msg: Any) -> None:
        self.topic = topic
        self.desc = desc = msg.DESCRIPTOR
        self.pose = _pose_path(desc)
        self.obstacles = _obstacle_field(desc)
        self.ego_frame = "ego_position" in desc.fields_by_name and "ego_heading" in desc.fields_by_name
        polylines = [] if self.obstacles else _polyline_paths(desc)
        self.plan = next((p for p in polylines if len(p) == 1), None)
        self.prediction = next((p for p in polylines if len(p) > 1), None)
        self.numeric = _numeric_paths(desc)
        self.enums = _enum_paths(desc)
        self.object_decision = "object_decision" in desc.fields_by_name
        self.schema = schema
        self.times: list[float] = []
        self.rows: list[list[float]] = []
        self.last_enums: tuple[int, ...] | None = None
        self.last_decisions: str | None = None
        if self.obstacles:
            et = desc.fields_by_name[self.obstacles].message_type
            ef = et.fields_by_name
            self.ob_id = _first(ef, _ID_FIELDS)
            self.ob_xy = _point_getter(et)
            self.ob_heading = _first(ef, _HEADING_FIELDS, _NUMERIC)
            self.ob_len = "length" in ef and "width" in ef
            self.ob_color = "color" in ef and ef["color"].type == 9
            self.ob_sub = "sub_type" in ef and ef["sub_type"].type == _TYPE_ENUM
            self.ob_type = "type" in ef and ef["type"].type == _TYPE_ENUM
            self.ob_label = _first(ef, ("label", "kind", "class_name", "category"), {9})
            self.ob_desc = et


def _kind(reader: _ChannelReader, o: Any) -> str:
    if reader.ob_sub:
        name = _enum_name(reader.ob_desc, ("sub_type",), o.sub_type).removeprefix("ST_")
        if name not in ("UNKNOWN", ""):
            return _SUBTYPE_TO_MODEL.get(name, name.lower())
    if reader.ob_type:
        return _enum_name(reader.ob_desc, ("type",), o.type).lower()
    if reader.ob_label:
        return str(getattr(o, reader.ob_label))
    return "object"


def _default_size(kind: str) -> tuple[float, float]:
    if kind in VEHICLE_DIMENSIONS:
        return VEHICLE_DIMENSIONS[kind][:2]
    if kind in ("cyclist", "bicycle", "bike"):
        return CYCLIST_DIMENSIONS[:2]
    if kind == "pedestrian":
        return PEDESTRIAN_DIMENSIONS[:2]
    if kind in ("trafficcone", "cone"):
        return OBJECT_DIMENSIONS["cone"][:2]
    return 4.5, 1.9


def _read_obstacles(r: _ChannelReader, msg: Any, t: float) -> ObstacleFrame:
    items = list(getattr(msg, r.obstacles))
    n = len(items)
    xy = np.zeros((n, 2))
    heading = np.zeros(n)
    size = np.zeros((n, 2))
    ids, kinds, colors = [], [], []
    for k, o in enumerate(items):
        ids.append(str(getattr(o, r.ob_id)))
        xy[k] = r.ob_xy(o)
        heading[k] = getattr(o, r.ob_heading) if r.ob_heading else 0.0
        kind = _kind(r, o)
        kinds.append(kind)
        if r.ob_len and o.length > 0 and o.width > 0:
            size[k] = (o.length, o.width)
        else:
            size[k] = _default_size(kind)
        colors.append(o.color if r.ob_color else "")
    if r.ego_frame and n:
        ex, ey, eh = msg.ego_position.x, msg.ego_position.y, msg.ego_heading
        c, s = math.cos(eh), math.sin(eh)
        xy = np.stack([ex + c * xy[:, 0] - s * xy[:, 1], ey + s * xy[:, 0] + c * xy[:, 1]], axis=1)
        heading = heading + eh
        if r.ob_heading is None:
            heading[:] = eh
    return ObstacleFrame(t, ids, xy, heading, size, kinds, colors)


def _polylines(msg: Any, path: tuple[str, ...]) -> tuple[list[str], list[np.ndarray]]:
    """Every polyline at ``path`` with the id of the top-level element that owns it."""
    owners: list[str] = []
    lines: list[np.ndarray] = []

    def owner_of(e: Any) -> str:
        f = _fields(e)
        name = _first(f, _ID_FIELDS)
        if name:
            return str(getattr(e, name))
        for fd in e.DESCRIPTOR.fields:
            if fd.type == _TYPE_MESSAGE and not fd.is_repeated:
                inner = _first(fd.message_type.fields_by_name, _ID_FIELDS)
                if inner:
                    return str(getattr(getattr(e, fd.name), inner))
        return ""

    def walk(m: Any, rest: tuple[str, ...], owner: str) -> None:
        items = getattr(m, rest[0])
        if len(rest) == 1:
            if len(items) >= 2:
                get = _point_getter(items[0].DESCRIPTOR)
                lines.append(np.array([get(p) for p in items], dtype=np.float64))
                owners.append(owner)
            return
        for e in items:
            walk(e, rest[1:], owner or owner_of(e))

    walk(msg, path, "")
    return owners, lines


#: Most channels whose fields a view plots; a recording with more (one channel per object or
#: per sensor cell) would take gigabytes and show nothing readable.
MAX_CHANNELS_SHOWN = 500


def load_execution(path: str | os.PathLike[str]) -> Execution:
    """Read a recording once and keep what the scene and the signals need."""
    from rocas.recording.formats import open_recording

    rec = open_recording(path)
    ex = Execution(Path(path))
    readers: dict[str, _ChannelReader | None] = {}
    left_out: set[str] = set()
    json_rows: dict[str, tuple[list[float], list[dict[str, float]]]] = {}
    pose_topic: str | None = None
    obstacle_topic: str | None = None
    plan_topic: str | None = None
    pred_topic: str | None = None
    ego_t: list[float] = []
    ego_xyh: list[tuple[float, float, float]] = []
    t0: int | None = rec.summary_start_time_ns()  # what the diff's ``time`` is relative to
    last = 0
    for m in rec.decoded():
        if t0 is None:
            t0 = m.log_time_ns
        last = max(last, m.log_time_ns)
        t = (m.log_time_ns - t0) * 1e-9
        topic = m.channel.topic
        msg = m.message
        if not hasattr(msg, "DESCRIPTOR"):
            if isinstance(msg, dict):
                ts, rows = json_rows.setdefault(topic, ([], []))
                ts.append(t)
                rows.append({k: float(v) for k, v in msg.items() if isinstance(v, int | float)})
            continue
        r = readers.get(topic, False)
        if r is False:
            if len(readers) >= MAX_CHANNELS_SHOWN:
                # past what a viewer can show usefully: this channel is left out (and said)
                left_out.add(topic)
                readers[topic] = None
                continue
            try:
                r = _ChannelReader(topic, m.channel.schema_name, msg)
            except Exception:  # a descriptor rocas cannot walk: show nothing from it
                r = None
            readers[topic] = r
            if r is not None:
                schema = m.channel.schema_name
                if r.pose is not None and _prefer(topic, schema, pose_topic, ("pose", "locali")):
                    pose_topic = topic
                if r.obstacles and obstacle_topic is None:
                    obstacle_topic = topic
                if r.plan and _prefer(topic, schema, plan_topic, ("plan", "trajector")):
                    plan_topic = topic
                if r.prediction and pred_topic is None:
                    pred_topic = topic
        if r is None:
            continue
        r.times.append(t)
        r.rows.append([float(_get(msg, p)) for p in r.numeric])
        if r.enums or r.object_decision:
            _decision_events(ex, r, msg, t)
        if topic == pose_topic:
            p = _get(msg, r.pose)
            pos = getattr(p, _first(_fields(p), _POS_FIELDS, {_TYPE_MESSAGE}))
            ego_t.append(t)
            ego_xyh.append((pos.x, pos.y, getattr(p, _first(_fields(p), _HEADING_FIELDS, _NUMERIC))))
        if topic == obstacle_topic:
            ex.obstacles.append(_read_obstacles(r, msg, t))
        if topic == plan_topic:
            _, lines = _polylines(msg, r.plan)
            ex.plans.append((t, lines[0] if lines else np.zeros((0, 2))))
        if topic == pred_topic:
            owners, lines = _polylines(msg, r.prediction)
            ex.predictions.append((t, owners, lines))
    ex.t0_ns = t0 or 0
    ex.duration_s = (last - (t0 or 0)) * 1e-9
    ex.warnings = rec.report.warnings(Path(path).name)
    if left_out:
        ex.warnings.append(
            f"{Path(path).name}: {len(left_out)} of {len(readers)} channels are not shown: "
            f"the view plots the first {MAX_CHANNELS_SHOWN} channels that publish (rocas diff "
            "and rocas cmg read them all)")
    if ego_t:
        a = np.asarray(ego_xyh, dtype=np.float64)
        order = np.argsort(np.asarray(ego_t), kind="stable")
        ex.ego_t = np.asarray(ego_t)[order]
        ex.ego_xy, ex.ego_heading = a[order, :2], a[order, 2]
    for topic, r in readers.items():
        if r is not None and r.times and r.numeric:
            ex.channels[topic] = ChannelSeries(
                topic,
                np.asarray(r.times),
                [".".join(p) for p in r.numeric],
                np.asarray(r.rows, dtype=np.float64),
            )
    for topic, (ts, rows) in json_rows.items():
        names = sorted({k for row in rows for k in row})
        if names:
            vals = np.array([[row.get(k, np.nan) for k in names] for row in rows], dtype=np.float64)
            ex.channels[topic] = ChannelSeries(topic, np.asarray(ts), names, vals)
    for topic, ch in rec.topics().items():
        md = ch.metadata
        ex.topology[topic] = (
            md.get("rocas.writers", ""),
            md.get("rocas.readers", ""),
            md.get("rocas.role", ""),
        )
    for name, data in rec.metadata:
        if name == RUN_METADATA:
            ex.run = dict(data)
        elif name == EGO_METADATA and data.get("actors"):
            try:
                ex.actors = list(json.loads(data["actors"]))
            except ValueError:
                pass
    world = rec.attachment(WORLD_ATTACHMENT)
    if world:
        try:
            ex.world = json.loads(world)
        except ValueError:
            ex.warnings.append(f"{Path(path).name}: unreadable {WORLD_ATTACHMENT} attachment")
    ex.sources = {
        k: v
        for k, v in (
            ("pose", pose_topic),
            ("obstacles", obstacle_topic),
            ("plan", plan_topic),
            ("prediction", pred_topic),
        )
        if v
    }
    return ex


def _decision_events(ex: Execution, r: _ChannelReader, msg: Any, t: float) -> None:
    values = tuple(int(_get(msg, p)) for p in r.enums)
    if values != r.last_enums:
        for k, (p, v) in enumerate(zip(r.enums, values, strict=True)):
            if r.last_enums is None or r.last_enums[k] != v:
                ex.events.append((t, r.topic, f"{'.'.join(p)} = {_enum_name(r.desc, p, v)}"))
        r.last_enums = values
    if r.object_decision:
        parts = []
        for d in msg.object_decision:
            f = _fields(d)
            kind = _enum_name(d.DESCRIPTOR, ("type",), d.type) if "type" in f else "?"
            parts.append(f"{kind} {d.id}" if "id" in f else kind)
        text = ", ".join(sorted(parts)) or "none"
        if text != r.last_decisions:
            ex.events.append((t, r.topic, f"object decisions: {text}"))
            r.last_decisions = text


# --------------------------------------------------------------------------------------------
# logging


def rgb(name: str, alpha: int = 255) -> tuple[int, int, int, int]:
    """A scenario colour name as RGBA in [0, 255] (grey when unknown)."""
    c = COLORS.get(name)
    if c is None:
        return (150, 150, 150, alpha)
    return (round(c[0] * 255), round(c[1] * 255), round(c[2] * 255), alpha)


def _id_color(track: str) -> tuple[int, int, int, int]:
    h = sum(ord(ch) * 31**i for i, ch in enumerate(track)) % len(_PALETTE)
    return (*_PALETTE[h], 255)


def box_outline(xy: np.ndarray, heading: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Closed outlines of oriented boxes: (k, 5, 2) from centres (k, 2), headings, (length, width)."""
    corners = np.array([[1, 1], [1, -1], [-1, -1], [-1, 1], [1, 1]], dtype=np.float64) * 0.5
    local = corners[None, :, :] * size[:, None, :]
    c, s = np.cos(heading)[:, None], np.sin(heading)[:, None]
    x = xy[:, None, 0] + c * local[:, :, 0] - s * local[:, :, 1]
    y = xy[:, None, 1] + s * local[:, :, 0] + c * local[:, :, 1]
    return np.stack([x, y], axis=2)


def _body_line(xy: np.ndarray, heading: np.ndarray, size: np.ndarray) -> np.ndarray:
    """A centre segment per box (k, 2, 2); drawn with radius width/2 it fills the body."""
    half = np.maximum(size[:, 0] - size[:, 1], 0.05)[:, None] * 0.5
    d = np.stack([np.cos(heading), np.sin(heading)], axis=1) * half
    return np.stack([xy - d, xy + d], axis=1)


def _contrast(color: tuple[int, ...]) -> tuple[int, int, int, int]:
    lum = 0.3 * color[0] + 0.59 * color[1] + 0.11 * color[2]
    return (20, 20, 20, 255) if lum > 140 else (240, 240, 240, 255)


def _offset(points: np.ndarray, d: float) -> np.ndarray:
    seg = np.diff(points, axis=0)
    n = np.stack([-seg[:, 1], seg[:, 0]], axis=1)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-9)
    normals = np.vstack([n[:1], (n[:-1] + n[1:]) / 2, n[-1:]]) if len(n) > 1 else np.vstack([n, n])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-9)
    return points + d * normals


def _point_at(points: np.ndarray, s: float) -> tuple[float, float, float]:
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    i = int(np.clip(np.searchsorted(cum, s) - 1, 0, len(seg) - 1))
    u = 0.0 if seg[i] <= 0 else float(np.clip((s - cum[i]) / seg[i], 0.0, 1.0))
    p = points[i] + u * (points[i + 1] - points[i])
    d = points[i + 1] - points[i]
    return float(p[0]), float(p[1]), math.atan2(d[1], d[0])


def light_color_at(policy: dict[str, Any], enabled: bool, t: float) -> str:
    """Colour a light shows at ``t`` [s] (same rule as the simulator)."""
    if not enabled:
        return "off"
    if policy.get("mode") != "cycle":
        return str(policy.get("color", "green"))
    g, y, r = (float(policy.get(k, 0.0)) for k in ("green_s", "yellow_s", "red_s"))
    phase = (t + float(policy.get("offset_s", 0.0))) % max(g + y + r, 1e-9)
    return "green" if phase < g else "yellow" if phase < g + y else "red"


def _time(times: Any) -> Any:
    import rerun as rr

    return [rr.TimeColumn(TIMELINE, duration=np.asarray(times, dtype=np.float64))]


def _over_time(rec: Any, path: str, static: Any, times: Any, columns: Any) -> None:
    """Log ``static`` (the fields that never change) once and ``columns`` (one row per time)."""
    rec.log(path, static, static=True)
    rec.send_columns(path, indexes=_time(times), columns=columns)


def log_world(
    rec: Any,
    world: dict[str, Any],
    prefix: str,
    *,
    duration_s: float,
    highlight: frozenset[str] = frozenset(),
) -> None:
    """Log the static map (lanes, areas, objects) and the traffic lights over time."""
    import rerun as rr

    w = f"{prefix}/world"
    lanes = [ln for ln in world.get("lanes", []) if len(ln.get("points", [])) >= 2]
    pts = {ln["id"]: np.asarray(ln["points"], dtype=np.float64) for ln in lanes}
    if lanes:
        # one strip per lane, radius = half the lane width: the asphalt
        for width in sorted({float(ln.get("width_m", 3.5)) for ln in lanes}):
            group = [ln for ln in lanes if float(ln.get("width_m", 3.5)) == width]
            name = "roads" if width == float(lanes[0].get("width_m", 3.5)) else f"roads_{width:g}m"
            rec.log(
                f"{w}/{name}",
                rr.LineStrips2D(
                    [pts[ln["id"]] for ln in group], radii=width / 2, colors=[ROAD_RGB], draw_order=0.0
                ),
                static=True,
            )
        edges = []
        for ln in lanes:
            half = float(ln.get("width_m", 3.5)) / 2
            edges += [_offset(pts[ln["id"]], half), _offset(pts[ln["id"]], -half)]
        rec.log(
            f"{w}/lane_edges",
            rr.LineStrips2D(edges, radii=0.08, colors=[(235, 235, 235, 200)], draw_order=1.0),
            static=True,
        )
        rec.log(
            f"{w}/centerlines",
            rr.LineStrips2D(
                [pts[ln["id"]] for ln in lanes],
                radii=0.04,
                colors=[(240, 210, 80, 110)],
                labels=[ln["id"] for ln in lanes],
                show_labels=False,
                draw_order=1.1,
            ),
            static=True,
        )
    for kind, color in (("building", (120, 100, 90)), ("vegetation", (40, 140, 50))):
        areas = [
            a for a in world.get("areas", []) if a.get("kind") == kind and len(a.get("polygon", [])) >= 3
        ]
        if not areas:
            continue
        strips = [np.vstack([a["polygon"], a["polygon"][:1]]) for a in areas]
        colors = [(*color, 255 if a.get("enabled", True) else 90) for a in areas]
        labels = [a["id"] + ("" if a.get("enabled", True) else " (disabled)") for a in areas]
        plural = "buildings" if kind == "building" else kind
        rec.log(
            f"{w}/areas/{plural}",
            rr.LineStrips2D(strips, radii=0.35, colors=colors, labels=labels, draw_order=2.0),
            static=True,
        )
    objects = world.get("objects", [])
    if objects:
        xy = np.array([o["position"] for o in objects], dtype=np.float64)
        yaw = np.radians([float(o.get("yaw_deg", 0.0)) for o in objects])
        size = np.array([OBJECT_DIMENSIONS.get(o.get("kind"), (1.0, 1.0, 1.0))[:2] for o in objects])
        colors = [(250, 120, 20) if o.get("kind") == "cone" else (150, 105, 60) for o in objects]
        rec.log(
            f"{w}/objects",
            rr.LineStrips2D(
                box_outline(xy, yaw, size),
                radii=0.1,
                colors=colors,
                labels=[o["id"] for o in objects],
                show_labels=False,
                draw_order=4.0,
            ),
            static=True,
        )
        rec.log(
            f"{w}/objects/markers", rr.Points2D(xy, radii=0.3, colors=colors, draw_order=4.1), static=True
        )
    lights = [tl for tl in world.get("traffic_lights", []) if tl.get("stop_lane") in pts]
    if lights:
        road = road_patches(lanes, pts, [tuple(tl["position"]) for tl in lights])
        _log_lights(rec, w, lights, pts, duration_s, float(world.get("scenario", {}).get("dt_s", 0.05)),
                    road)
    _log_world_highlight(rec, w, world, pts, highlight)


#: Labels near a light keep off the road within this distance of it [m], where stop lines and
#: queued cars are; the road is tested in squares this far apart along each lane [m].
ROAD_CLEAR_RADIUS_M, ROAD_PATCH_STEP_M = 25.0, 1.5


def road_patches(
    lanes: list[dict[str, Any]], pts: dict[str, np.ndarray], near: list[tuple[float, float]],
    radius_m: float = ROAD_CLEAR_RADIUS_M, step_m: float = ROAD_PATCH_STEP_M,
) -> list[tuple[float, float, float, float]]:
    """Squares (x0, y0, x1, y1) [m] covering the lanes' surface within ``radius_m`` of any point
    of ``near``: one square of the lane's width every ``step_m`` along each lane."""
    if not near:
        return []
    centers = np.asarray(near, dtype=np.float64).reshape(-1, 2)
    out: list[tuple[float, float, float, float]] = []
    for ln in lanes:
        line = pts[ln["id"]]
        if len(line) < 2:
            continue
        half = float(ln.get("width_m", 3.5)) / 2
        seg = np.linalg.norm(np.diff(line, axis=0), axis=1)
        cum = np.concatenate([[0.0], np.cumsum(seg)])
        s = np.arange(0.0, cum[-1] + step_m / 2, step_m)
        xy = np.column_stack([np.interp(s, cum, line[:, 0]), np.interp(s, cum, line[:, 1])])
        d = np.min(np.linalg.norm(xy[:, None, :] - centers[None, :, :], axis=2), axis=1)
        out += [(x - half, y - half, x + half, y + half) for x, y in xy[d <= radius_m + half]]
    return out


def _log_lights(
    rec: Any, w: str, lights: list[dict[str, Any]], pts: dict[str, np.ndarray], duration_s: float,
    dt_s: float, road: Sequence[tuple[float, float, float, float]] = (),
) -> None:
    import rerun as rr

    lines, heads = [], np.array([tl["position"] for tl in lights], dtype=np.float64)
    for tl in lights:
        lane = pts[tl["stop_lane"]]
        x, y, h = _point_at(lane, float(tl.get("stop_s_m", 0.0)))
        nx, ny = -math.sin(h) * 1.75, math.cos(h) * 1.75
        lines.append(np.array([[x - nx, y - ny], [x + nx, y + ny]]))
    # colour changes only: one row at 0 and one per change
    steps = np.arange(0.0, max(duration_s, dt_s) + dt_s / 2, max(dt_s, 1e-3))
    times, states = [], []
    prev = None
    for t in steps:
        state = tuple(
            light_color_at(tl.get("policy", {}), bool(tl.get("enabled", True)), float(t)) for tl in lights
        )
        if state != prev:
            times.append(float(t))
            states.append(state)
            prev = state
    n = len(lights)
    colors = [LIGHT_RGB.get(c, LIGHT_RGB["off"]) for s in states for c in s]
    labels = [f"{tl['id']}: {c}" for s in states for tl, c in zip(lights, s, strict=True)]
    _over_time(rec, f"{w}/stop_lines", rr.LineStrips2D(lines, radii=0.3, draw_order=3.0), times,
               rr.LineStrips2D.columns(colors=colors).partition([n] * len(times)))
    _over_time(rec, f"{w}/traffic_lights", rr.Points2D(heads, radii=0.9, draw_order=9.5,
                                                       show_labels=False), times,
               rr.Points2D.columns(colors=colors, labels=labels).partition([n] * len(times)))
    # the labels beside the lights, clear of them, of each other and of the road around them
    # (stop lines, queued cars; rocas.viz.labels), at a spot chosen once for each light's
    # longest text
    from rocas.viz.labels import LabelItem, label_anchors, place_labels

    items = [LabelItem(f"{tl['id']}: yellow", (float(x), float(y)), 1.2)
             for tl, (x, y) in zip(lights, heads, strict=True)]
    anchors = np.asarray(label_anchors(items, place_labels(items, obstacles=road)), dtype=np.float64)
    _over_time(rec, f"{w}/traffic_light_labels",
               rr.Points2D(anchors, radii=0.05, draw_order=13.0, show_labels=True), times,
               rr.Points2D.columns(colors=colors, labels=labels).partition([n] * len(times)))


def _log_world_highlight(
    rec: Any, w: str, world: dict[str, Any], pts: dict[str, np.ndarray], highlight: frozenset[str]
) -> None:
    import rerun as rr

    if not highlight:
        return
    strips, labels = [], []
    for a in world.get("areas", []):
        if a["id"] in highlight:
            strips.append(np.vstack([a["polygon"], a["polygon"][:1]]))
            labels.append(f"mutated: {a['id']}")
    for o in world.get("objects", []):
        if o["id"] in highlight:
            x, y = o["position"]
            strips.append(box_outline(np.array([[x, y]]), np.zeros(1), np.array([[2.0, 2.0]]))[0])
            labels.append(f"mutated: {o['id']}")
    for tl in world.get("traffic_lights", []):
        if tl["id"] in highlight:
            x, y = tl["position"]
            strips.append(box_outline(np.array([[x, y]]), np.zeros(1), np.array([[3.0, 3.0]]))[0])
            labels.append(f"mutated: {tl['id']}")
    for ln in world.get("lanes", []):
        if ln["id"] in highlight and ln["id"] in pts:
            strips.append(pts[ln["id"]])
            labels.append(f"mutated: {ln['id']}")
    if strips:
        rec.log(
            f"{w}/highlight",
            rr.LineStrips2D(strips, radii=0.6, colors=[HIGHLIGHT_COLOR], labels=labels, draw_order=8.5),
            static=True,
        )


def actor_names(ex: Execution) -> dict[str, str]:
    """Track id -> scenario actor id, where the actor's kind and colour identify it uniquely."""
    by_key: dict[tuple[str, str], list[str]] = {}
    for a in ex.actors:
        kind = a.get("model") if a.get("kind") == "vehicle" else a.get("kind")
        by_key.setdefault((str(kind), str(a.get("color", ""))), []).append(str(a.get("id")))
    out: dict[str, str] = {}
    for fr in ex.obstacles:
        for tid, kind, color in zip(fr.ids, fr.kinds, fr.colors, strict=True):
            if tid not in out:
                cands = by_key.get((kind, color), [])
                if len(cands) == 1:
                    out[tid] = cands[0]
    return out


def _trail(t_arr: np.ndarray, xy: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Trail points before ``t`` (every TRAIL_STEP_S back to TRAIL_S) and their ages [s]."""
    lo = np.searchsorted(t_arr, t - TRAIL_S, side="left")
    hi = np.searchsorted(t_arr, t, side="right")
    if hi - lo < 2:
        return np.zeros((0, 2)), np.zeros(0)
    ts, ps = t_arr[lo:hi], xy[lo:hi]
    step = max(1, round(TRAIL_STEP_S / max(float(np.median(np.diff(ts))), 1e-6)))
    idx = np.arange(hi - lo - 1, -1, -step)[::-1]
    return ps[idx], t - ts[idx]


def _trail_colors(base: tuple[int, ...], ages: np.ndarray) -> np.ndarray:
    alpha = np.clip(230 * (1 - ages / TRAIL_S), 10, 230).astype(np.uint8)
    out = np.empty((len(ages), 4), dtype=np.uint8)
    out[:, :3] = base[:3]
    out[:, 3] = alpha
    return out


def log_scene(
    rec: Any, ex: Execution, prefix: str, *, highlight: Iterable[str] = (), label: str | None = None
) -> None:
    """Log one execution's scene under ``prefix`` on the ``sim_time`` timeline.

    Args:
        rec: an open ``rerun.RecordingStream``.
        ex: the execution (see :func:`load_execution`).
        prefix: entity subtree, e.g. ``executions/accident``.
        highlight: ids of scenario entities (actors, areas, objects, lights, lanes) to mark as
            mutated.
        label: name of the execution in labels (default: the last segment of ``prefix``).
    """
    import rerun as rr

    highlight = frozenset(highlight)
    label = label or prefix.rsplit("/", 1)[-1]
    if ex.world:
        log_world(rec, ex.world, prefix, duration_s=ex.duration_s, highlight=highlight)
    _log_ego(rec, ex, prefix)
    names = actor_names(ex)
    _log_actors(rec, ex, prefix, names, highlight)
    _log_paths(rec, ex, prefix)
    acc = ex.accident()
    events: list[tuple[float, str]] = []
    if acc is not None:
        t, what, pos = acc
        if pos is None:
            ego = ex.ego_at(t)
            pos = None if ego is None else (ego[0], ego[1])
        if pos is not None:
            a = np.linspace(0.0, 2 * np.pi, 41)
            ring = np.stack([pos[0] + 4.0 * np.cos(a), pos[1] + 4.0 * np.sin(a)], axis=1)
            rec.send_columns(
                f"{prefix}/accident",
                indexes=_time([t]),
                columns=rr.LineStrips2D.columns(
                    strips=[ring],
                    radii=[0.35],
                    colors=[ACCIDENT_COLOR],
                    labels=[f"{label}: {what} at {t:.2f} s"],
                    # with obstacles, <prefix>/labels places this label clear of the boxes
                    show_labels=[not ex.obstacles],
                ),
            )
            rec.log(f"{prefix}/accident", rr.LineStrips2D.from_fields(draw_order=12.0), static=True)
        events.append((t, f"ACCIDENT: {what} at {t:.2f} s" + (f" — {ex.run['outcome']}" if ex.run else "")))
    if events:
        events.sort(key=lambda e: e[0])
        rec.send_columns(
            f"{prefix}/events",
            indexes=_time([e[0] for e in events]),
            columns=rr.TextLog.columns(
                text=[e[1] for e in events],
                level=["CRITICAL" if e[1].startswith("ACCIDENT") else "INFO" for e in events],
            ),
        )


def _log_ego(rec: Any, ex: Execution, prefix: str) -> None:
    import rerun as rr

    n = len(ex.ego_t)
    if n == 0:
        return
    size = np.tile([EGO_LENGTH_M, EGO_WIDTH_M], (n, 1))
    _over_time(
        rec, f"{prefix}/ego/box",
        rr.LineStrips2D.from_fields(
            radii=0.12, colors=[(255, 255, 255)], labels=["ego"], show_labels=not ex.obstacles,
            draw_order=11.0
        ),
        ex.ego_t, rr.LineStrips2D.columns(strips=list(box_outline(ex.ego_xy, ex.ego_heading, size))),
    )
    _over_time(
        rec, f"{prefix}/ego/body",
        rr.LineStrips2D.from_fields(radii=EGO_WIDTH_M / 2 - 0.1, colors=[EGO_COLOR], draw_order=10.5),
        ex.ego_t, rr.LineStrips2D.columns(strips=list(_body_line(ex.ego_xy, ex.ego_heading, size))),
    )
    # trail at TRAIL_STEP_S: one row per 0.1 s of poses
    step = max(1, round(TRAIL_STEP_S / max(float(np.median(np.diff(ex.ego_t))) if n > 1 else 1.0, 1e-6)))
    rows = np.arange(0, n, step)
    pos, col, counts = [], [], []
    for i in rows:
        p, ages = _trail(ex.ego_t, ex.ego_xy, float(ex.ego_t[i]))
        pos.append(p)
        col.append(_trail_colors(EGO_COLOR, ages))
        counts.append(len(p))
    _over_time(rec, f"{prefix}/ego/trail", rr.Points2D.from_fields(radii=0.35, draw_order=5.0),
               ex.ego_t[rows],
               rr.Points2D.columns(positions=np.concatenate(pos), colors=np.concatenate(col))
               .partition(counts))


def _log_actors(
    rec: Any, ex: Execution, prefix: str, names: dict[str, str], highlight: frozenset[str]
) -> None:
    import rerun as rr

    if not ex.obstacles:
        return
    frames = ex.obstacles
    times = [f.t for f in frames]
    counts = [len(f.ids) for f in frames]
    xy = np.concatenate([f.xy for f in frames]) if sum(counts) else np.zeros((0, 2))
    heading = np.concatenate([f.heading for f in frames]) if sum(counts) else np.zeros(0)
    size = np.concatenate([f.size for f in frames]) if sum(counts) else np.zeros((0, 2))
    ids = [i for f in frames for i in f.ids]
    fill = [
        rgb(c) if c in COLORS else _id_color(i) for f in frames for i, c in zip(f.ids, f.colors, strict=True)
    ]
    labels = [
        f"{names[i]}" if i in names else f"{k} #{i}"
        for f in frames
        for i, k in zip(f.ids, f.kinds, strict=True)
    ]
    outline = [_contrast(c) for c in fill]
    _over_time(
        rec, f"{prefix}/actors/boxes",
        rr.LineStrips2D.from_fields(radii=0.1, show_labels=False, draw_order=9.1), times,
        rr.LineStrips2D.columns(strips=list(box_outline(xy, heading, size)), colors=outline,
                                labels=labels).partition(counts),
    )
    mutated = [i in names and names[i] in highlight for i in ids]
    _log_labels(rec, ex, prefix, [f"mutated: {t}" if m else t for t, m in zip(labels, mutated, strict=True)],
                xy, size, fill, mutated, counts)
    radii = np.maximum(size[:, 1] / 2 - 0.08, 0.1)
    _over_time(
        rec, f"{prefix}/actors/bodies", rr.LineStrips2D.from_fields(draw_order=9.0), times,
        rr.LineStrips2D.columns(strips=list(_body_line(xy, heading, size)), colors=fill,
                                radii=radii).partition(counts),
    )
    # fading trails per track
    tracks: dict[str, tuple[list[float], list[np.ndarray]]] = {}
    for f in frames:
        for k, i in enumerate(f.ids):
            ts, ps = tracks.setdefault(i, ([], []))
            ts.append(f.t)
            ps.append(f.xy[k])
    arrays = {i: (np.asarray(ts), np.asarray(ps)) for i, (ts, ps) in tracks.items()}
    color_of = dict(zip(ids, fill, strict=True))
    pos, col, tcounts = [], [], []
    for f in frames:
        c = 0
        for i in f.ids:
            p, ages = _trail(*arrays[i], f.t)
            pos.append(p)
            col.append(_trail_colors(color_of[i], ages))
            c += len(p)
        tcounts.append(c)
    if sum(tcounts):
        _over_time(rec, f"{prefix}/actors/trails", rr.Points2D.from_fields(radii=0.3, draw_order=5.1),
                   times, rr.Points2D.columns(positions=np.concatenate(pos), colors=np.concatenate(col))
                   .partition(tcounts))
    if highlight:
        hi = [i in names and names[i] in highlight for i in ids]
        hcounts, start = [], 0
        for n in counts:
            hcounts.append(sum(hi[start : start + n]))
            start += n
        if sum(hcounts):
            mask = np.asarray(hi)
            _over_time(
                rec, f"{prefix}/actors/highlight",
                rr.LineStrips2D.from_fields(radii=0.35, colors=[HIGHLIGHT_COLOR], draw_order=9.2),
                times,
                rr.LineStrips2D.columns(
                    strips=list(box_outline(xy[mask], heading[mask], size[mask] + 1.2)),
                ).partition(hcounts),
            )


def first_frame_at(times: Sequence[float], t: float) -> int | None:
    """Index of the frame a view at time ``t`` shows (the last one at or before it, which is
    what Rerun's latest-at query returns), or None when ``t`` comes before every frame."""
    k = int(np.searchsorted(np.asarray(times, dtype=float), t + 1e-9, side="right")) - 1
    return k if k >= 0 else None


def _log_labels(rec: Any, ex: Execution, prefix: str, texts: list[str], xy: np.ndarray,
                size: np.ndarray, fill: list[tuple[int, ...]], mutated: list[bool], counts: list[int]
                ) -> None:
    """``<prefix>/labels``: per obstacle frame, the labels of the ego, the obstacles and the
    accident (from its time on), each placed clear of the boxes and of each other
    (:func:`rocas.viz.labels.place_labels`); the mutated actor's and the accident's first."""
    import rerun as rr

    from rocas.viz.labels import LabelItem, label_anchors, place_labels

    acc = ex.accident()
    acc_item = None
    if acc is not None:
        pos = acc[2] or (ex.ego_at(acc[0]) or (None, None))[:2]
        if pos[0] is not None:
            acc_item = (acc[0], LabelItem(f"{acc[1]} at {acc[0]:.2f} s",
                                          (float(pos[0]), float(pos[1])), 4.0))
    ego_r = float(np.hypot(EGO_LENGTH_M, EGO_WIDTH_M)) / 2
    first = first_frame_at([f.t for f in ex.obstacles], acc_item[0]) if acc_item else None
    pos_rows, text_rows, color_rows, n_rows = [], [], [], []
    start = 0
    for i, (f, n) in enumerate(zip(ex.obstacles, counts, strict=True)):
        items: list[tuple[LabelItem, tuple[int, ...]]] = []
        if acc_item is not None and first is not None and i >= first:
            items.append((acc_item[1], ACCIDENT_COLOR))
        order = sorted(range(start, start + n), key=lambda k: not mutated[k])
        for k in order:
            r = float(np.hypot(*size[k])) / 2
            item = LabelItem(texts[k], (float(xy[k, 0]), float(xy[k, 1])), r)
            items.append((item, HIGHLIGHT_COLOR if mutated[k] else fill[k]))
        ego = ex.ego_at(f.t)
        if ego is not None:
            items.insert(1 if items and items[0][1] == ACCIDENT_COLOR else 0,
                         (LabelItem("ego", (ego[0], ego[1]), ego_r), (255, 255, 255)))
        spots = label_anchors([it for it, _ in items], place_labels([it for it, _ in items]))
        pos_rows.append(np.asarray(spots, dtype=np.float64).reshape(-1, 2))
        text_rows += [it.text for it, _ in items]
        color_rows += [(*c[:3], 255) for _, c in items]
        n_rows.append(len(items))
        start += n
    if sum(n_rows):
        _over_time(rec, f"{prefix}/labels",
                   rr.Points2D.from_fields(radii=0.05, show_labels=True, draw_order=13.0),
                   [f.t for f in ex.obstacles],
                   rr.Points2D.columns(positions=np.concatenate(pos_rows), labels=text_rows,
                                       colors=color_rows).partition(n_rows))


def _log_paths(rec: Any, ex: Execution, prefix: str) -> None:
    import rerun as rr

    if ex.plans:
        _over_time(
            rec, f"{prefix}/ego/plan",
            rr.LineStrips2D.from_fields(radii=0.25, colors=[(*EGO_COLOR, 170)], draw_order=7.0),
            [p[0] for p in ex.plans], rr.LineStrips2D.columns(strips=[p[1] for p in ex.plans]),
        )
    if ex.predictions:
        color_of: dict[str, tuple[int, ...]] = {}
        for f in ex.obstacles:
            for i, c in zip(f.ids, f.colors, strict=True):
                color_of.setdefault(i, rgb(c) if c in COLORS else _id_color(i))
        strips, colors, counts = [], [], []
        for _, owners, lines in ex.predictions:
            strips += lines
            colors += [(*color_of.get(o, _id_color(o))[:3], 150) for o in owners]
            counts.append(len(lines))
        if sum(counts):
            _over_time(
                rec, f"{prefix}/actors/predictions", rr.LineStrips2D.from_fields(radii=0.15, draw_order=6.0),
                [p[0] for p in ex.predictions],
                rr.LineStrips2D.columns(strips=strips, colors=colors).partition(counts),
            )


__all__ = [
    "Execution",
    "ObstacleFrame",
    "ChannelSeries",
    "TIMELINE",
    "load_execution",
    "log_scene",
    "log_world",
    "box_outline",
    "light_color_at",
    "actor_names",
]
