"""Rerun layout of a differential analysis.

Entities (all under ``diff/``):

- ``diff/mdr/<topic>``: the channel's MDR series (Scalars) on the ``time`` timeline [s].
- ``diff/change_points/<topic>``: one point per change point, at its time and MDR value.
- ``diff/t_star``: each channel's first change point (its t*, the one Algorithm 1 uses) as a
  large red marker on its MDR curve, drawn in the MDR view.
- ``diff/events``: a text log line per change point, on the ``time`` timeline.
- ``diff/cmg``: the channel-module graph after Algorithm 1, laid out in layers
  (:mod:`rocas.viz.cmg_layout`: the control channel at the bottom, the walk straight up the
  middle); each node's label is its name and t*. Colours: the deviating module red, the
  rest of the walk orange, other modules blue, channels grey; the kept edges as arrows.
- ``diff/cmg/walk``: orange dots along the walk's edges (the path Algorithm 1 followed).
- ``diff/cmg/removed``: faint dotted lines where Algorithm 1 removed an edge; every dot's
  label (shown on hover) says which edge and why.
- ``diff/removed_edges``: the removed edges and their reasons as a markdown table.
- ``diff/report``: the verdict as a markdown document.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas.analysis.cmg import CHANNEL, Node
from rocas.analysis.diff import DiffResult
from rocas.viz import cmg_layout
from rocas.viz.stream import rrd_recording

RED = (220, 50, 47)
ORANGE = (240, 150, 30)
BLUE = (60, 120, 220)
GREY = (150, 150, 150)
FADED = (150, 150, 150, 110)
#: Spacing of the dots that draw the walk and the removed edges [points].
WALK_DOT_STEP, REMOVED_DOT_STEP = 7.0, 11.0
#: Radius of those dots [points].
WALK_DOT_RADIUS, REMOVED_DOT_RADIUS = 3.0, 1.8
#: How far the marks' frame reaches above the nodes' frame, so that the graph view's two entity
#: paths (written above each frame) are a line apart [points].
MARKS_FRAME_TOP = 30.0
#: Room above a frame for the entity path the graph view writes there [points].
ENTITY_PATH_LINE = 45.0
#: Seconds shown around the change points when the MDR view opens [s].
MDR_MARGIN_S = 1.5


def entity_name(topic: str) -> str:
    """A topic as one entity path segment ("/perception/obstacles" -> "perception.obstacles")."""
    name = topic.strip("/").replace("/", ".")
    return name or "root"


def diff_blueprint(result: DiffResult | None = None) -> Any:
    """The default layout: MDR plot and change points left; the CMG (tabs: removed edges,
    verdict) right. With ``result`` the views open framed on its change points and graph."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                mdr_view(result, panel_height_pt=560.0),
                rrb.TextLogView(origin="diff/events", name="Change points"),
                row_shares=[3, 1],
            ),
            rrb.Tabs(
                cmg_view(result),
                rrb.TextDocumentView(origin="diff/report", name="Verdict"),
                rrb.TextDocumentView(origin="diff/removed_edges", name="Removed edges"),
                active_tab=0,
            ),
            column_shares=[1, 1],
        ),
        collapse_panels=True,
    )


def mdr_window(result: DiffResult, margin_s: float = MDR_MARGIN_S) -> tuple[float, float] | None:
    """The seconds around the channels' first change points [s], or None without any."""
    firsts = [c.change_point_s for c in result.channels if c.change_point_s is not None]
    if not firsts:
        return None
    ends = [float(c.series.times_s[-1]) for c in result.channels if len(c.series.times_s)]
    lo = max(min(firsts) - margin_s, 0.0)
    hi = max(firsts) + margin_s
    if ends:
        hi = min(hi, max(ends))
    return lo, max(hi, lo + 2 * margin_s)


