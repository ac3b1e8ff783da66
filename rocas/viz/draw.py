"""What every view of an execution draws with: the ``sim_time`` timeline, the colours, oriented
boxes, and logging a component that changes over time as one static part plus columns.

Shapes: points are ``(k, 2)`` [m] in the world frame; headings ``(k,)`` [rad]; box sizes
``(k, 2)`` length and width [m]. Colours are RGB(A) in [0, 255].
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rocas.scenarios.model import COLORS

#: The timeline every execution is logged on [s since the recording's start].
TIMELINE = "sim_time"

EGO_COLOR = (0, 190, 255)
HIGHLIGHT_COLOR = (255, 215, 0)
ACCIDENT_COLOR = (230, 20, 20)
LIGHT_RGB = {"red": (230, 30, 30), "yellow": (250, 200, 0), "green": (40, 200, 60), "off": (60, 60, 60)}
ROAD_RGB = (62, 64, 70)
BACKGROUND_RGB = (176, 186, 168)
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


def rgb(name: str, alpha: int = 255) -> tuple[int, int, int, int]:
    """A scenario colour name as RGBA in [0, 255] (grey when unknown)."""
    c = COLORS.get(name)
    if c is None:
        return (150, 150, 150, alpha)
    return (round(c[0] * 255), round(c[1] * 255), round(c[2] * 255), alpha)


def id_color(track: str) -> tuple[int, int, int, int]:
    """A colour of the palette chosen by a track id (the same id, the same colour)."""
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


def body_line(xy: np.ndarray, heading: np.ndarray, size: np.ndarray) -> np.ndarray:
    """A centre segment per box (k, 2, 2); drawn with radius width/2 it fills the body."""
    half = np.maximum(size[:, 0] - size[:, 1], 0.05)[:, None] * 0.5
    d = np.stack([np.cos(heading), np.sin(heading)], axis=1) * half
    return np.stack([xy - d, xy + d], axis=1)


def contrast(color: tuple[int, ...]) -> tuple[int, int, int, int]:
    """Near black on a light ``color``, near white on a dark one (an outline that shows)."""
    lum = 0.3 * color[0] + 0.59 * color[1] + 0.11 * color[2]
    return (20, 20, 20, 255) if lum > 140 else (240, 240, 240, 255)


def time_column(times: Any) -> Any:
    """The ``sim_time`` index of rows at ``times`` [s]."""
    import rerun as rr

    return [rr.TimeColumn(TIMELINE, duration=np.asarray(times, dtype=np.float64))]


def over_time(rec: Any, path: str, static: Any, times: Any, columns: Any) -> None:
    """Log ``static`` (the fields that never change) once and ``columns`` (one row per time)."""
    rec.log(path, static, static=True)
    rec.send_columns(path, indexes=time_column(times), columns=columns)
