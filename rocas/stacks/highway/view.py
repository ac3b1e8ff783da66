"""The Rerun view of a highway analysis: one ``.rrd`` of the accident, the reference and the
fix run on highway-env's own road, with the answer beside them.

Entity layout (timeline ``sim_time`` [s], as in :mod:`rocas.viz`)::

    world/road/surface, world/road/lines,     highway-env's lanes (static), sampled from each
    world/road/stripes                        lane's ``position(s, lateral)`` and
                                              ``width_at(s)``: the asphalt, the continuous and
                                              the striped lines its ``line_types`` name
    world/road/objects                        objects on the road (merge-v0's obstacle)
    world/<run>/ego/box, ego/body             the ego per tick; ego/path its whole path (static)
    world/<run>/vehicles/boxes, bodies        every other vehicle per tick ("v<id> <kind>")
    world/<run>/vehicles/changed              the vehicles the reference changes, outlined
    world/<run>/crash, crash/label            where and when the accident happens
    world/<run>/events                        the run's outcome as a text log line
    signals/<run>/speed, acceleration,        the ego's speed [m/s], acceleration command
    signals/<run>/steering                    [m/s^2] and steering command [rad]
    report/verdict, report/diff, report/fix   the answer as Markdown documents

``<run>`` is ``accident``, ``reference`` or ``fix`` (those the analysis has). No name from the
data (the scene's name, a vehicle's kind, a recording's path) is part of an entity path: they
appear in labels and in the documents only, escaped for Markdown
(:func:`rocas._text.markdown_text`) and never inside a code span (where no escape holds).
Rows go in with ``send_columns`` (one call per entity), the layout as the file's active
blueprint (:func:`rocas.viz.stream.rrd_recording`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas._text import markdown_text
from rocas.stacks.highway.analysis import trigger
from rocas.stacks.highway.comutation import Analysis, physical_space
from rocas.stacks.highway.world import RunResult, build
from rocas.viz.draw import (
    ACCIDENT_COLOR,
    BACKGROUND_RGB,
    EGO_COLOR,
    HIGHLIGHT_COLOR,
    ROAD_RGB,
    TIMELINE,
    body_line,
    box_outline,
    contrast,
    id_color,
    over_time,
    time_column,
)
from rocas.viz.stream import rrd_recording

#: the runs of an analysis, in the order the view shows them
RUNS = ("accident", "reference", "fix")
#: each run's colour in the ego paths and the signal plots (as rocas.viz.signals colours them)
RUN_COLORS = {"accident": (220, 50, 47), "reference": (40, 170, 80), "fix": (40, 110, 230)}
#: other vehicles' fill by highway-env behaviour class (rocas.stacks.highway.scene.KINDS)
KIND_COLORS = {"idm": (220, 200, 60), "linear": (160, 120, 220), "aggressive": (245, 130, 48),
               "defensive": (70, 200, 120), "still": (150, 150, 150)}
#: points along a lane are this far apart [m], at most MAX_LANE_POINTS per lane
LANE_STEP_M, MAX_LANE_POINTS = 1.0, 1000
#: a lane of no finite length is drawn this far [m]
UNBOUNDED_LANE_M = 2000.0
#: the road is drawn this far around every vehicle's path [m] (highway-v0's lanes are 10 km)
ROAD_MARGIN_M = 150.0
#: highway-env's own stripe pattern (``LaneGraphics.STRIPE_SPACING``, ``STRIPE_LENGTH``) [m]
STRIPE_SPACING_M, STRIPE_LENGTH_M = 4.33, 3.0
#: the crash's text sits this far from the ego's position, above it as the view shows it
#: (highway-env's y axis points down, as Rerun's 2D views draw it) [m]
CRASH_LABEL_OFFSET_M = 6.5
#: the scene views open on this much around the accident (half width, half height) [m]
FRAME_HALF_M = (45.0, 22.0)
REPORT = "report"


@dataclass(frozen=True)
class _Run:
    """One run as the view draws it: the result, its vehicles' (length, width) [m] (A, 2)
    and the ids of the vehicles the reference changes (outlined)."""

    name: str
    result: RunResult
    sizes: np.ndarray
    ego_size: tuple[float, float]
    changed: frozenset[int]


def write_analysis_rrd(path: str | os.PathLike[str], analysis: Analysis,
                       source: str | None = None) -> tuple[str, ...]:
    """Write the ``.rrd`` of ``analysis`` (atomically) with its layout as the active
    blueprint; ``source`` names the recording analysed in the verdict.

    Returns:
        The runs drawn (``accident`` and those of ``reference`` and ``fix`` it has).

    Raises:
        OutputError: the file cannot be written.
    """
    changed = frozenset(int(k.split(".", 1)[0][1:]) for k in analysis.reference_change)
    runs = [_prepared(name, r, changed if name != "fix" else frozenset())
            for name, r in (("accident", analysis.accident), ("reference", analysis.reference),
                            ("fix", analysis.fix_run)) if r is not None]
    names = tuple(r.name for r in runs)
    with rrd_recording(path, blueprint(names, _frame(analysis.accident)),
                       kind="highway-analysis") as rec:
        _log_road(rec, runs)
        for run in runs:
            _log_run(rec, run)
            _log_signals(rec, run)
        _log_report(rec, analysis, source)
    return names


def _prepared(name: str, result: RunResult, changed: frozenset[int]) -> _Run:
    sim = build(result.scene, result.params, result.seed)  # for the sizes: nothing is stepped
    sizes = np.array([(v.LENGTH, v.WIDTH) for v in sim.others], dtype=np.float64).reshape(-1, 2)
    return _Run(name, result, sizes, (float(sim.ego.LENGTH), float(sim.ego.WIDTH)), changed)


# -- the road -----------------------------------------------------------------------------------

def _bounds(runs: Sequence[_Run]) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) corners (2,) [m] of every vehicle's path, widened by ROAD_MARGIN_M."""
    pts = [r.result.ego[:, :2] for r in runs]
    pts += [r.result.others[:, :, :2].reshape(-1, 2) for r in runs]
    xy = np.concatenate(pts)
    return xy.min(axis=0) - ROAD_MARGIN_M, xy.max(axis=0) + ROAD_MARGIN_M


