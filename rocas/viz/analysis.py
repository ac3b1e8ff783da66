"""The whole analysis in one ``.rrd``: executions, differential analysis, searches, verdict.

Entity layout::

    executions/<name>/...       scene and signals of each execution (rocas.viz.scene, .signals);
                                name: accident, reference, fixed; timeline ``sim_time`` [s]
    diff/...                    the differential analysis (rocas.viz.diff), on ``time`` and
                                ``sim_time``
    search/<phase>/...          search progress (rocas.viz.search), timeline ``generation``
    validation/...              phase V (static): accident-free share of the perturbed variants
                                for the original, the minimal fix and each stronger value, and a
                                table of them with the robust value marked
    verdict                     the report as a markdown document

The default blueprint shows the scene (one tab per execution), the module signals, the MDR
plots, the channel-module graph and the verdict at once; the search plots sit in tabs beside
the verdict (they need the ``generation`` timeline selected in the time panel).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rocas.errors import InputError
from rocas.viz.draw import BACKGROUND_RGB, TIMELINE
from rocas.viz.execution import MAX_CHANNELS_SHOWN, Execution, load_execution
from rocas.viz.scene import log_scene
from rocas.viz.signals import log_signals
from rocas.viz.stream import rrd_recording

if TYPE_CHECKING:
    from rocas.analysis.diff import DiffResult
    from rocas.pipeline.results import ValidationResult
    from rocas.search.ga import GenerationStats

EXECUTIONS = ("accident", "reference", "fixed")
VERDICT_ENTITY = "verdict"
VALIDATION_ENTITY = "validation"


def log_verdict(rec: Any, markdown: str, entity: str = VERDICT_ENTITY) -> None:
    """Log the verdict (a markdown string) as a static text document."""
    import rerun as rr

    rec.log(entity, rr.TextDocument(markdown, media_type="text/markdown"), static=True)


def log_validation(rec: Any, validation: ValidationResult | None, entity: str = VALIDATION_ENTITY
                   ) -> None:
    """Log phase V (the report's ``validation``) as static bar charts and a table.

    ``<entity>/original`` is one bar at x = -0.125, ``<entity>/fix`` the minimal fix at x = 0 and
    the stronger values at their fraction of the way to the range's end (x = 0.125 ... 1), all in
    % of the variants that stay accident-free; ``<entity>/summary`` is the table. Logs nothing
    when there was no validation.
    """
    import numpy as np
    import rerun as rr

    from rocas.pipeline.report import validation_text

    if validation is None or not validation.variants:
        return
    original, fixed = validation_text(validation)
    rec.log(f"{entity}/original",
            rr.BarChart([original], abscissa=[-0.125], widths=[0.1], color=(220, 50, 47)), static=True)
    run = [s for s in validation.stronger if s.success_rate is not None]  # the sweep may stop early
    xs = [0.0] + [float(s.fraction) for s in run]
    ys = [fixed] + [100 * s.success_rate for s in run]  # type: ignore[operator]
    rec.log(f"{entity}/fix", rr.BarChart(np.asarray(ys), abscissa=np.asarray(xs),
                                         widths=[0.1] * len(xs), color=(40, 170, 80)), static=True)
    rec.log(f"{entity}/summary", rr.TextDocument(_validation_table(validation), media_type="text/markdown"),
            static=True)


def _validation_table(validation: ValidationResult) -> str:
    """Phase V as a markdown table: the original, the minimal fix and each stronger value."""
    from rocas.pipeline.report import sweep_text, validation_text

    original, fixed = validation_text(validation)
    robust = validation.robust_fix.fraction if validation.robust_fix is not None else None
    rows = ["| configuration | values | accident-free | avoids this accident | h1 [m^2] |",
            "|---|---|---|---|---|",
            f"| original | | {original:.1f} % | no | |",
            f"| minimal fix | | {fixed:.1f} % | yes | |"]
    for st in validation.stronger:
        values = ", ".join(f"{k} = {v:.4g}" for k, v in st.fix.items())
        mark = " **(robust value)**" if st.fraction == robust else ""
        rate = (f"{100 * st.success_rate:.1f} %" if st.success_rate is not None
                else f"not run: {st.skipped or 'skipped'}")
        rows.append(f"| {st.fraction:g} of the way to the range end{mark} | {values} | "
                    f"{rate} | {'yes' if st.avoids_accident else 'no'} | {st.h1_m2:.3g} |")
    return (f"# Validation\n\n{validation.variants} perturbed variants, each run with every "
            "configuration below that could still change the robust value.\n\n"
            + "\n".join(rows) + "\n" + (f"\n{sweep_text(validation)}\n" if sweep_text(validation) else ""))


def log_execution(
    rec: Any,
    name: str,
    execution: Execution | str | os.PathLike[str],
    *,
    highlight: Iterable[str] = (),
    channels: bool = True,
) -> Execution:
    """Log the scene and the signals of one execution under ``executions/<name>``."""
    ex = execution if isinstance(execution, Execution) else load_execution(execution)
    prefix = f"executions/{name}"
    log_scene(rec, ex, prefix, highlight=highlight, label=name)
    log_signals(rec, ex, prefix, label=name, channels=channels)
    return ex


def scene_bounds(
    ex: Execution | None, half_width_m: float = 45.0, half_height_m: float = 22.0
) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """(x range, y range) [m] framing the accident (else the ego's whole path), or None."""
    if ex is None or len(ex.ego_t) == 0:
        return None
    acc = ex.accident()
    if acc is not None and ex.ego_at(acc[0]) is not None:
        x, y, _ = ex.ego_at(acc[0])  # type: ignore[misc]
        if acc[2] is not None:
            x, y = acc[2]
        return (x - half_width_m, x + half_width_m), (y - half_height_m, y + half_height_m)
    lo, hi = ex.ego_xy.min(axis=0) - 15.0, ex.ego_xy.max(axis=0) + 15.0
    return (float(lo[0]), float(hi[0])), (float(lo[1]), float(hi[1]))


def _scene_view(name: str, ex: Execution | None = None) -> Any:
    import rerun.blueprint as rrb

    bounds = scene_bounds(ex)
    return rrb.Spatial2DView(
        origin=f"executions/{name}",
        contents=["+ $origin/world/**", "+ $origin/ego/**", "+ $origin/actors/**", "+ $origin/accident",
                  "+ $origin/labels"],
        name=f"Scene: {name}",
        background=BACKGROUND_RGB,
        visual_bounds=None if bounds is None else rrb.VisualBounds2D(x_range=bounds[0], y_range=bounds[1]),
    )


def _signal_views(names: Sequence[str], with_brake: bool) -> list[Any]:
    import rerun.blueprint as rrb

    views = [
        rrb.TimeSeriesView(
            origin="executions",
            contents=[f"+ executions/{n}/signals/speed" for n in names],
            name="Speed [m/s]",
        ),
        rrb.TimeSeriesView(
            origin="executions",
            contents=[f"+ executions/{n}/signals/acceleration/**" for n in names],
            name="Acceleration [m/s²]",
        ),
    ]
    if with_brake:
        views.append(
            rrb.TimeSeriesView(
                origin="executions",
                contents=[f"+ executions/{n}/signals/brake/**" for n in names],
                name="Brake classifier",
                axis_y=rrb.ScalarAxis(range=(0.0, 1.0)),
            )
        )
    views.append(
        rrb.TextLogView(
            origin="executions",
            contents=[f"+ executions/{n}/signals/decisions" for n in names]
            + [f"+ executions/{n}/events" for n in names],
            name="Decisions and events",
        )
    )
    return views


#: The window the default layout is designed for [points] (the README picture's size).
WINDOW_PT = (1600, 900)


def analysis_blueprint(
    executions: Sequence[str] = EXECUTIONS,
    *,
    diff: bool = True,
    diff_result: DiffResult | None = None,
    searches: Sequence[str] = (),
    verdict: bool = True,
    brake: bool = True,
    focus: Execution | None = None,
    validation: bool = False,
) -> Any:
    """The default layout, three columns: scene over signals; the CMG after Algorithm 1 (tabs:
    change points, removed edges); the MDR plot over the verdict (tabs: searches, validation).

    ``diff_result``: frames the MDR plot on its change points and the CMG view on its graph.
    ``focus``: the execution whose accident the scene views frame (default: the whole map).
    """
    import rerun.blueprint as rrb

    from rocas.viz.diff import cmg_view, mdr_view

    scenes = [_scene_view(n, focus) for n in executions]
    left = rrb.Vertical(
        rrb.Tabs(*scenes, active_tab=0) if len(scenes) > 1 else scenes[0],
        rrb.Tabs(*_signal_views(executions, brake), active_tab=0),
        row_shares=[3, 2],
    )
    columns: list[Any] = [left]
    shares = [5.0]
    right_parts: list[Any] = []
    if diff:
        columns.append(rrb.Tabs(
            cmg_view(diff_result),
            rrb.TextLogView(origin="diff/events", name="Change points"),
            rrb.TextDocumentView(origin="diff/removed_edges", name="Removed edges"),
            active_tab=0,
        ))
        shares.append(3.0)
        right_parts.append(mdr_view(diff_result, panel_height_pt=0.45 * (WINDOW_PT[1] - 80)))
    bottom: list[Any] = []
    if verdict:
        bottom.append(rrb.TextDocumentView(origin=VERDICT_ENTITY, name="Verdict"))
    for phase in searches:
        bottom.extend(search_views(phase))
    if validation:
        bottom.append(rrb.BarChartView(origin=VALIDATION_ENTITY, name="Validation"))
        bottom.append(rrb.TextDocumentView(origin=f"{VALIDATION_ENTITY}/summary", name="Validation table"))
    if bottom:
        right_parts.append(rrb.Tabs(*bottom, active_tab=0) if len(bottom) > 1 else bottom[0])
    if right_parts:
        columns.append(rrb.Vertical(*right_parts, row_shares=[45, 55][: len(right_parts)])
                       if len(right_parts) > 1 else right_parts[0])
        shares.append(3.0)
    layout = rrb.Horizontal(*columns, column_shares=shares) if len(columns) > 1 else left
    return rrb.Blueprint(layout, rrb.TimePanel(timeline=TIMELINE, state="collapsed"),
                         collapse_panels=True)


def search_views(phase: str) -> list[Any]:
    """The views of one search: what it tried and where it ended (static, any timeline), its
    progress per generation (``generation`` timeline), and its table."""
    import rerun.blueprint as rrb

    title = phase.capitalize()
    return [
        rrb.Spatial2DView(origin=f"search/{phase}/tried", name=f"{title} search: tried",
                          background=(24, 24, 28)),
        rrb.TimeSeriesView(
            origin=f"search/{phase}",
            contents=[f"+ search/{phase}/objectives/**", f"+ search/{phase}/best/**",
                      f"+ search/{phase}/feasible"],
            name=f"{title} search: per generation",
        ),
        rrb.TextDocumentView(origin=f"search/{phase}/summary", name=f"{title} table"),
    ]


#: The timeline of Rerun's own MCAP importer, which ``rocas view RECORDING.mcap`` uses to show
#: every channel (protobuf, ROS 2 and Foxglove schemas decoded by Rerun, other channels raw)
#: at the entity path of its topic (rerun-sdk 0.41 ignores an entity path prefix for MCAP):
#: the importer's timeline (each message's MCAP log time).
MCAP_TIMELINE = "message_log_time"


def recording_blueprint(name: str, ex: Execution, topics: Sequence[str] = ()) -> Any:
    """The layout of ``rocas view RECORDING.mcap``: scene and signals (when rocas finds them in
    the recording) left, and every channel as Rerun's MCAP importer shows it (``topics``), one
    tab each."""
    import rerun.blueprint as rrb

    channel_views = [
        rrb.DataframeView(origin=t if t.startswith("/") else "/" + t, name=t)
        for t in sorted(topics)
    ]
    right = rrb.Tabs(*channel_views, active_tab=0) if channel_views else None
    if right is not None and ex.world is None and not len(ex.ego_t) and not _signal_channels(ex):
        layout = right
        timeline = MCAP_TIMELINE
    else:
        left = rrb.Vertical(
            _scene_view(name, ex),
            rrb.Tabs(*_signal_views([name], _has_brake(ex)), active_tab=0),
            row_shares=[3, 2],
        )
        layout = rrb.Horizontal(left, right, column_shares=[3, 2]) if right is not None else left
        timeline = TIMELINE
    return rrb.Blueprint(layout, rrb.TimePanel(timeline=timeline), collapse_panels=True)


def _signal_channels(ex: Execution) -> list[str]:
    return [c.topic for c in ex.channels.values() if len(c.times_s) and c.names]


def _has_brake(ex: Execution) -> bool:
    return any("brake_probability" in c.names for c in ex.channels.values())


def write_recording_rrd(
    path: str | os.PathLike[str], recording: str | os.PathLike[str], name: str = "accident"
) -> tuple[Execution, tuple[str, ...]]:
    """Write the ``.rrd`` of one plain recording with its layout: the scene and signals rocas
    reads from it, and the recording itself through Rerun's MCAP importer (each channel at its
    topic's entity path), which shows every channel in the viewer's own way.

    Returns:
        The execution rocas read and the topics that hold messages.

    Raises:
        InputError: the recording holds neither a readable message nor a world attachment
            (the ``.rrd`` would be empty).
    """
    from rocas.recording import open_recording

    ex = load_execution(recording)
    scan = open_recording(recording).scan()
    topics = tuple(sorted(t for t, st in scan.report.channel_stats.items() if st.messages))
    if not topics and ex.world is None:
        raise InputError(f"{recording}: nothing to show (no readable message and no world)")
    if len(topics) > MAX_CHANNELS_SHOWN:
        # Rerun's importer would make an entity of every channel: gigabytes for tens of
        # thousands of them, and nothing readable; rocas's own plots stay (the first ones)
        ex.warnings.append(
            f"{Path(recording).name}: {len(topics)} channels are more than the view imports "
            f"({MAX_CHANNELS_SHOWN}); the recording is shown through rocas's own plots of its "
            "first channels only, not Rerun's MCAP importer")
        topics, own_plots = (), True
    else:
        own_plots = False
    import tempfile

    with tempfile.TemporaryDirectory(prefix="rocas-view-") as tmp:
        source = Path(recording)
        if topics and scan.format != "mcap":
            # Rerun imports MCAP: a ROS bag or Cyber record goes in as an MCAP copy, kept
            # until the .rrd is written
            from rocas.recording.convert import write_mcap

            source = Path(tmp) / "recording.mcap"
            write_mcap(scan, source)  # type: ignore[arg-type]
        with rrd_recording(path, recording_blueprint(name, ex, topics), kind="view") as rec:
            log_execution(rec, name, ex, channels=own_plots)
            if topics:
                rec.log_file_from_path(source)
    return ex, topics


def write_analysis_rrd(
    path: str | os.PathLike[str],
    *,
    accident: str | os.PathLike[str] | Execution,
    reference: str | os.PathLike[str] | Execution | None = None,
    fixed: str | os.PathLike[str] | Execution | None = None,
    diff_result: DiffResult | None = None,
    searches: Mapping[str, Sequence[GenerationStats]] = {},  # noqa: B006 (read only)
    verdict_md: str | None = None,
    highlight: str | Iterable[str] | None = None,
    best_labels: Mapping[str, list[str]] | None = None,
) -> None:
    """Write the analysis ``.rrd`` (atomically) with the default blueprint.

    Args:
        path: the ``.rrd`` to write.
        accident, reference, fixed: recordings (paths) or loaded executions; reference and
            fixed are optional.
        diff_result: the differential analysis of accident vs reference.
        searches: phase name (``physical``, ``cyber``) -> per-generation statistics.
        verdict_md: the report as markdown.
        highlight: scenario entity id(s) mutated in the reference execution (drawn highlighted
            there, and outlined in the accident for comparison).
        best_labels: phase -> best candidate so far, one label per generation.
    """
    from rocas.viz.diff import log_diff
    from rocas.viz.search import log_search

    ids = [highlight] if isinstance(highlight, str) else list(highlight or ())
    runs = [
        (n, e)
        for n, e in (("accident", accident), ("reference", reference), ("fixed", fixed))
        if e is not None
    ]
    executions = [(n, e if isinstance(e, Execution) else load_execution(e)) for n, e in runs]
    bp = analysis_blueprint(
        [n for n, _ in executions],
        diff=diff_result is not None,
        diff_result=diff_result,
        searches=[p for p, g in searches.items() if g],
        verdict=verdict_md is not None,
        brake=any(_has_brake(e) for _, e in executions),
        focus=executions[0][1],
    )
    with rrd_recording(path, bp, kind="analysis") as rec:
        for name, ex in executions:
            log_execution(rec, name, ex, highlight=ids if name in ("accident", "reference") else ())
        if diff_result is not None:
            log_diff(rec, diff_result, "diff", timelines=("time", TIMELINE))
        for phase, gens in searches.items():
            if gens:
                log_search(rec, phase, list(gens), (best_labels or {}).get(phase))
        if verdict_md is not None:
            log_verdict(rec, verdict_md)


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: unreadable JSON ({exc})") from None


def search_outcome(phase: str, data: Mapping[str, Any]) -> str | None:
    """Where a search of a run directory ended, in words (from ``physical.json``/``cyber.json``)."""
    if phase == "physical":
        trig = data.get("triggering_entity") or {}
        if not trig:
            return "no triggering entity found"
        props = ", ".join(f"{p['name']} {p['original']} -> {p['mutated']}"
                          for p in trig.get("properties", []))
        return f"{trig.get('entity')}" + (f" ({props})" if props else "")
    if phase == "cyber":
        mis = data.get("misconfiguration") or []
        if not mis:
            return "no fix found"
        return ", ".join(f"{m['parameter']} {m['original']:.4g} -> {m['mutated']:.4g}" for m in mis)
    return None


def run_dir_contents(run_dir: str | os.PathLike[str]) -> dict[str, Any]:
    """What a ``rocas analyze`` run directory holds, read into Python objects.

    Keys (only for the files that exist): ``accident``, ``reference``, ``fixed`` (paths),
    ``diff`` (the diff JSON), ``searches`` (phase -> generations), ``verdict_md``,
    ``report`` (report.json as a :class:`~rocas.pipeline.report.Report`), ``validation``
    (its phase V result, when variants ran),
    ``highlight`` (mutated entity ids from physical.json).
    """
    from rocas.viz.search import generations_from_json

    d = Path(run_dir)
    if not d.is_dir():
        raise InputError(f"{d}: not a directory")
    out: dict[str, Any] = {"searches": {}}
    for name in EXECUTIONS:
        if (d / f"{name}.mcap").is_file():
            out[name] = d / f"{name}.mcap"
    if (d / "diff.json").is_file():
        out["diff"] = _read_json(d / "diff.json")
    for phase in ("physical", "cyber"):
        if (d / f"{phase}.json").is_file():
            data = _read_json(d / f"{phase}.json")
            out["searches"][phase] = generations_from_json(data.get("generations", []))
            out.setdefault("outcomes", {})[phase] = search_outcome(phase, data)
            trig = data.get("triggering_entity") or {}
            if phase == "physical" and trig:
                out["highlight"] = [e for e in (trig.get("entities") or [trig.get("entity")]) if e]
    if (d / "report.json").is_file():  # the verdict rendered from the report's view model
        from rocas.pipeline.codec import ShapeError
        from rocas.pipeline.report import Report, markdown

        try:
            report = Report.from_json(_read_json(d / "report.json"))
        except ShapeError as exc:
            raise InputError(f"{d / 'report.json'}: not a rocas report ({exc})") from None
        out["report"], out["verdict_md"] = report, markdown(report)
        if report.validation is not None and report.validation.variants:
            out["validation"] = report.validation
    elif (d / "report.md").is_file():
        out["verdict_md"] = (d / "report.md").read_text()
    if "accident" not in out:
        raise InputError(f"{d}: no accident.mcap", hint="is this a directory written by rocas analyze?")
    return out


def _diff_for(contents: dict[str, Any]) -> DiffResult | None:
    """Recompute the diff (its series are not in diff.json) with the run's settings."""
    from rocas.analysis.diff import diff

    if "reference" not in contents:
        return None
    d = contents.get("diff") or {}
    kw: dict[str, Any] = {}
    if d.get("delta_s") is not None:
        kw["delta_s"] = float(d["delta_s"])
    if d.get("bin_s") is not None:
        kw["bin_s"] = float(d["bin_s"])
    if d.get("control_channel"):
        kw["control_channel_topic"] = d["control_channel"]
    a, r = (x.path if isinstance(x, Execution) else x for x in (contents["accident"], contents["reference"]))
    return diff(a, r, **kw)


def log_run_dir(rec: Any, run_dir: str | os.PathLike[str]) -> dict[str, Any]:
    """Log whatever a run directory holds into an open recording stream; returns its contents."""
    c = run_dir_contents(run_dir)
    _log_contents(rec, c)
    return c


def _log_contents(rec: Any, c: dict[str, Any]) -> None:
    from rocas.viz.diff import log_diff
    from rocas.viz.search import log_search

    ids = c.get("highlight", [])
    for name in EXECUTIONS:
        if name in c:
            c[name] = log_execution(
                rec, name, c[name], highlight=ids if name in ("accident", "reference") else ()
            )
    result = c["diff_result"] if "diff_result" in c else _diff_for(c)
    if result is not None:
        log_diff(rec, result, "diff", timelines=("time", TIMELINE))
    elif c.get("diff"):
        _log_diff_json(rec, c["diff"])
    for phase, gens in c["searches"].items():
        log_search(rec, phase, gens, outcome=c.get("outcomes", {}).get(phase))
    log_validation(rec, c.get("validation"))
    if "verdict_md" in c:
        log_verdict(rec, c["verdict_md"])


def _log_diff_json(rec: Any, data: dict[str, Any]) -> None:
    """The diff JSON alone (no reference recording to recompute it): change points and verdict."""
    import rerun as rr

    events = sorted(
        (t, ch["topic"]) for ch in data.get("channels", []) for t in ch.get("change_points_s", [])
    )
    if events:
        rec.send_columns(
            "diff/events",
            indexes=[rr.TimeColumn(TIMELINE, duration=[e[0] for e in events])],
            columns=rr.TextLog.columns(text=[f"{tp}: MDR change point at {t:.2f} s" for t, tp in events]),
        )
    module = data.get("deviating_module")
    text = (
        f"# Differential analysis\n\n**Initial deviating module: `{module}`**\n\nWalk: "
        + " → ".join(f"`{n}`" for n in data.get("path", []))
        + "\n"
        if module
        else "# Differential analysis\n\n**No deviating module found.**\n"
    )
    if data.get("fallback"):
        text += f"\nNote: {data['fallback']}.\n"
    entries = data.get("entries")
    if entries and entries["deviating_module"] != module:
        from rocas.analysis.entries import entries_text

        text += f"\nNote: {entries_text(entries['channels'], entries['deviating_module'])}.\n"
    rec.log("diff/report", rr.TextDocument(text, media_type="text/markdown"), static=True)


def write_run_dir_rrd(path: str | os.PathLike[str], run_dir: str | os.PathLike[str]) -> dict[str, Any]:
    """Write the ``.rrd`` of a run directory with the default blueprint; returns its contents."""
    c = run_dir_contents(run_dir)
    names = [n for n in EXECUTIONS if n in c]
    for n in names:
        c[n] = load_execution(c[n])
    c["diff_result"] = _diff_for(c)
    bp = analysis_blueprint(
        names,
        diff="reference" in c or "diff" in c,
        diff_result=c["diff_result"],
        searches=[p for p, g in c["searches"].items() if g],
        verdict="verdict_md" in c,
        brake=any(_has_brake(c[n]) for n in names),
        focus=c["accident"],
        validation="validation" in c,
    )
    with rrd_recording(path, bp, kind="analysis") as rec:
        _log_contents(rec, c)
    return c


__all__ = [
    "analysis_blueprint",
    "log_execution",
    "log_run_dir",
    "log_validation",
    "log_verdict",
    "recording_blueprint",
    "run_dir_contents",
    "write_analysis_rrd",
    "write_recording_rrd",
    "write_run_dir_rrd",
]