def mdr_view(result: DiffResult | None, *, origin: str = "diff", name: str = "MDR per channel",
             panel_height_pt: float = 300.0) -> Any:
    """The MDR time series view: every channel's curve and its t* marker, the legend in the
    top-left corner above the curves (the y axis leaves it room: MDR is in [0, 1]), opening on
    :func:`mdr_window` (zoom out for the whole run). ``panel_height_pt``: the view's expected
    height [points], which sets the room left for the legend."""
    import rerun.blueprint as rrb

    kw: dict[str, Any] = {}
    if result is not None:
        window = mdr_window(result)
        if window is not None:
            kw["axis_x"] = rrb.TimeAxis(view_range=rrb.TimeRange(
                start=rrb.TimeRangeBoundary.absolute(seconds=window[0]),
                end=rrb.TimeRangeBoundary.absolute(seconds=window[1])))
        entries = sum(1 for c in result.channels if len(c.series.mdr)) + 1
        legend_pt = 20.0 * entries + 16.0
        share = min(legend_pt / max(panel_height_pt - 40.0, 1.0), 0.7)
        kw["axis_y"] = rrb.ScalarAxis(range=(-0.03, 1.03 / (1.0 - share)), zoom_lock=False)
    return rrb.TimeSeriesView(
        origin=f"{origin}",
        contents=[f"+ {origin}/mdr/**", f"+ {origin}/t_star"],
        name=name,
        plot_legend=rrb.PlotLegend(corner=rrb.Corner2D.LeftTop),
        **kw,
    )


def cmg_view(result: DiffResult | None, *, origin: str = "diff/cmg",
             name: str = "CMG after Algorithm 1") -> Any:
    """The CMG graph view: the layout's positions as logged (no force simulation), framed on
    the whole graph."""
    import rerun.blueprint as rrb
    import rerun.blueprint.archetypes as rrba

    kw: dict[str, Any] = {}
    if result is not None:
        x0, y0, x1, y1 = cmg_drawing(result).bounds
        kw["visual_bounds"] = rrb.VisualBounds2D(x_range=(x0, x1), y_range=(y0, y1))
    return rrb.GraphView(
        origin=origin,
        name=name,
        force_link=rrba.ForceLink(enabled=False),
        force_many_body=rrba.ForceManyBody(enabled=False),
        force_position=rrba.ForcePosition(enabled=False),
        force_collision_radius=rrba.ForceCollisionRadius(enabled=False),
        force_center=rrba.ForceCenter(enabled=False),
        **kw,
    )


@dataclass(frozen=True)
class CmgDrawing:
    """How the CMG of a diff is drawn (see :mod:`rocas.viz.cmg_layout`).

    Attributes:
        nodes: the graph's nodes, sorted; ids: their node ids (``kind:name``), (n,).
        labels, colors: per node, (n,).
        positions: (n, 2) box centres [points].
        kept: (source id, target id) of the edges Algorithm 1 kept.
        walk_dots: (k, 2) points along the walk's edges [points].
        removed_dots: (m, 2) points along the removed edges [points]; removed_labels: (m,)
            which edge each dot belongs to and why it was removed.
        node_extent: (x0, y0, x1, y1) of the nodes' boxes [points].
        bounds: what the view shows: the nodes' boxes with a margin, and above them the marks'
            frame and the line of its entity path [points].
    """

    nodes: tuple[Node, ...]
    ids: tuple[str, ...]
    labels: tuple[str, ...]
    colors: tuple[tuple[int, int, int], ...]
    positions: np.ndarray
    kept: tuple[tuple[str, str], ...]
    walk_dots: np.ndarray
    removed_dots: np.ndarray
    removed_labels: tuple[str, ...]
    node_extent: tuple[float, float, float, float]
    bounds: tuple[float, float, float, float]


def _node_id(n: Node) -> str:
    return f"{n[0]}:{n[1]}"


#: Longest line of a node label [characters]; a longer name is broken after a "/" or "_".
LABEL_LINE_CHARS = 14


def _wrap(name: str, width: int = LABEL_LINE_CHARS) -> list[str]:
    lines: list[str] = []
    rest = name
    while len(rest) > width:
        cut = max(rest.rfind("/", 1, width + 1), rest.rfind("_", 1, width + 1))
        if cut <= 0:
            break
        lines.append(rest[: cut + 1])
        rest = rest[cut + 1:]
    return [*lines, rest]


