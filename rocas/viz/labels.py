"""Where the scene's labels go so that they collide neither with each other nor with the boxes
they name.

Rerun draws a 2D label at a fixed size on screen, so its extent in metres depends on the zoom.
rocas knows the zoom the scene view opens at (it frames the accident, see
:func:`rocas.viz.analysis.scene_bounds`) and places each label there: the label's rectangle is
tried at eight spots around its box, nearest first, and the first spot clear of every box and of
every label already placed is taken (else the spot with the least overlap). Labels are placed in
the order given: the most important first.

Rerun draws a point's label centred below the point, and a 2D view's y axis points down the
screen: a label whose rectangle is centred at (x, y) is logged at (x, y - height / 2)
(:func:`label_anchors`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: Screen size of one label character and one line, and the margin kept around a label [px].
CHAR_PX, LINE_PX, MARGIN_PX = 7.5, 18.0, 3.0
#: The scene view's scale when it opens: about 727 px for the 90 m it frames [px/m].
DEFAULT_PX_PER_M = 8.0

Rect = tuple[float, float, float, float]  # x0, y0, x1, y1 [m]


@dataclass(frozen=True)
class LabelItem:
    """One label to place.

    Attributes:
        text: what it says.
        center: (x, y) of the thing it names [m].
        radius: half the thing's diagonal [m] (the label stays outside this circle's square).
    """

    text: str
    center: tuple[float, float]
    radius: float


def label_extent(text: str, px_per_m: float = DEFAULT_PX_PER_M) -> tuple[float, float]:
    """(width, height) [m] of a label's rectangle at scale ``px_per_m``."""
    lines = text.split("\n")
    w = (max(len(s) for s in lines) * CHAR_PX + 2 * MARGIN_PX) / px_per_m
    return w, (len(lines) * LINE_PX + 2 * MARGIN_PX) / px_per_m


def _overlap(a: Rect, b: Rect) -> float:
    w = min(a[2], b[2]) - max(a[0], b[0])
    h = min(a[3], b[3]) - max(a[1], b[1])
    return w * h if w > 0 and h > 0 else 0.0


def place_labels(
    items: Sequence[LabelItem], obstacles: Sequence[Rect] = (), px_per_m: float = DEFAULT_PX_PER_M
) -> list[tuple[float, float]]:
    """Centre (x, y) [m] of each item's label; see the module doc.

    Args:
        items: the labels, most important first.
        obstacles: further rectangles no label may cover [m] (besides every item's own box).
        px_per_m: the view's scale.
    """
    boxes: list[Rect] = [
        (it.center[0] - it.radius, it.center[1] - it.radius, it.center[0] + it.radius,
         it.center[1] + it.radius)
        for it in items
    ] + list(obstacles)
    placed: list[Rect] = []
    out: list[tuple[float, float]] = []
    for it in items:
        w, h = label_extent(it.text, px_per_m)
        cx, cy = it.center
        best, best_cost = (cx, cy, (cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2)), np.inf
        for dist in (1.0, 1.8, 2.8):
            for ux, uy in ((0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (-1, 1), (1, -1), (-1, -1)):
                x = cx + ux * (it.radius + w / 2) * dist
                y = cy + uy * (it.radius + h / 2) * dist
                rect = (x - w / 2, y - h / 2, x + w / 2, y + h / 2)
                cost = sum(_overlap(rect, b) for b in boxes) + sum(_overlap(rect, r) for r in placed)
                if cost < best_cost:
                    best, best_cost = (x, y, rect), cost
                if cost == 0.0:
                    break
            if best_cost == 0.0:
                break
        placed.append(best[2])
        out.append((best[0], best[1]))
    return out


def label_anchors(items: Sequence[LabelItem], centers: Sequence[tuple[float, float]],
                  px_per_m: float = DEFAULT_PX_PER_M) -> list[tuple[float, float]]:
    """Where to log the points whose labels Rerun draws centred at ``centers`` [m]."""
    return [(x, y - label_extent(it.text, px_per_m)[1] / 2)
            for it, (x, y) in zip(items, centers, strict=True)]


def label_rects(items: Sequence[LabelItem], positions: Sequence[tuple[float, float]],
                px_per_m: float = DEFAULT_PX_PER_M) -> list[Rect]:
    """The rectangles [m] of labels centred at ``positions``."""
    out = []
    for it, (x, y) in zip(items, positions, strict=True):
        w, h = label_extent(it.text, px_per_m)
        out.append((x - w / 2, y - h / 2, x + w / 2, y + h / 2))
    return out


__all__ = ["LabelItem", "label_anchors", "label_extent", "label_rects", "place_labels"]
