"""A layered drawing of the channel-module graph, as the paper draws it: the control channel
at the bottom, each layer one step further upstream (towards the sensors) above it, and the
Algorithm 1 walk straight up the middle.

Coordinates are in the graph view's units (UI points at zoom 1; y grows downwards). Every node
is drawn as its label in a box of :func:`label_size`; nodes of one layer share a row and are
packed side by side with a gap, layers are a full box height apart, so no two boxes overlap
whatever the graph (:func:`overlapping_boxes` checks it).

Layers: the walk's nodes sit at their index along the walk (the control channel at 0); every
other node at the smallest ``k + d`` over walk nodes ``w_k`` it reaches downstream in ``d``
edges. Nodes that reach no walk node go one layer above a node they feed, or one below a node
that feeds them; a part of the graph with no link to the walk is layered on its own (sinks at
0) and packed to the right. Within a layer nodes are ordered by the mean position of their
neighbours (a few barycentre sweeps), which keeps crossings few.
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping, Sequence
from typing import TypeVar

import networkx as nx

N = TypeVar("N", bound=Hashable)

#: Width of one character of a node label [points] (Rerun's UI font at 12 pt, with margin).
CHAR_W = 7.6
#: Height of one label line [points].
LINE_H = 16.0
#: Padding inside a node's box [points] (x, y).
PAD = (10.0, 6.0)
#: Gap between two boxes of one layer, and between two layers [points].
GAP_X, GAP_Y = 28.0, 34.0

Box = tuple[float, float, float, float]  # x0, y0, x1, y1


def label_size(label: str) -> tuple[float, float]:
    """(width, height) [points] of the box a label is drawn in."""
    lines = label.split("\n") or [""]
    return max(len(s) for s in lines) * CHAR_W + 2 * PAD[0], len(lines) * LINE_H + 2 * PAD[1]


def layers(graph: nx.DiGraph, walk: Sequence[N]) -> dict[N, int]:
    """Layer of every node: 0 for the walk's start (the control channel), growing upstream."""
    layer: dict[N, int] = {}
    rev = graph.reverse(copy=False)
    frontier = [(k, n) for k, n in enumerate(walk) if n in graph]
    for k, n in frontier:
        layer.setdefault(n, k)
    # multi-source breadth-first search upstream; the walk keeps its own layers
    pending = sorted(frontier, key=lambda kn: kn[0])
    while pending:
        nxt: list[tuple[int, N]] = []
        for k, n in pending:
            for u in sorted(rev.successors(n), key=repr):
                if u not in layer or (u not in walk and layer[u] > k + 1):
                    layer[u] = k + 1
                    nxt.append((k + 1, u))
        pending = nxt
    rest = sorted((n for n in graph if n not in layer), key=repr)
    changed = True
    while rest and changed:
        changed = False
        for n in list(rest):
            down = [layer[s] for s in graph.successors(n) if s in layer]
            up = [layer[p] for p in graph.predecessors(n) if p in layer]
            if down or up:
                layer[n] = min(down) + 1 if down else max(up) - 1
                rest.remove(n)
                changed = True
    if rest:  # parts with no link to the walk: layered on their own, sinks at 0
        sub = graph.subgraph(rest)
        for comp in sorted(nx.weakly_connected_components(sub), key=lambda c: sorted(map(repr, c))):
            part = sub.subgraph(comp)
            depth = {n: 0 for n in part if part.out_degree(n) == 0} or {min(part, key=repr): 0}
            todo = sorted(depth, key=repr)
            while todo:
                n = todo.pop(0)
                for u in sorted(part.predecessors(n), key=repr):
                    if u not in depth:
                        depth[u] = depth[n] + 1
                        todo.append(u)
            for n in part:
                layer[n] = depth.get(n, 0)
    lo = min(layer.values(), default=0)
    return {n: k - lo for n, k in layer.items()}