def node_label(name: str, t_star: float | None) -> str:
    """A CMG node's label: its name (broken after a "/" or "_" when long), and its t*."""
    return "\n".join(_wrap(name)) + f"\nt* = {'none' if t_star is None else f'{t_star:.2f} s'}"


def walk_nodes(result: DiffResult) -> list[Node]:
    """The walk as CMG nodes, from the control channel upstream (channels and modules
    alternate along it)."""
    g = result.cmg.graph
    out: list[Node] = []
    for i, name in enumerate(result.pinpoint.path):
        kinds = (CHANNEL, "module") if i % 2 == 0 else ("module", CHANNEL)
        node = next(((k, name) for k in kinds if (k, name) in g), None)
        if node is not None:
            out.append(node)
    return out


def _clip(box: cmg_layout.Box, inside: np.ndarray, outside: np.ndarray) -> np.ndarray:
    """Where the segment from ``inside`` (the box's centre) to ``outside`` leaves the box."""
    d = outside - inside
    ts = [1.0]
    for axis, (lo, hi) in enumerate(((box[0], box[2]), (box[1], box[3]))):
        if d[axis] > 1e-9:
            ts.append((hi - inside[axis]) / d[axis])
        elif d[axis] < -1e-9:
            ts.append((lo - inside[axis]) / d[axis])
    return inside + min(ts) * d


