"""Module signals of one execution on the ``sim_time`` timeline.

Entities, under ``<prefix>`` (e.g. ``executions/accident``):

- ``signals/speed`` [m/s]: the chassis speed (a ``speed_mps``/``speed`` field), else the norm of
  the pose velocity.
- ``signals/acceleration/commanded`` [m/s^2]: the control channel's ``acceleration``/``accel``.
- ``signals/acceleration/measured`` [m/s^2]: the pose acceleration along the heading (else the
  derivative of the speed).
- ``signals/brake/probability`` and ``signals/brake/threshold``: the brake classifier's output
  and the threshold in force.
- ``signals/decisions``: a text log line per change of a decision or of any enumeration
  (main decision, object decisions, e-stop reason, driving mode, ...).
- ``channels/<topic>``: every numeric field of every channel, one series per field.

Series names carry the execution's name so that a plot of ``executions/*/signals/speed``
compares the executions.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rocas.viz.draw import TIMELINE
from rocas.viz.execution import ChannelSeries, Execution

#: Series colour per execution name.
EXECUTION_COLORS = {"accident": (220, 50, 47), "reference": (40, 170, 80), "fixed": (40, 110, 230)}
THRESHOLD_COLOR = (150, 150, 150)


def entity_name(topic: str) -> str:
    """A topic as one entity path segment ("/perception/obstacles" -> "perception.obstacles")."""
    return topic.strip("/").replace("/", ".") or "root"


def _find(
    ex: Execution, names: tuple[str, ...], prefer: tuple[str, ...] = ()
) -> tuple[ChannelSeries, int] | None:
    """The first channel with a field called one of ``names`` (channels matching ``prefer`` first)."""
    channels = sorted(
        ex.channels.values(), key=lambda c: (not any(w in c.topic.lower() for w in prefer), c.topic)
    )
    for name in names:
        for c in channels:
            if name in c.names:
                return c, c.names.index(name)
    return None


def _control_channels(ex: Execution) -> tuple[str, ...]:
    return tuple(t for t, (_, _, role) in ex.topology.items() if role == "control")


def _series(
    rec: Any,
    entity: str,
    times: np.ndarray,
    values: np.ndarray,
    name: str,
    color: tuple[int, int, int],
    width: float = 1.5,
) -> None:
    import rerun as rr

    ok = np.isfinite(values)
    if not ok.any():
        return
    rec.send_columns(
        entity,
        indexes=[rr.TimeColumn(TIMELINE, duration=times[ok])],
        columns=rr.Scalars.columns(scalars=values[ok]),
    )
    rec.log(entity, rr.SeriesLines(names=name, colors=[color], widths=width), static=True)


def log_signals(
    rec: Any, ex: Execution, prefix: str, *, label: str | None = None, channels: bool = True
) -> None:
    """Log the module signals of one execution under ``prefix``.

    Args:
        rec: an open ``rerun.RecordingStream``.
        ex: the execution (see :func:`rocas.viz.execution.load_execution`).
        prefix: entity subtree, e.g. ``executions/accident``.
        label: the execution's name in series names (default: last segment of ``prefix``).
        channels: also log every numeric field of every channel under ``channels/``.
    """
    label = label or prefix.rsplit("/", 1)[-1]
    color = EXECUTION_COLORS.get(label, (200, 120, 30))
    s = f"{prefix}/signals"
    speed_t, speed_v = _speed(ex)
    if speed_t is not None:
        _series(rec, f"{s}/speed", speed_t, speed_v, f"{label} speed [m/s]", color)
    _log_acceleration(rec, s, ex, label, color, speed_t, speed_v)
    _log_brake(rec, s, ex, label, color)
    if ex.events:
        _log_decisions(rec, s, ex)
    if channels:
        _log_channels(rec, prefix, ex)


def _speed(ex: Execution) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(times [s], speed [m/s]): a chassis speed field, else the norm of the pose velocity;
    (None, None) when the execution has neither."""
    speed = _find(ex, ("speed_mps", "speed"), prefer=("chassis", "vehicle", "state", "canbus"))
    pose = _find(ex, ("pose.linear_velocity.x", "linear_velocity.x", "velocity.x"))
    if speed is not None:
        c, k = speed
        return c.times_s, c.values[:, k]
    if pose is not None:
        c, k = pose
        return c.times_s, np.hypot(c.values[:, k], c.values[:, k + 1])
    return None, None