def layered_layout(
    graph: nx.DiGraph, walk: Sequence[N], labels: Mapping[N, str], sweeps: int = 4
) -> dict[N, tuple[float, float]]:
    """Centre (x, y) [points] of every node's box; the walk runs up the line x = 0.

    Args:
        graph: the CMG (edges writer -> channel -> reader).
        walk: the nodes of Algorithm 1's walk, from the control channel upstream.
        labels: node -> the label drawn in its box (sets the box's size).
        sweeps: barycentre ordering passes.
    """
    layer = layers(graph, walk)
    if not layer:
        return {}
    size = {n: label_size(labels[n]) for n in layer}
    row_h = max(h for _, h in size.values()) + GAP_Y
    top = max(layer.values())
    on_walk = {n for n in walk if n in layer}
    linked = set(on_walk)
    for n in on_walk:
        linked |= nx.node_connected_component(graph.to_undirected(as_view=True), n)
    by_layer: dict[int, list[N]] = {}
    for n in sorted(layer, key=repr):
        by_layer.setdefault(layer[n], []).append(n)
    x: dict[N, float] = {}
    for row in by_layer.values():
        _pack(row, size, x, on_walk, linked)
    neighbours = {n: [m for m in nx.all_neighbors(graph, n) if m in layer] for n in layer}
    for _ in range(sweeps):
        for k in sorted(by_layer):
            row = by_layer[k]
            bary = {
                n: (0.0 if n in on_walk else
                    sum(x[m] for m in neighbours[n]) / len(neighbours[n]) if neighbours[n] else x[n])
                for n in row
            }
            row.sort(key=lambda n: (n not in linked, bary[n], repr(n)))
            _pack(row, size, x, on_walk, linked)
    return {n: (x[n], (top - layer[n]) * row_h) for n in layer}


def _pack(row: list[N], size: Mapping[N, tuple[float, float]], x: dict[N, float], on_walk: set[N],
          linked: set[N]) -> None:
    """Place a layer's nodes side by side, a gap apart. With a walk node in the layer it sits
    at x = 0 and the others (in ``row`` order) are split between its left and right so both
    sides are about as wide; otherwise the linked nodes are centred on 0. Unlinked nodes
    follow on the right."""
    anchor = next((n for n in row if n in on_walk), None)
    main = [n for n in row if n in linked and n is not anchor]
    extra = [n for n in row if n not in linked and n is not anchor]
    if anchor is not None:
        total = sum(size[n][0] + GAP_X for n in main)
        left: list[N] = []
        acc = 0.0
        for n in main:
            if acc + (size[n][0] + GAP_X) / 2 <= total / 2:
                left.append(n)
                acc += size[n][0] + GAP_X
        right = [n for n in main if n not in left]
        x[anchor] = 0.0
        cursor = -size[anchor][0] / 2 - GAP_X
        for n in reversed(left):
            x[n] = cursor - size[n][0] / 2
            cursor -= size[n][0] + GAP_X
        cursor = size[anchor][0] / 2 + GAP_X
        for n in right + extra:
            x[n] = cursor + size[n][0] / 2
            cursor += size[n][0] + GAP_X
        return
    width = sum(size[n][0] for n in main) + GAP_X * max(len(main) - 1, 0)
    cursor = -width / 2
    for n in main + extra:
        x[n] = cursor + size[n][0] / 2
        cursor += size[n][0] + GAP_X


def node_boxes(positions: Mapping[N, tuple[float, float]], labels: Mapping[N, str]) -> dict[N, Box]:
    """Each node's box (x0, y0, x1, y1) [points] around its centre."""
    out = {}
    for n, (cx, cy) in positions.items():
        w, h = label_size(labels[n])
        out[n] = (cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2)
    return out


def overlapping_boxes(boxes: Mapping[N, Box]) -> list[tuple[N, N]]:
    """Every pair of boxes that overlap (touching edges do not count)."""
    items = sorted(boxes.items(), key=lambda kv: kv[1][0])
    out = []
    for i, (a, ba) in enumerate(items):
        for b, bb in items[i + 1:]:
            if bb[0] >= ba[2]:
                break
            if ba[0] < bb[2] and bb[0] < ba[2] and ba[1] < bb[3] and bb[1] < ba[3]:
                out.append((a, b))
    return out


def bounds(boxes: Mapping[N, Box], margin: float = 20.0) -> Box:
    """The rectangle holding every box, with ``margin`` [points] around it."""
    if not boxes:
        return (-100.0, -100.0, 100.0, 100.0)
    return (min(b[0] for b in boxes.values()) - margin, min(b[1] for b in boxes.values()) - margin,
            max(b[2] for b in boxes.values()) + margin, max(b[3] for b in boxes.values()) + margin)


__all__ = ["bounds", "label_size", "layered_layout", "layers", "node_boxes", "overlapping_boxes"]
