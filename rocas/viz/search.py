"""Progress of a mutation search on the ``generation`` timeline.

Entities, under ``search/<phase>`` (phase: ``physical`` or ``cyber``):

- ``objectives/<name>``: every member's objective value per generation (points).
- ``best/<name>``: the best value among feasible candidates so far (line; from the first
  generation with a feasible candidate).
- ``feasible``, ``evaluations``, ``best_constraint``: counts and the smallest constraint value
  per generation (``<= 0`` means the accident is avoided).
- ``population``: the population in objective space (first two objectives), green when
  feasible, red otherwise.
- ``best_candidate``: a text log line per generation naming the best candidate so far.
- ``summary``: a static markdown table of the generations (readable on any timeline).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rocas.search.ga import GenerationStats

TIMELINE = "generation"
FEASIBLE_RGB = (40, 170, 80)
INFEASIBLE_RGB = (220, 50, 47)


def generations_from_json(items: Sequence[dict[str, Any]]) -> list[GenerationStats]:
    """``GenerationStats`` from their JSON form (``physical.json``/``cyber.json`` ``generations``)."""
    out = []
    for d in items:
        obj = np.asarray(d.get("objectives", []), dtype=np.float64)
        if obj.ndim == 1:
            obj = obj.reshape(len(obj), -1) if obj.size else np.zeros((0, 0))
        out.append(
            GenerationStats(
                int(d["generation"]),
                int(d.get("evaluations", 0)),
                int(d.get("feasible", 0)),
                float(d.get("best_constraint", np.nan)),
                obj,
                np.asarray(d.get("constraints", []), dtype=np.float64),
            )
        )
    return out


#: the paper's names of each search's objectives: f for the physical mutation (section 5.1),
#: h for the cyber mutation (section 5.3); other phases get f1, f2, ...
OBJECTIVE_NAMES: dict[str, tuple[str, ...]] = {"physical": ("f1", "f2", "f3"), "cyber": ("h1", "h2")}


def log_search(
    rec: Any,
    phase: str,
    generations: list[GenerationStats],
    best_labels: list[str] | None = None,
    *,
    objective_names: Sequence[str] | None = None,
) -> None:
    """Log one search's progress under ``search/<phase>`` on the ``generation`` timeline.

    Args:
        rec: an open ``rerun.RecordingStream``.
        phase: ``"physical"`` or ``"cyber"`` (any name works).
        generations: per-generation statistics in order.
        best_labels: a description of the best candidate so far, one per generation.
        objective_names: names of the objectives (default: :data:`OBJECTIVE_NAMES` of the
            phase, else ``f1``, ``f2``, ...).
    """
    import rerun as rr

    if not generations:
        return
    base = f"search/{phase}"
    gens = np.array([g.generation for g in generations], dtype=np.int64)

    def index(values: Any) -> list[Any]:
        return [rr.TimeColumn(TIMELINE, sequence=values)]

    n_obj = max((g.objectives.shape[1] for g in generations if g.objectives.ndim == 2), default=0)
    names = list(objective_names or OBJECTIVE_NAMES.get(phase, ()))[:n_obj]
    names += [f"f{j + 1}" for j in range(len(names), n_obj)]
    best_so_far = np.full(n_obj, np.inf)
    best_rows: list[np.ndarray] = []
    for g in generations:
        obj = g.objectives if g.objectives.ndim == 2 else np.zeros((0, n_obj))
        feas = np.asarray(g.constraints) <= 0 if len(g.constraints) == len(obj) else np.zeros(len(obj), bool)
        if feas.any():
            best_so_far = np.minimum(best_so_far, np.nanmin(np.where(feas[:, None], obj, np.inf), axis=0))
        best_rows.append(best_so_far.copy())
    best = np.array(best_rows).reshape(len(generations), n_obj)
    for j, name in enumerate(names):
        counts, values = [], []
        for g in generations:
            col = g.objectives[:, j] if g.objectives.ndim == 2 and g.objectives.shape[1] > j else np.zeros(0)
            col = col[np.isfinite(col)]
            counts.append(len(col))
            values.append(col)
        if sum(counts):
            rec.send_columns(
                f"{base}/objectives/{name}",
                indexes=index(gens),
                columns=rr.Scalars.columns(scalars=np.concatenate(values)).partition(counts),
            )
            rec.log(
                f"{base}/objectives/{name}",
                rr.SeriesPoints(names=f"{phase} {name} (population)", marker_sizes=3.0),
                static=True,
            )
        ok = np.isfinite(best[:, j])
        if ok.any():
            rec.send_columns(
                f"{base}/best/{name}",
                indexes=index(gens[ok]),
                columns=rr.Scalars.columns(scalars=best[ok, j]),
            )
            rec.log(
                f"{base}/best/{name}",
                rr.SeriesLines(names=f"{phase} best feasible {name}", widths=2.5),
                static=True,
            )
    for entity, values, color in (
        ("feasible", [g.feasible for g in generations], FEASIBLE_RGB),
        ("evaluations", [g.evaluations for g in generations], (90, 90, 200)),
        ("best_constraint", [g.best_constraint for g in generations], INFEASIBLE_RGB),
    ):
        arr = np.asarray(values, dtype=np.float64)
        ok = np.isfinite(arr)
        if ok.any():
            rec.send_columns(
                f"{base}/{entity}", indexes=index(gens[ok]), columns=rr.Scalars.columns(scalars=arr[ok])
            )
            rec.log(
                f"{base}/{entity}",
                rr.SeriesLines(names=f"{phase} {entity.replace('_', ' ')}", colors=[color]),
                static=True,
            )
    if n_obj >= 2:
        pos, col, counts = [], [], []
        for g in generations:
            obj = g.objectives[:, :2]
            ok = np.isfinite(obj).all(axis=1)
            feas = (
                (np.asarray(g.constraints) <= 0)
                if len(g.constraints) == len(obj)
                else np.zeros(len(obj), bool)
            )
            pos.append(obj[ok])
            col += [FEASIBLE_RGB if f else INFEASIBLE_RGB for f in feas[ok]]
            counts.append(int(ok.sum()))
        if sum(counts):
            rec.send_columns(
                f"{base}/population",
                indexes=index(gens),
                columns=rr.Points2D.columns(positions=np.concatenate(pos), colors=col).partition(counts),
            )
            rec.log(f"{base}/population", rr.Points2D.from_fields(radii=-4.0), static=True)
    if best_labels:
        k = min(len(best_labels), len(gens))
        rec.send_columns(
            f"{base}/best_candidate",
            indexes=index(gens[:k]),
            columns=rr.TextLog.columns(text=[str(s) for s in best_labels[:k]]),
        )
    rec.log(
        f"{base}/summary",
        rr.TextDocument(summary_markdown(phase, generations, names, best_labels), media_type="text/markdown"),
        static=True,
    )


def summary_markdown(
    phase: str, generations: list[GenerationStats], names: Sequence[str], best_labels: list[str] | None = None
) -> str:
    """A markdown table of the search's generations."""
    head = ["gen", "evaluations", "feasible", "best constraint", *[f"min {n}" for n in names]]
    if best_labels:
        head.append("best so far")
    lines = [f"# {phase.capitalize()} search", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for i, g in enumerate(generations):
        mins = []
        for j in range(len(names)):
            col = g.objectives[:, j] if g.objectives.ndim == 2 and g.objectives.shape[1] > j else np.zeros(0)
            col = col[np.isfinite(col)]
            mins.append(f"{col.min():.3g}" if len(col) else "—")
        row = [str(g.generation), str(g.evaluations), str(g.feasible), f"{g.best_constraint:.3g}", *mins]
        if best_labels:
            row.append(best_labels[i] if i < len(best_labels) else "")
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"


__all__ = ["generations_from_json", "log_search", "summary_markdown"]
