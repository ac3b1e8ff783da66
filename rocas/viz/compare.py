"""The Rerun view of two analyses compared (``rocas compare --rrd``).

Three panels: on top the comparison (every field of the answer and every setting, the ones
that differ first, then the seconds and simulations per phase); below it each analysis's own
verdict document, side by side, A on the left. Every name from the run directories is escaped
for Markdown (:func:`rocas._text.markdown_text`).
"""

from __future__ import annotations

import os
from typing import Any

from rocas._text import markdown_text
from rocas.pipeline.compare import Comparison
from rocas.viz.stream import rrd_recording

SUMMARY_ENTITY = "compare/summary"
REPORT_ENTITIES = ("compare/a", "compare/b")


def compare_blueprint(comparison: Comparison) -> Any:
    """The layout: the comparison above, the two verdicts side by side below."""
    import rerun.blueprint as rrb

    name_a, name_b = (markdown_text(p.name or str(p)) for p in (comparison.run_a, comparison.run_b))
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.TextDocumentView(origin=SUMMARY_ENTITY, name="What differs"),
            rrb.Horizontal(
                rrb.TextDocumentView(origin=REPORT_ENTITIES[0], name=f"A: {name_a}"),
                rrb.TextDocumentView(origin=REPORT_ENTITIES[1], name=f"B: {name_b}"),
            ),
            row_shares=[1, 1],
        ),
        collapse_panels=True,
    )


def _seconds(v: float | None) -> str:
    return "" if v is None else f"{v:.1f}"


def _count(v: int | None) -> str:
    return "" if v is None else str(v)


def summary_markdown(comparison: Comparison) -> str:
    """The comparison as one Markdown document: the fields, then the costs."""
    md = markdown_text
    differing = comparison.differing
    head = ("**Same answer**" if comparison.same_answer else "**Different answers**") + (
        f": {len(differing)} of {len(comparison.fields)} fields differ" if differing
        else ": every field agrees")
    lines = [f"# A: {md(comparison.run_a)} · B: {md(comparison.run_b)}", "", head, "",
             "| field | A | B | |", "|---|---|---|---|"]
    for f in sorted(comparison.fields, key=lambda f: f.same):
        lines.append(f"| {md(f.name)} | {md(f.a)} | {md(f.b)} | {'' if f.same else 'differs'} |")
    lines += ["", "| phase | seconds A | seconds B | simulations A | simulations B |",
              "|---|---|---|---|---|"]
    for c in comparison.costs:
        lines.append(f"| {md(c.phase)} | {_seconds(c.seconds_a)} | {_seconds(c.seconds_b)} | "
                     f"{_count(c.simulations_a)} | {_count(c.simulations_b)} |")
    return "\n".join(lines) + "\n"


def _report_markdown(report: dict[str, Any]) -> str:
    from rocas.pipeline.report import markdown

    try:
        return markdown(report)
    except (KeyError, TypeError, ValueError, AttributeError):  # a report of an older rocas
        return f"# rocas analyze: {markdown_text(report.get('verdict', '?'))}\n"


def write_compare_rrd(path: str | os.PathLike[str], comparison: Comparison,
                      reports: tuple[dict[str, Any], dict[str, Any]]) -> None:
    """Write the ``.rrd`` of a comparison (atomically), ``reports`` being A's and B's."""
    import rerun as rr

    with rrd_recording(path, compare_blueprint(comparison), kind="compare") as rec:
        rec.log(SUMMARY_ENTITY, rr.TextDocument(summary_markdown(comparison),
                                                media_type="text/markdown"), static=True)
        for entity, report in zip(REPORT_ENTITIES, reports, strict=True):
            rec.log(entity, rr.TextDocument(_report_markdown(report), media_type="text/markdown"),
                    static=True)
