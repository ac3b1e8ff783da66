"""One execution as the views draw it: a recording read once into poses, obstacles, plans,
predictions, signals and events (:func:`load_execution`).

Which channel is the ego pose, the obstacle list, the plan or the prediction is learnt from
the messages' fields (:mod:`rocas.viz.fields`); rocas's own recordings also carry the static
world (``rocas/world.json``) and the outcome (``rocas.run`` metadata). Nothing here logs to
Rerun: :mod:`rocas.viz.scene` and :mod:`rocas.viz.signals` draw an :class:`Execution`.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rocas.viz.fields import (
    ChannelReader,
    ObstacleFrame,
    decision_events,
    ego_pose,
    get,
    polylines,
    prefer,
    read_obstacles,
)

WORLD_ATTACHMENT = "rocas/world.json"
RUN_METADATA = "rocas.run"
EGO_METADATA = "rocas.ego"
#: Most channels whose fields a view plots; a recording with more (one channel per object or
#: per sensor cell) would take gigabytes and show nothing readable.
MAX_CHANNELS_SHOWN = 500


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


@dataclass
class _Sources:
    """The channel each kind of drawn data is read from, chosen as channels first publish: the
    first candidate, replaced by a later one whose name says it is that kind (pose, plan)."""

    pose: str | None = None
    obstacles: str | None = None
    plan: str | None = None
    prediction: str | None = None

    def consider(self, topic: str, schema: str, r: ChannelReader) -> None:
        """Take ``topic`` (its reader ``r`` decided from its first message) where it fits."""
        if r.pose is not None and prefer(topic, schema, self.pose, ("pose", "locali")):
            self.pose = topic
        if r.obstacles and self.obstacles is None:
            self.obstacles = topic
        if r.plan and prefer(topic, schema, self.plan, ("plan", "trajector")):
            self.plan = topic
        if r.prediction and self.prediction is None:
            self.prediction = topic

    def named(self) -> dict[str, str]:
        """What was interpreted as what, e.g. ``{"pose": "/localization/pose"}``."""
        found = (("pose", self.pose), ("obstacles", self.obstacles), ("plan", self.plan),
                 ("prediction", self.prediction))
        return {k: v for k, v in found if v}


class _Pass:
    """What one pass over a recording collects into an :class:`Execution`, message by message."""

    def __init__(self, ex: Execution) -> None:
        self.ex = ex
        self.readers: dict[str, ChannelReader | None] = {}
        self.left_out: set[str] = set()
        self.json_rows: dict[str, tuple[list[float], list[dict[str, float]]]] = {}
        self.sources = _Sources()
        self.ego_t: list[float] = []
        self.ego_xyh: list[tuple[float, float, float]] = []

    def add(self, topic: str, schema: str, msg: Any, t: float) -> None:
        """One decoded message at ``t`` [s since the start]."""
        if not hasattr(msg, "DESCRIPTOR"):  # JSON: its numeric top-level fields are signals
            if isinstance(msg, dict):
                ts, rows = self.json_rows.setdefault(topic, ([], []))
                ts.append(t)
                rows.append({k: float(v) for k, v in msg.items() if isinstance(v, int | float)})
            return
        r = self.readers.get(topic, False)
        if r is False:
            r = self._first_message(topic, schema, msg)
        if r is not None:
            self._take(r, topic, msg, t)

    def _first_message(self, topic: str, schema: str, msg: Any) -> ChannelReader | None:
        """The reader of a channel met for the first time (None: nothing of it is shown)."""
        if len(self.readers) >= MAX_CHANNELS_SHOWN:
            # past what a viewer can show usefully: this channel is left out (and said)
            self.left_out.add(topic)
            self.readers[topic] = None
            return None
        try:
            r: ChannelReader | None = ChannelReader(topic, schema, msg)
        except Exception:  # a descriptor rocas cannot walk: show nothing from it
            r = None
        self.readers[topic] = r
        if r is not None:
            self.sources.consider(topic, schema, r)
        return r

    def _take(self, r: ChannelReader, topic: str, msg: Any, t: float) -> None:
        """Keep the message's signals and events, and what it draws if its channel is a source."""
        ex, sources = self.ex, self.sources
        r.times.append(t)
        r.rows.append([float(get(msg, p)) for p in r.numeric])
        if r.enums or r.object_decision:
            ex.events.extend(decision_events(r, msg, t))
        if topic == sources.pose:
            self.ego_t.append(t)
            self.ego_xyh.append(ego_pose(r, msg))
        if topic == sources.obstacles:
            ex.obstacles.append(read_obstacles(r, msg, t))
        if topic == sources.plan:
            _, lines = polylines(msg, r.plan)
            ex.plans.append((t, lines[0] if lines else np.zeros((0, 2))))
        if topic == sources.prediction:
            owners, lines = polylines(msg, r.prediction)
            ex.predictions.append((t, owners, lines))

    def finish(self) -> None:
        """The ego pose series in time order and every channel's numeric series."""
        ex = self.ex
        if self.ego_t:
            a = np.asarray(self.ego_xyh, dtype=np.float64)
            order = np.argsort(np.asarray(self.ego_t), kind="stable")
            ex.ego_t = np.asarray(self.ego_t)[order]
            ex.ego_xy, ex.ego_heading = a[order, :2], a[order, 2]
        for topic, r in self.readers.items():
            if r is not None and r.times and r.numeric:
                ex.channels[topic] = ChannelSeries(
                    topic,
                    np.asarray(r.times),
                    [".".join(p) for p in r.numeric],
                    np.asarray(r.rows, dtype=np.float64),
                )
        for topic, (ts, rows) in self.json_rows.items():
            names = sorted({k for row in rows for k in row})
            if names:
                vals = np.array([[row.get(k, np.nan) for k in names] for row in rows],
                                dtype=np.float64)
                ex.channels[topic] = ChannelSeries(topic, np.asarray(ts), names, vals)
        ex.sources = self.sources.named()