def _dots(a: np.ndarray, b: np.ndarray, step: float) -> np.ndarray:
    n = max(int(math.hypot(*(b - a)) // step), 1)
    return a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)


def cmg_drawing(result: DiffResult) -> CmgDrawing:
    """Lay out and colour the CMG of ``result`` (pure; :func:`log_cmg` logs it)."""
    p = result.pinpoint
    g = result.cmg.graph
    nodes = tuple(sorted(g.nodes))
    labels = {n: node_label(n[1], p.t_star.get(n)) for n in nodes}
    walk = walk_nodes(result)
    on_walk = set(walk)
    pos = cmg_layout.layered_layout(g, walk, labels)
    boxes = cmg_layout.node_boxes(pos, labels)
    colors = []
    for n in nodes:
        if n[0] != CHANNEL and n[1] == p.deviating_module:
            colors.append(RED)
        elif n in on_walk:
            colors.append(ORANGE)
        else:
            colors.append(GREY if n[0] == CHANNEL else BLUE)

    def segment(u: Node, v: Node) -> tuple[np.ndarray, np.ndarray]:
        a, b = np.asarray(pos[u], dtype=np.float64), np.asarray(pos[v], dtype=np.float64)
        return _clip(boxes[u], a, b), _clip(boxes[v], b, a)

    removed = {(e.source, e.target): e.reason for e in p.removed_edges}
    kept = tuple((_node_id(u), _node_id(v)) for u, v in sorted(g.edges) if (u, v) not in removed)
    walk_pts = [_dots(*segment(walk[k + 1], walk[k]), WALK_DOT_STEP) for k in range(len(walk) - 1)
                if g.has_edge(walk[k + 1], walk[k])]
    rem_pts, rem_labels = [], []
    for (u, v), why in sorted(removed.items()):
        if u in pos and v in pos:
            pts = _dots(*segment(u, v), REMOVED_DOT_STEP)[1:-1]
            rem_pts.append(pts)
            rem_labels += [f"removed {u[1]} → {v[1]}: {why}"] * len(pts)
    extent = cmg_layout.bounds(boxes, margin=0.0)
    x0, y0, x1, y1 = cmg_layout.bounds(boxes)
    return CmgDrawing(
        nodes=nodes,
        ids=tuple(_node_id(n) for n in nodes),
        labels=tuple(labels[n] for n in nodes),
        colors=tuple(colors),
        positions=np.array([pos[n] for n in nodes], dtype=np.float64).reshape(-1, 2),
        kept=kept,
        walk_dots=np.concatenate(walk_pts) if walk_pts else np.zeros((0, 2)),
        removed_dots=np.concatenate(rem_pts) if rem_pts else np.zeros((0, 2)),
        removed_labels=tuple(rem_labels),
        node_extent=extent,
        bounds=(x0, min(y0, marks_frame(extent)[1] - ENTITY_PATH_LINE), x1, y1),
    )


def marks_frame(node_extent: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1) of the marks' frame: the nodes' frame with 8 points around it and
    :data:`MARKS_FRAME_TOP` above it (the graph view's y axis points down) [points]."""
    margins = (-8.0, -MARKS_FRAME_TOP, 8.0, 8.0)
    x0, y0, x1, y1 = (v + m for v, m in zip(node_extent, margins, strict=True))
    return x0, y0, x1, y1


def log_cmg(rec: Any, result: DiffResult, prefix: str = "diff") -> CmgDrawing:
    """Log the laid-out CMG under ``<prefix>/cmg`` (static); returns the drawing."""
    import rerun as rr

    d = cmg_drawing(result)
    rec.log(
        f"{prefix}/cmg",
        rr.GraphNodes(list(d.ids), positions=d.positions, labels=list(d.labels),
                      colors=list(d.colors), show_labels=True),
        rr.GraphEdges(list(d.kept), graph_type="directed"),
        static=True,
    )
    # The dots of the walk and of the removed edges are a second entity (one entity's labels
    # are all shown or all hidden). The graph view frames each entity's extent and writes its
    # path above the frame's top-left corner; two invisible dots on the corners make the marks'
    # frame enclose the nodes' frame, MARKS_FRAME_TOP higher so the two paths do not overlap.
    n_walk, n_rem = len(d.walk_dots), len(d.removed_dots)
    if n_walk + n_rem:
        x0, y0, x1, y1 = marks_frame(d.node_extent)
        rec.log(
            f"{prefix}/cmg/marks",
            rr.GraphNodes(
                # a dot's id is what hovering it shows: for a removed edge, which and why
                [*(f"walk {i}" for i in range(n_walk)),
                 *(f"{why} ({i})" for i, why in enumerate(d.removed_labels)), "corner 0", "corner 1"],
                positions=np.concatenate([d.walk_dots, d.removed_dots, [[x0, y0], [x1, y1]]]),
                colors=[*([ORANGE] * n_walk), *([FADED] * n_rem), (0, 0, 0, 0), (0, 0, 0, 0)],
                radii=[WALK_DOT_RADIUS] * n_walk + [REMOVED_DOT_RADIUS] * n_rem + [0.0, 0.0],
                show_labels=False,
            ),
            static=True,
        )
    rows = ["| edge | why Algorithm 1 removed it |", "|---|---|"]
    rows += [f"| `{e.source[1]}` → `{e.target[1]}` | {e.reason} |" for e in result.pinpoint.removed_edges]
    text = "# Removed edges\n\n" + ("\n".join(rows) if result.pinpoint.removed_edges
                                     else "Algorithm 1 removed no edge.") + "\n"
    rec.log(f"{prefix}/removed_edges", rr.TextDocument(text, media_type="text/markdown"), static=True)
    return d


def report_markdown(result: DiffResult) -> str:
    """The verdict of a diff as markdown. Every name from data (channels, modules, files) and
    every line made from them is escaped (:func:`rocas._text.markdown_text`): no Markdown or
    HTML in a name acts."""
    from rocas._text import markdown_text as md

    p = result.pinpoint
    lines = ["# Differential analysis", ""]
    if p.deviating_module:
        lines.append(f"**Initial deviating module: {md(p.deviating_module)}**")
        lines.append("")
        lines.append("Walk: " + " → ".join(md(n) for n in p.path))
    else:
        lines.append("**No deviating module found** (no module reachable from the control "
                     "channel has a change point).")
    if p.fallback:
        lines += ["", f"Note: {md(p.fallback)}."]
    e = result.entries
    if e is not None and e.deviating_module != p.deviating_module:
        from rocas.analysis.entries import entries_text

        entered = {c.topic: c.entered_s for c in result.channels if c.entered_s is not None}
        lines += ["", f"Note: {md(entries_text(entered, e.deviating_module))}."]
    notes = result.comparison_notes()
    if notes or result.warnings:
        lines += ["", "## How the recordings were compared", ""]
        lines += [f"- {md(n)}" for n in notes]
        lines += [f"- Warning: {md(w)}" for w in result.warnings]
    lines += ["", "| channel | writers | t* [s] | MDR before | MDR after |", "|---|---|---|---|---|"]
    for c in result.channels:
        t = "—" if c.change_point_s is None else f"{c.change_point_s:.2f}"
        if c.change_points.converges_s:
            t += f" (converges at {c.change_points.converges_s[0]:.2f})"
        before = "—" if c.mdr_before is None else f"{c.mdr_before:.3f}"
        after = "—" if c.mdr_after is None else f"{c.mdr_after:.3f}"
        lines.append(f"| {md(c.topic)} | {md(', '.join(c.writers)) or '—'} | {t} | {before} "
                     f"| {after} |")
    if p.exclusions:
        lines += ["", "## Excluded modules", ""]
        lines += [f"- {md(m)}: {md(why)}" for m, why in sorted(p.exclusions.items())]
    return "\n".join(lines) + "\n"


def log_diff(rec: Any, result: DiffResult, prefix: str = "diff",
             timelines: tuple[str, ...] = ("time",)) -> None:
    """Log a diff result into an open ``rerun.RecordingStream``.

    ``timelines``: the timelines the series are indexed on (the analysis ``.rrd`` adds
    ``sim_time`` so that MDR plots and the scene share one time cursor).
    """
    import rerun as rr

    for c in result.channels:
        s = c.series
        if len(s.mdr) == 0:
            continue
        name = entity_name(c.topic)
        rec.send_columns(
            f"{prefix}/mdr/{name}",
            indexes=[rr.TimeColumn(tl, duration=s.times_s) for tl in timelines],
            columns=rr.Scalars.columns(scalars=s.mdr),
        )
        rec.log(f"{prefix}/mdr/{name}", rr.SeriesLines(names=c.topic), static=True)
        idx = np.asarray(c.change_points.indices, dtype=np.int64)
        if len(idx):
            rec.send_columns(
                f"{prefix}/change_points/{name}",
                indexes=[rr.TimeColumn(tl, duration=s.times_s[idx]) for tl in timelines],
                columns=rr.Scalars.columns(scalars=s.mdr[idx]),
            )
            rec.log(
                f"{prefix}/change_points/{name}",
                rr.SeriesPoints(names=f"{c.topic} change point", colors=[RED], marker_sizes=6.0),
                static=True,
            )
            rec.send_columns(
                f"{prefix}/events",
                indexes=[rr.TimeColumn(tl, duration=s.times_s[idx]) for tl in timelines],
                columns=rr.TextLog.columns(
                    text=[f"{c.topic}: MDR {'rises' if up else 'falls (the runs converge)'} "
                          f"at {s.times_s[i]:.2f} s"
                          for i, up in zip(idx, c.change_points.rises or (True,) * len(idx),
                                           strict=True)],
                    level=["INFO"] * len(idx),
                ),
            )

    firsts = sorted(((c.change_point_s, c) for c in result.channels
                     if c.change_point_s is not None and c.change_points.first_index is not None),
                    key=lambda tc: (tc[0], tc[1].topic))
    if firsts:
        idx = [c.change_points.first_index for _, c in firsts]
        times = np.array([t for t, _ in firsts], dtype=np.float64)
        rec.send_columns(
            f"{prefix}/t_star",
            indexes=[rr.TimeColumn(tl, duration=times) for tl in timelines],
            columns=rr.Scalars.columns(scalars=np.array(
                [float(c.series.mdr[i]) for i, (_, c) in zip(idx, firsts, strict=True)])),
        )
        rec.log(f"{prefix}/t_star",
                rr.SeriesPoints(names="t* (first change point)", colors=[RED], marker_sizes=7.0,
                                markers="diamond"),
                static=True)
    log_cmg(rec, result, prefix)
    rec.log(
        f"{prefix}/report",
        rr.TextDocument(report_markdown(result), media_type="text/markdown"),
        static=True,
    )


def write_diff_rrd(result: DiffResult, path: str | os.PathLike[str]) -> None:
    """Write a ``.rrd`` of the diff with its default blueprint (atomically)."""
    with rrd_recording(path, diff_blueprint(result), kind="diff") as rec:
        log_diff(rec, result)