def _spans(inside: np.ndarray) -> list[slice]:
    """The contiguous runs of True in ``inside`` (n,) that hold at least two points."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], inside.astype(np.int8), [0]])))
    return [slice(a, b) for a, b in zip(edges[::2], edges[1::2], strict=True) if b - a >= 2]


def _lane_geometry(lane: Any, low: np.ndarray, high: np.ndarray
                   ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The parts of ``lane`` inside the box: (s (n,) [m], centre (n, 2) [m], width (n,) [m])."""
    length = float(lane.length) if math.isfinite(lane.length) else UNBOUNDED_LANE_M
    n = min(max(math.ceil(length / LANE_STEP_M), 1), MAX_LANE_POINTS)
    s = np.linspace(0.0, length, n + 1)
    centre = np.array([lane.position(float(x), 0.0) for x in s], dtype=np.float64)
    width = np.array([lane.width_at(float(x)) for x in s], dtype=np.float64)
    inside = np.all((centre >= low) & (centre <= high), axis=1)
    return [(s[p], centre[p], width[p]) for p in _spans(inside)]


def _side(lane: Any, s: np.ndarray, width: np.ndarray, side: int) -> np.ndarray:
    """Points (n, 2) [m] along one side of a lane (0: lateral -w/2, 1: +w/2, as highway-env's
    ``LaneGraphics`` draws them)."""
    return np.array([lane.position(float(x), (side - 0.5) * float(w))
                     for x, w in zip(s, width, strict=True)], dtype=np.float64)


def _stripes(lane: Any, s: np.ndarray, side: int) -> list[np.ndarray]:
    """The dashes of a striped side within [s[0], s[-1]]: three points each (curves bend)."""
    starts = np.arange(math.ceil(s[0] / STRIPE_SPACING_M) * STRIPE_SPACING_M,
                       s[-1] - STRIPE_LENGTH_M, STRIPE_SPACING_M)
    out = []
    for a in starts:
        ss = np.array([a, a + STRIPE_LENGTH_M / 2, a + STRIPE_LENGTH_M])
        out.append(_side(lane, ss, np.array([lane.width_at(float(x)) for x in ss]), side))
    return out