def _read_file_level(ex: Execution, rec: Any, name: str) -> None:
    """What the file says beside its messages: topology metadata, the outcome and actors, and
    the static world attachment (after a pass, when they are all known)."""
    for topic, ch in rec.topics().items():
        md = ch.metadata
        ex.topology[topic] = (
            md.get("rocas.writers", ""),
            md.get("rocas.readers", ""),
            md.get("rocas.role", ""),
        )
    for md_name, data in rec.metadata:
        if md_name == RUN_METADATA:
            ex.run = dict(data)
        elif md_name == EGO_METADATA and data.get("actors"):
            try:
                ex.actors = list(json.loads(data["actors"]))
            except ValueError:
                pass
    world = rec.attachment(WORLD_ATTACHMENT)
    if world:
        try:
            ex.world = json.loads(world)
        except ValueError:
            ex.warnings.append(f"{name}: unreadable {WORLD_ATTACHMENT} attachment")


def load_execution(path: str | os.PathLike[str]) -> Execution:
    """Read a recording once and keep what the scene and the signals need."""
    from rocas.recording.formats import open_recording

    rec = open_recording(path)
    ex = Execution(Path(path))
    collected = _Pass(ex)
    t0: int | None = rec.summary_start_time_ns()  # what the diff's ``time`` is relative to
    last = 0
    for m in rec.decoded():
        if t0 is None:
            t0 = m.log_time_ns
        last = max(last, m.log_time_ns)
        collected.add(m.channel.topic, m.channel.schema_name, m.message, (m.log_time_ns - t0) * 1e-9)
    ex.t0_ns = t0 or 0
    ex.duration_s = (last - (t0 or 0)) * 1e-9
    name = Path(path).name
    ex.warnings = rec.report.warnings(name)
    if collected.left_out:
        ex.warnings.append(
            f"{name}: {len(collected.left_out)} of {len(collected.readers)} channels are not "
            f"shown: the view plots the first {MAX_CHANNELS_SHOWN} channels that publish "
            "(rocas diff and rocas cmg read them all)")
    collected.finish()
    _read_file_level(ex, rec, name)
    return ex


__all__ = ["MAX_CHANNELS_SHOWN", "ChannelSeries", "Execution", "load_execution"]
