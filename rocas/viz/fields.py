"""What a message shows, learnt from its fields (protobuf descriptors), not from topic names.

A channel is read by a :class:`ChannelReader` decided from its first message: a ``pose``
(``position`` + ``heading``) makes it an ego pose; a repeated field whose elements carry an id
(``id``/``uid``/``track_id``) and a position (``position``/``pos``/``center``) an obstacle list
(in the ego frame when the message also carries ``ego_position``/``ego_heading``); a repeated
field of ``x``/``y`` points at the top level the ego's planned trajectory, nested deeper a
predicted trajectory. Singular numeric fields become signals; enumerations and object
decisions become events when they change. Nothing here knows Rerun or the file.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas.scenarios.model import (
    CYCLIST_DIMENSIONS,
    OBJECT_DIMENSIONS,
    PEDESTRIAN_DIMENSIONS,
    VEHICLE_DIMENSIONS,
)

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


def get(msg: Any, path: tuple[str, ...]) -> Any:
    """The field at ``path`` (names, outermost first) of ``msg``."""
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


def prefer(topic: str, schema: str, current: str | None, words: tuple[str, ...]) -> bool:
    """Whether ``topic`` should replace ``current`` as the source of one kind of data: the
    first candidate, or one whose name says it is that kind when the current one's does not."""
    return current is None or _priority(topic, schema, words) < _priority(current, "", words)


class ChannelReader:
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


def _kind(reader: ChannelReader, o: Any) -> str:
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


def read_obstacles(r: ChannelReader, msg: Any, t: float) -> ObstacleFrame:
    """The obstacles of a message of an obstacle channel at ``t`` [s], in the world frame
    (sizes the message lacks are the scenario's defaults for the obstacle's kind)."""
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


def polylines(msg: Any, path: tuple[str, ...]) -> tuple[list[str], list[np.ndarray]]:
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


def ego_pose(r: ChannelReader, msg: Any) -> tuple[float, float, float]:
    """The ego's (x [m], y [m], heading [rad]) in a message of a pose channel."""
    p = get(msg, r.pose)
    pos = getattr(p, _first(_fields(p), _POS_FIELDS, {_TYPE_MESSAGE}))
    return (pos.x, pos.y, getattr(p, _first(_fields(p), _HEADING_FIELDS, _NUMERIC)))


def decision_events(r: ChannelReader, msg: Any, t: float) -> list[tuple[float, str, str]]:
    """(t, topic, text) for each enumeration of ``msg`` that changed since the channel's last
    message, and for its object decisions when they changed (``r`` remembers the last ones)."""
    events: list[tuple[float, str, str]] = []
    values = tuple(int(get(msg, p)) for p in r.enums)
    if values != r.last_enums:
        for k, (p, v) in enumerate(zip(r.enums, values, strict=True)):
            if r.last_enums is None or r.last_enums[k] != v:
                events.append((t, r.topic, f"{'.'.join(p)} = {_enum_name(r.desc, p, v)}"))
        r.last_enums = values
    if r.object_decision:
        parts = []
        for d in msg.object_decision:
            f = _fields(d)
            kind = _enum_name(d.DESCRIPTOR, ("type",), d.type) if "type" in f else "?"
            parts.append(f"{kind} {d.id}" if "id" in f else kind)
        text = ", ".join(sorted(parts)) or "none"
        if text != r.last_decisions:
            events.append((t, r.topic, f"object decisions: {text}"))
            r.last_decisions = text
    return events