def _log_acceleration(rec: Any, s: str, ex: Execution, label: str, color: tuple[int, int, int],
                      speed_t: np.ndarray | None, speed_v: np.ndarray | None) -> None:
    """``acceleration/commanded`` (the control channel's) and ``acceleration/measured`` (the
    pose's along the heading, else the derivative of the speed) [m/s^2]."""
    cmd = _find(ex, ("acceleration", "accel"), prefer=_control_channels(ex) or ("control",))
    if cmd is not None:
        c, k = cmd
        _series(
            rec,
            f"{s}/acceleration/commanded",
            c.times_s,
            c.values[:, k],
            f"{label} commanded [m/s²]",
            color,
            1.0,
        )
    acc = _find(ex, ("pose.linear_acceleration.x",))
    head = _find(ex, ("pose.heading",))
    if acc is not None and head is not None and acc[0] is head[0]:
        c, k = acc
        h = c.values[:, head[1]]
        along = c.values[:, k] * np.cos(h) + c.values[:, k + 1] * np.sin(h)
        _series(rec, f"{s}/acceleration/measured", c.times_s, along, f"{label} measured [m/s²]", color, 2.5)
    elif speed_t is not None and speed_v is not None and len(speed_t) > 2:
        _series(
            rec,
            f"{s}/acceleration/measured",
            speed_t,
            np.gradient(speed_v, speed_t),
            f"{label} measured [m/s²]",
            color,
            2.5,
        )


def _log_brake(rec: Any, s: str, ex: Execution, label: str, color: tuple[int, int, int]) -> None:
    """``brake/probability`` and ``brake/threshold``: the brake classifier's output and the
    threshold in force."""
    prob = _find(ex, ("brake_probability",))
    if prob is None:
        return
    c, k = prob
    _series(
        rec, f"{s}/brake/probability", c.times_s, c.values[:, k], f"{label} brake probability", color, 2.0
    )
    if "brake_threshold" in c.names:
        _series(
            rec,
            f"{s}/brake/threshold",
            c.times_s,
            c.values[:, c.names.index("brake_threshold")],
            f"{label} brake threshold",
            THRESHOLD_COLOR,
            1.0,
        )


def _log_decisions(rec: Any, s: str, ex: Execution) -> None:
    """``decisions``: the execution's events as text log lines (warnings for e-stops)."""
    import rerun as rr

    rec.send_columns(
        f"{s}/decisions",
        indexes=[rr.TimeColumn(TIMELINE, duration=[e[0] for e in ex.events])],
        columns=rr.TextLog.columns(
            text=[f"{e[1]}: {e[2]}" for e in ex.events], level=[_level(e[2]) for e in ex.events]
        ),
    )


def _log_channels(rec: Any, prefix: str, ex: Execution) -> None:
    """``channels/<topic>``: every numeric field of every channel, one series per field."""
    import rerun as rr

    for c in ex.channels.values():
        if len(c.times_s) == 0 or not c.names:
            continue
        entity = f"{prefix}/channels/{entity_name(c.topic)}"
        rec.send_columns(
            entity,
            indexes=[rr.TimeColumn(TIMELINE, duration=c.times_s)],
            columns=rr.Scalars.columns(scalars=np.where(np.isfinite(c.values), c.values, np.nan)),
        )
        rec.log(entity, rr.SeriesLines(names=c.names), static=True)


def _level(text: str) -> str:
    upper = text.upper()
    if any(w in upper for w in ("ESTOP", "EMERGENCY", "COLLISION")):
        return "WARN"
    return "INFO"


__all__ = ["EXECUTION_COLORS", "log_signals"]