def _log_road(rec: Any, runs: Sequence[_Run]) -> None:
    """highway-env's road of the accident's scene (the reference and the fix drive on it too:
    the physical search changes the other vehicles only) and its objects, static."""
    import importlib

    import rerun as rr

    accident = runs[0].result
    road = build(accident.scene, accident.params, accident.seed).road  # imports highway-env
    line_type = importlib.import_module("highway_env.road.lane").LineType
    low, high = _bounds(runs)
    surface: dict[float, list[np.ndarray]] = {}
    lines: list[np.ndarray] = []
    stripes: list[np.ndarray] = []
    for lane in (ln for tos in road.network.graph.values() for lns in tos.values() for ln in lns):
        for s, centre, width in _lane_geometry(lane, low, high):
            surface.setdefault(round(float(np.median(width)), 2), []).append(centre)
            for side in (0, 1):
                kind = lane.line_types[side]
                if kind in (line_type.CONTINUOUS, line_type.CONTINUOUS_LINE):
                    lines.append(_side(lane, s, width, side))
                elif kind == line_type.STRIPED:
                    stripes += _stripes(lane, s, side)
    for i, (w, strips) in enumerate(sorted(surface.items())):
        rec.log("world/road/surface" if i == 0 else f"world/road/surface_{i}",
                rr.LineStrips2D(strips, radii=w / 2, colors=[ROAD_RGB], draw_order=0.0),
                static=True)
    for entity, strips, radius in (("lines", lines, 0.15), ("stripes", stripes, 0.12)):
        if strips:
            rec.log(f"world/road/{entity}", rr.LineStrips2D(
                strips, radii=radius, colors=[(235, 235, 235)], draw_order=1.0), static=True)
    objects = list(road.objects)
    if objects:
        xy = np.array([o.position for o in objects], dtype=np.float64).reshape(-1, 2)
        heading = np.array([o.heading for o in objects], dtype=np.float64)
        size = np.array([(o.LENGTH, o.WIDTH) for o in objects], dtype=np.float64)
        rec.log("world/road/objects", rr.LineStrips2D(
            list(box_outline(xy, heading, size)), radii=0.2, colors=[(250, 120, 20)],
            labels=[type(o).__name__.lower() for o in objects], show_labels=False,
            draw_order=4.0), static=True)


# -- the runs -----------------------------------------------------------------------------------

def _outcome(r: RunResult) -> tuple[float, str] | None:
    """(time [s], what) of the run's accident, or None."""
    if r.collided and r.collision_t_s is not None:
        if r.collided_with > 0:
            kind = r.scene.others[r.collided_with - 1].kind
            what = f"collision with v{r.collided_with} ({kind})"
        else:
            what = "collision with an object on the road"
        return r.collision_t_s, what
    if r.off_road and r.off_road_t_s is not None:
        return r.off_road_t_s, "off road"
    return None


