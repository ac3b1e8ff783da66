"""Rerun layout of a differential analysis.

Entities (all under ``diff/``):

- ``diff/mdr/<topic>``: the channel's MDR series (Scalars) on the ``time`` timeline [s].
- ``diff/change_points/<topic>``: one point per change point, at its time and MDR value.
- ``diff/events``: a text log line per change point, on the ``time`` timeline.
- ``diff/cmg``: the channel-module graph after Algorithm 1 (kept edges); nodes coloured:
  deviating module red, the walk orange, other modules blue, channels grey.
- ``diff/cmg_removed``: the same nodes with the edges Algorithm 1 removed.
- ``diff/report``: the verdict as a markdown document.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from rocas.analysis.cmg import CHANNEL
from rocas.analysis.diff import DiffResult
from rocas.viz.stream import rrd_recording

RED = (220, 50, 47)
ORANGE = (240, 150, 30)
BLUE = (60, 120, 220)
GREY = (150, 150, 150)


def entity_name(topic: str) -> str:
    """A topic as one entity path segment ("/perception/obstacles" -> "perception.obstacles")."""
    name = topic.strip("/").replace("/", ".")
    return name or "root"


def diff_blueprint() -> Any:
    """The default layout: MDR plots left, graphs and verdict right."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.TimeSeriesView(origin="diff/mdr", name="MDR per channel"),
                rrb.TextLogView(origin="diff/events", name="Change points"),
                row_shares=[3, 1],
            ),
            rrb.Vertical(
                rrb.GraphView(origin="diff/cmg", name="CMG after Algorithm 1"),
                rrb.GraphView(origin="diff/cmg_removed", name="Removed edges"),
                rrb.TextDocumentView(origin="diff/report", name="Verdict"),
            ),
            column_shares=[3, 2],
        ),
        collapse_panels=True,
    )


def report_markdown(result: DiffResult) -> str:
    """The verdict of a diff as markdown."""
    p = result.pinpoint
    lines = ["# Differential analysis", ""]
    if p.deviating_module:
        lines.append(f"**Initial deviating module: `{p.deviating_module}`**")
        lines.append("")
        lines.append("Walk: " + " → ".join(f"`{n}`" for n in p.path))
    else:
        lines.append("**No deviating module found** (no module reachable from the control "
                     "channel has a change point).")
    lines += ["", "| channel | writers | t* [s] | MDR before | MDR after |", "|---|---|---|---|---|"]
    for c in result.channels:
        t = "—" if c.change_point_s is None else f"{c.change_point_s:.2f}"
        before = "—" if c.mdr_before is None else f"{c.mdr_before:.3f}"
        after = "—" if c.mdr_after is None else f"{c.mdr_after:.3f}"
        lines.append(f"| `{c.topic}` | {', '.join(c.writers) or '—'} | {t} | {before} | {after} |")
    if p.exclusions:
        lines += ["", "## Excluded modules", ""]
        lines += [f"- `{m}`: {why}" for m, why in sorted(p.exclusions.items())]
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
                    text=[f"{c.topic}: MDR change point at {s.times_s[i]:.2f} s" for i in idx],
                    level=["INFO"] * len(idx),
                ),
            )

    p = result.pinpoint
    g = result.cmg.graph
    on_path = set(p.path)
    node_ids, labels, colors = [], [], []
    for kind, name in sorted(g.nodes):
        node_ids.append(f"{kind}:{name}")
        t = p.t_star.get((kind, name))
        labels.append(f"{name}\nt*={'—' if t is None else f'{t:.2f} s'}")
        if kind == CHANNEL:
            colors.append(ORANGE if name in on_path else GREY)
        elif name == p.deviating_module:
            colors.append(RED)
        else:
            colors.append(ORANGE if name in on_path else BLUE)
    removed = {(e.source, e.target) for e in p.removed_edges}
    kept = [(f"{a[0]}:{a[1]}", f"{b[0]}:{b[1]}") for a, b in sorted(g.edges) if (a, b) not in removed]
    cut = [(f"{a[0]}:{a[1]}", f"{b[0]}:{b[1]}") for a, b in sorted(removed)]
    for entity, edges in ((f"{prefix}/cmg", kept), (f"{prefix}/cmg_removed", cut)):
        rec.log(
            entity,
            rr.GraphNodes(node_ids, labels=labels, colors=colors, show_labels=True),
            rr.GraphEdges(edges, graph_type="directed"),
            static=True,
        )
    rec.log(
        f"{prefix}/report",
        rr.TextDocument(report_markdown(result), media_type="text/markdown"),
        static=True,
    )


def write_diff_rrd(result: DiffResult, path: str | os.PathLike[str]) -> None:
    """Write a ``.rrd`` of the diff with its default blueprint (atomically)."""
    with rrd_recording(path, diff_blueprint(), kind="diff") as rec:
        log_diff(rec, result)
