"""The top-down scene of one execution on the ``sim_time`` timeline: the ego, the obstacles,
plans and predictions, the accident, over the map (:mod:`rocas.viz.world`).

The execution is read beforehand (:func:`rocas.viz.execution.load_execution`): this module
only logs. Entities, under ``<prefix>`` (e.g. ``executions/accident``)::

    world/...                                           the map and lights (rocas.viz.world)
    ego/box, ego/body, ego/trail, ego/plan              ego outline, body, fading trail, plan
    actors/boxes, actors/bodies, actors/trails          every obstacle, per frame
    actors/predictions                                  predicted trajectories, per frame
    actors/highlight                                    the mutated actor, per frame
    labels                                              names placed clear of the boxes
    accident                                            where and when the accident happens
    events                                              the outcome as a text log line
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from rocas.scenarios.model import COLORS, EGO_LENGTH_M, EGO_WIDTH_M
from rocas.viz.draw import (
    ACCIDENT_COLOR,
    EGO_COLOR,
    HIGHLIGHT_COLOR,
    body_line,
    box_outline,
    contrast,
    id_color,
    over_time,
    rgb,
    time_column,
)
from rocas.viz.execution import Execution
from rocas.viz.world import log_world

TRAIL_S = 3.0  # how far back a trail reaches [s]
TRAIL_STEP_S = 0.1  # spacing of trail points [s]


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
        ex: the execution (see :func:`rocas.viz.execution.load_execution`).
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
                indexes=time_column([t]),
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
            indexes=time_column([e[0] for e in events]),
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
    over_time(
        rec, f"{prefix}/ego/box",
        rr.LineStrips2D.from_fields(
            radii=0.12, colors=[(255, 255, 255)], labels=["ego"], show_labels=not ex.obstacles,
            draw_order=11.0
        ),
        ex.ego_t, rr.LineStrips2D.columns(strips=list(box_outline(ex.ego_xy, ex.ego_heading, size))),
    )
    over_time(
        rec, f"{prefix}/ego/body",
        rr.LineStrips2D.from_fields(radii=EGO_WIDTH_M / 2 - 0.1, colors=[EGO_COLOR], draw_order=10.5),
        ex.ego_t, rr.LineStrips2D.columns(strips=list(body_line(ex.ego_xy, ex.ego_heading, size))),
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
    over_time(rec, f"{prefix}/ego/trail", rr.Points2D.from_fields(radii=0.35, draw_order=5.0),
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
        rgb(c) if c in COLORS else id_color(i) for f in frames for i, c in zip(f.ids, f.colors, strict=True)
    ]
    labels = [
        f"{names[i]}" if i in names else f"{k} #{i}"
        for f in frames
        for i, k in zip(f.ids, f.kinds, strict=True)
    ]
    outline = [contrast(c) for c in fill]
    over_time(
        rec, f"{prefix}/actors/boxes",
        rr.LineStrips2D.from_fields(radii=0.1, show_labels=False, draw_order=9.1), times,
        rr.LineStrips2D.columns(strips=list(box_outline(xy, heading, size)), colors=outline,
                                labels=labels).partition(counts),
    )
    mutated = [i in names and names[i] in highlight for i in ids]
    _log_labels(rec, ex, prefix, [f"mutated: {t}" if m else t for t, m in zip(labels, mutated, strict=True)],
                xy, size, fill, mutated, counts)
    radii = np.maximum(size[:, 1] / 2 - 0.08, 0.1)
    over_time(
        rec, f"{prefix}/actors/bodies", rr.LineStrips2D.from_fields(draw_order=9.0), times,
        rr.LineStrips2D.columns(strips=list(body_line(xy, heading, size)), colors=fill,
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
        over_time(rec, f"{prefix}/actors/trails", rr.Points2D.from_fields(radii=0.3, draw_order=5.1),
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
            over_time(
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
        over_time(rec, f"{prefix}/labels",
                   rr.Points2D.from_fields(radii=0.05, show_labels=True, draw_order=13.0),
                   [f.t for f in ex.obstacles],
                   rr.Points2D.columns(positions=np.concatenate(pos_rows), labels=text_rows,
                                       colors=color_rows).partition(n_rows))


def _log_paths(rec: Any, ex: Execution, prefix: str) -> None:
    import rerun as rr

    if ex.plans:
        over_time(
            rec, f"{prefix}/ego/plan",
            rr.LineStrips2D.from_fields(radii=0.25, colors=[(*EGO_COLOR, 170)], draw_order=7.0),
            [p[0] for p in ex.plans], rr.LineStrips2D.columns(strips=[p[1] for p in ex.plans]),
        )
    if ex.predictions:
        color_of: dict[str, tuple[int, ...]] = {}
        for f in ex.obstacles:
            for i, c in zip(f.ids, f.colors, strict=True):
                color_of.setdefault(i, rgb(c) if c in COLORS else id_color(i))
        strips, colors, counts = [], [], []
        for _, owners, lines in ex.predictions:
            strips += lines
            colors += [(*color_of.get(o, id_color(o))[:3], 150) for o in owners]
            counts.append(len(lines))
        if sum(counts):
            over_time(
                rec, f"{prefix}/actors/predictions", rr.LineStrips2D.from_fields(radii=0.15, draw_order=6.0),
                [p[0] for p in ex.predictions],
                rr.LineStrips2D.columns(strips=strips, colors=colors).partition(counts),
            )


__all__ = ["actor_names", "first_frame_at", "log_scene"]