def _log_run(rec: Any, run: _Run) -> None:
    """The ego, the other vehicles, the crash and the outcome of one run."""
    import rerun as rr

    r, prefix = run.result, f"world/{run.name}"
    k = len(r.times)
    if k == 0:
        return
    size = np.tile(run.ego_size, (k, 1))
    over_time(rec, f"{prefix}/ego/box", rr.LineStrips2D.from_fields(
        radii=0.12, colors=[(255, 255, 255)], labels=["ego"], show_labels=True,
        draw_order=11.0), r.times,
        rr.LineStrips2D.columns(strips=list(box_outline(r.ego[:, :2], r.ego[:, 2], size))))
    over_time(rec, f"{prefix}/ego/body", rr.LineStrips2D.from_fields(
        radii=run.ego_size[1] / 2 - 0.1, colors=[EGO_COLOR], draw_order=10.5), r.times,
        rr.LineStrips2D.columns(strips=list(body_line(r.ego[:, :2], r.ego[:, 2], size))))
    rec.log(f"{prefix}/ego/path", rr.LineStrips2D(
        [r.ego[:, :2]], radii=0.3, colors=[(*RUN_COLORS[run.name], 200)],
        labels=[run.name], show_labels=False, draw_order=5.0), static=True)
    _log_vehicles(rec, run, prefix)
    event = _outcome(r)
    if event is not None:
        t, what = event
        x, y = r.ego[-1, :2]
        a = np.linspace(0.0, 2 * np.pi, 41)
        ring = np.stack([x + 4.0 * np.cos(a), y + 4.0 * np.sin(a)], axis=1)
        label = f"{run.name}: {what} at {t:.2f} s"
        over_time(rec, f"{prefix}/crash", rr.LineStrips2D.from_fields(
            radii=0.35, colors=[ACCIDENT_COLOR], show_labels=False, draw_order=12.0), [t],
            rr.LineStrips2D.columns(strips=[ring], labels=[label]))
        # its text above the ring, clear of the ego's own label
        over_time(rec, f"{prefix}/crash/label", rr.Points2D.from_fields(
            radii=0.05, colors=[ACCIDENT_COLOR], show_labels=True, draw_order=13.0), [t],
            rr.Points2D.columns(positions=[(x, y - CRASH_LABEL_OFFSET_M)], labels=[label]))
        text, level = f"{run.name}: {what} at {t:.2f} s", "CRITICAL"
    else:
        t = float(r.times[-1])
        text = (f"{run.name}: no accident in {r.scene.duration_s:g} s (smallest clearance "
                f"{r.min_margin_m:.2f} m)")
        level = "INFO"
    rec.send_columns(f"{prefix}/events", indexes=time_column([t]),
                     columns=rr.TextLog.columns(text=[text], level=[level]))


def _log_vehicles(rec: Any, run: _Run, prefix: str) -> None:
    """The other vehicles per tick: outlines (labelled ``v<id> <kind>``), filled bodies, and
    the ones the reference changes outlined in the highlight colour."""
    import rerun as rr

    r = run.result
    k, a = r.others.shape[:2]
    if a == 0:
        return
    xy = r.others[:, :, :2].reshape(-1, 2)
    heading = r.others[:, :, 2].reshape(-1)
    size = np.tile(run.sizes, (k, 1))
    kinds = [o.kind for o in r.scene.others]
    fill = [KIND_COLORS.get(kd, id_color(kd)[:3]) for kd in kinds]
    labels = [f"v{i} {kd}" for i, kd in enumerate(kinds, start=1)]
    over_time(rec, f"{prefix}/vehicles/boxes", rr.LineStrips2D.from_fields(
        radii=0.1, draw_order=9.1), r.times,
        rr.LineStrips2D.columns(strips=list(box_outline(xy, heading, size)),
                                colors=[contrast(c) for c in fill] * k).partition([a] * k))
    # the labels on the bodies: in the body's colour, which reads on the label's dark ground
    over_time(rec, f"{prefix}/vehicles/bodies", rr.LineStrips2D.from_fields(
        show_labels=True, draw_order=9.0), r.times, rr.LineStrips2D.columns(
            strips=list(body_line(xy, heading, size)), colors=fill * k, labels=labels * k,
            radii=np.maximum(size[:, 1] / 2 - 0.08, 0.1)).partition([a] * k))
    ids = sorted(i for i in run.changed if 1 <= i <= a)
    if ids:
        cols = np.array(ids) - 1
        sub = r.others[:, cols, :]
        over_time(rec, f"{prefix}/vehicles/changed", rr.LineStrips2D.from_fields(
            radii=0.35, colors=[HIGHLIGHT_COLOR], show_labels=True, draw_order=9.2), r.times,
            rr.LineStrips2D.columns(
                strips=list(box_outline(sub[:, :, :2].reshape(-1, 2), sub[:, :, 2].reshape(-1),
                                        np.tile(run.sizes[cols] + 1.2, (k, 1)))),
                labels=[f"changed: v{i}" for i in ids] * k).partition([len(ids)] * k))


def _log_signals(rec: Any, run: _Run) -> None:
    """The ego's speed and its commands on ``sim_time``, one series per run."""
    import rerun as rr

    r = run.result
    for entity, values in (("speed", r.ego[:, 3]), ("acceleration", r.ego[:, 4]),
                           ("steering", r.steering)):
        over_time(rec, f"signals/{run.name}/{entity}",
                  rr.SeriesLines(names=run.name, colors=[RUN_COLORS[run.name]], widths=1.5),
                  r.times, rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)))


# -- the answer ---------------------------------------------------------------------------------

def _log_report(rec: Any, a: Analysis, source: str | None) -> None:
    import rerun as rr

    for name, text in (("verdict", verdict_markdown(a, source)), ("diff", diff_markdown(a)),
                       ("fix", fix_markdown(a))):
        rec.log(f"{REPORT}/{name}", rr.TextDocument(text, media_type="text/markdown"),
                static=True)


def _outcome_text(r: RunResult | None) -> str:
    if r is None:
        return "none"
    event = _outcome(r)
    if event is None:
        return f"no accident (smallest clearance {r.min_margin_m:.2f} m)"
    return f"{event[1]} at {event[0]:.2f} s"


def verdict_markdown(a: Analysis, source: str | None = None) -> str:
    """The answer in a few lines: verdict, module, fix, validation, time and simulations."""
    verdict = "misconfiguration" if a.fix else "no_configuration_fix"
    fix = ", ".join(f"{markdown_text(k)} = {v:.4g}" for k, v in sorted(a.fix.items()))
    rows = [f"# {markdown_text(a.accident.scene.name)}: {verdict}", ""]
    if source is not None:
        rows += [f"Recording: {markdown_text(source)}", ""]
    rows += [f"- accident: {_outcome_text(a.accident)} "
             f"({markdown_text(a.accident.scene.env_id)}, seed {a.accident.seed})",
             f"- deviating module: **{markdown_text(a.module or 'none')}** (diff: "
             f"{markdown_text(a.deviating_module or 'none')}, searched: "
             f"{markdown_text(a.searched_module or 'none')})",
             f"- fix: {fix or 'none'}",
             f"- validation: avoids {a.validated} of {a.variants} variants that crash unfixed",
             "", "| phase | time [s] | simulations |", "|---|---|---|"]
    rows += [f"| {markdown_text(p)} | {s:.1f} | {a.simulations.get(p, 0)} |"
             for p, s in a.seconds.items()]
    return "\n".join(rows) + "\n"


def diff_markdown(a: Analysis) -> str:
    """The reference (what the physical search changed) and the diff's deviating module."""
    rows = ["# Differential analysis", ""]
    if a.reference is None:
        rows += ["**No reference**: the physical search found no nearby scene without the "
                 "accident, so there was nothing to diff; the cyber search covered "
                 f"{markdown_text(a.searched_module or 'driver')}."]
        return "\n".join(rows + confidence_markdown(a)) + "\n"
    who, prop = trigger(a)
    space = physical_space(a.accident.scene)
    rows += [f"Reference: {_outcome_text(a.reference)}. The physical search changed:", "",
             "| vehicle property | accident | reference |", "|---|---|---|"]
    for name in sorted(a.reference_change):
        mark = " (trigger)" if name == f"{who}.{prop}" else ""
        rows.append(f"| {markdown_text(name)}{mark} | "
                    f"{_value(space.variable(name).original)} | "
                    f"{_value(a.reference_change[name])} |")
    module = a.deviating_module
    rows += ["", f"**Initial deviating module: {markdown_text(module)}**" if module else
             "**The diff named no deviating module.**"]
    if a.module != module:
        rows += ["", f"The answer's module is the fix's, **{markdown_text(a.module)}**: the "
                 "diff's module has no parameters, or none of them held a fix."]
    return "\n".join(rows + confidence_markdown(a)) + "\n"


def confidence_markdown(a: Analysis) -> list[str]:
    """The confidence in the answer's module: the references' diffs and module substitution."""
    if a.confidence is None:
        return []
    rows = ["", f"Confidence in **{markdown_text(a.module or 'none')}**: **{a.confidence}**."]
    agree = a.agreement
    if agree is not None:
        named = ", ".join(markdown_text(m or "none") for m in a.reference_modules)
        rows.append(f"{agree['same']} of {agree['runs']} references' diffs name it (their "
                    f"modules, the chosen reference's first: {named}).")
    if a.substitution is not None:
        rows.append(f"Module substitution {a.stance}: {markdown_text(a.substitution.reason)}.")
    return rows


def fix_markdown(a: Analysis) -> str:
    """The fix against the accident's values, the fix run, the validation, the other fixes."""
    searched = markdown_text(a.searched_module or "driver")
    if not a.fix:
        return ("# No configuration fix\n\nNo change of the parameters searched "
                f"({searched}) avoids the accident.\n")
    before = dict(a.accident.params)
    rows = [f"# Fix (cyber search over {searched})", "",
            "| parameter | accident | fix |", "|---|---|---|"]
    rows += [f"| {markdown_text(k)} | {before.get(k, float('nan')):.4g} | {v:.4g} |"
             for k, v in sorted(a.fix.items())]
    rows += ["", f"Fix run: {_outcome_text(a.fix_run)}.", "",
             f"Validation: avoids the accident on {a.validated} of {a.variants} perturbed "
             "variants that crash unfixed."]
    if a.alternatives:
        rows += ["", "Other fixes, smallest change first:", ""]
        rows += ["- " + ", ".join(f"{markdown_text(k)} = {v:.4g}" for k, v in sorted(f.items()))
                 for f in a.alternatives]
    return "\n".join(rows) + "\n"


def _value(v: object) -> str:
    return f"{v:.4g}" if isinstance(v, float) else markdown_text(v)


# -- the layout ---------------------------------------------------------------------------------

def _frame(accident: RunResult) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """(x range, y range) [m] around the accident's last pose, or None without a pose."""
    if not len(accident.times):
        return None
    x, y = (float(v) for v in accident.ego[-1, :2])
    return (x - FRAME_HALF_M[0], x + FRAME_HALF_M[0]), (y - FRAME_HALF_M[1], y + FRAME_HALF_M[1])


def blueprint(runs: Sequence[str], frame: tuple[tuple[float, float], tuple[float, float]] | None
              = None) -> Any:
    """Scene tabs (one per run, and the ego paths of all of them) over the signal plots; the
    verdict, diff and fix documents over the events on the right."""
    import rerun.blueprint as rrb

    bounds = None if frame is None else rrb.VisualBounds2D(x_range=frame[0], y_range=frame[1])

    def scene(name: str, contents: list[str]) -> Any:
        return rrb.Spatial2DView(origin="world", contents=["+ world/road/**", *contents],
                                 name=name, background=BACKGROUND_RGB, visual_bounds=bounds)

    scenes = [scene(f"Scene: {r}", [f"+ world/{r}/**"]) for r in runs]
    scenes.append(scene("Ego paths", [c for r in runs for c in (f"+ world/{r}/ego/path",
                                                                  f"+ world/{r}/crash/**")]))
    plots = [rrb.TimeSeriesView(origin="signals", contents=[f"+ signals/{r}/{s}" for r in runs],
                                name=title)
             for s, title in (("speed", "Ego speed [m/s]"),
                              ("acceleration", "Acceleration command [m/s²]"),
                              ("steering", "Steering command [rad]"))]
    left = rrb.Vertical(rrb.Tabs(*scenes, active_tab=0), rrb.Tabs(*plots, active_tab=0),
                        row_shares=[3, 2])
    docs = rrb.Tabs(rrb.TextDocumentView(origin=f"{REPORT}/verdict", name="Verdict"),
                    rrb.TextDocumentView(origin=f"{REPORT}/diff", name="Differential analysis"),
                    rrb.TextDocumentView(origin=f"{REPORT}/fix", name="Fix"), active_tab=0)
    events = rrb.TextLogView(origin="world", contents=[f"+ world/{r}/events" for r in runs],
                             name="Outcomes")
    right = rrb.Vertical(docs, events, row_shares=[3, 1])
    return rrb.Blueprint(rrb.Horizontal(left, right, column_shares=[5, 3]),
                         rrb.TimePanel(timeline=TIMELINE, state="collapsed"),
                         collapse_panels=True)


__all__ = ["blueprint", "diff_markdown", "fix_markdown", "verdict_markdown",
           "write_analysis_rrd"]
