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
- ``tried``: static (any timeline): one dot per simulation in the order the search ran them
  (x) at its constraint value (y; at or below the dashed line the accident is avoided), green
  when it avoided the accident, red otherwise, and a ring with a label where the search ended
  (``outcome``).
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
    outcome: str | None = None,
) -> None:
    """Log one search's progress under ``search/<phase>`` on the ``generation`` timeline.

    Args:
        rec: an open ``rerun.RecordingStream``.
        phase: ``"physical"`` or ``"cyber"`` (any name works).
        generations: per-generation statistics in order.
        best_labels: a description of the best candidate so far, one per generation.
        objective_names: names of the objectives (default: :data:`OBJECTIVE_NAMES` of the
            phase, else ``f1``, ``f2``, ...).
        outcome: where the search ended, in words (default: the last of ``best_labels``).
    """
    import rerun as rr

    if not generations:
        return
    base = f"search/{phase}"
    gens = np.array([g.generation for g in generations], dtype=np.int64)
    n_obj = max((g.objectives.shape[1] for g in generations if g.objectives.ndim == 2), default=0)
    names = list(objective_names or OBJECTIVE_NAMES.get(phase, ()))[:n_obj]
    names += [f"f{j + 1}" for j in range(len(names), n_obj)]
    _log_objectives(rec, base, phase, gens, generations, names)
    _log_counts(rec, base, phase, gens, generations)
    if n_obj >= 2:
        _log_population(rec, base, gens, generations)
    if best_labels:
        k = min(len(best_labels), len(gens))
        rec.send_columns(
            f"{base}/best_candidate",
            indexes=_index(gens[:k]),
            columns=rr.TextLog.columns(text=[str(s) for s in best_labels[:k]]),
        )
    log_tried(rec, base, generations, outcome or (best_labels[-1] if best_labels else None))
    rec.log(
        f"{base}/summary",
        rr.TextDocument(summary_markdown(phase, generations, names, best_labels), media_type="text/markdown"),
        static=True,
    )


def _index(values: Any) -> list[Any]:
    """The ``generation`` index of rows at ``values`` (generation numbers)."""
    import rerun as rr

    return [rr.TimeColumn(TIMELINE, sequence=values)]


def _feasible(g: GenerationStats, n: int) -> np.ndarray:
    """Which of the ``n`` members of ``g`` avoid the accident (all False without constraints)."""
    return np.asarray(g.constraints) <= 0 if len(g.constraints) == n else np.zeros(n, bool)


def _best_feasible(generations: list[GenerationStats], n_obj: int) -> np.ndarray:
    """(generations, n_obj): per objective, the smallest value of a feasible member so far
    (inf until a generation has one)."""
    best_so_far = np.full(n_obj, np.inf)
    best_rows: list[np.ndarray] = []
    for g in generations:
        obj = g.objectives if g.objectives.ndim == 2 else np.zeros((0, n_obj))
        feas = _feasible(g, len(obj))
        if feas.any():
            best_so_far = np.minimum(best_so_far, np.nanmin(np.where(feas[:, None], obj, np.inf), axis=0))
        best_rows.append(best_so_far.copy())
    return np.array(best_rows).reshape(len(generations), n_obj)


def _log_objectives(rec: Any, base: str, phase: str, gens: np.ndarray,
                    generations: list[GenerationStats], names: list[str]) -> None:
    """``objectives/<name>`` (every member's value) and ``best/<name>`` (best feasible so far)."""
    import rerun as rr

    best = _best_feasible(generations, len(names))
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
                indexes=_index(gens),
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
                indexes=_index(gens[ok]),
                columns=rr.Scalars.columns(scalars=best[ok, j]),
            )
            rec.log(
                f"{base}/best/{name}",
                rr.SeriesLines(names=f"{phase} best feasible {name}", widths=2.5),
                static=True,
            )


def _log_counts(rec: Any, base: str, phase: str, gens: np.ndarray,
                generations: list[GenerationStats]) -> None:
    """``feasible``, ``evaluations`` and ``best_constraint`` per generation."""
    import rerun as rr

    for entity, values, color in (
        ("feasible", [g.feasible for g in generations], FEASIBLE_RGB),
        ("evaluations", [g.evaluations for g in generations], (90, 90, 200)),
        ("best_constraint", [g.best_constraint for g in generations], INFEASIBLE_RGB),
    ):
        arr = np.asarray(values, dtype=np.float64)
        ok = np.isfinite(arr)
        if ok.any():
            rec.send_columns(
                f"{base}/{entity}", indexes=_index(gens[ok]), columns=rr.Scalars.columns(scalars=arr[ok])
            )
            rec.log(
                f"{base}/{entity}",
                rr.SeriesLines(names=f"{phase} {entity.replace('_', ' ')}", colors=[color]),
                static=True,
            )


def _log_population(rec: Any, base: str, gens: np.ndarray,
                    generations: list[GenerationStats]) -> None:
    """``population``: each generation in the plane of the first two objectives, coloured by
    feasibility."""
    import rerun as rr

    pos, col, counts = [], [], []
    for g in generations:
        obj = g.objectives[:, :2]
        ok = np.isfinite(obj).all(axis=1)
        feas = _feasible(g, len(obj))
        pos.append(obj[ok])
        col += [FEASIBLE_RGB if f else INFEASIBLE_RGB for f in feas[ok]]
        counts.append(int(ok.sum()))
    if sum(counts):
        rec.send_columns(
            f"{base}/population",
            indexes=_index(gens),
            columns=rr.Points2D.columns(positions=np.concatenate(pos), colors=col).partition(counts),
        )
        rec.log(f"{base}/population", rr.Points2D.from_fields(radii=-4.0), static=True)


#: Size of the ``tried`` plot [view units]: simulations across, constraint values up.
TRIED_W, TRIED_H = 160.0, 70.0


def log_tried(rec: Any, base: str, generations: list[GenerationStats], outcome: str | None) -> None:
    """Log ``<base>/tried``: every simulation of the search as a dot (see the module doc)."""
    import rerun as rr

    cons = [np.asarray(g.constraints, dtype=np.float64).reshape(-1) for g in generations]
    gen_of = np.concatenate([np.full(len(c), g.generation) for c, g in zip(cons, generations, strict=True)]
                            ) if cons else np.zeros(0)
    c = np.concatenate(cons) if cons else np.zeros(0)
    ok = np.isfinite(c)
    if not ok.any():
        return
    c, gen_of = c[ok], gen_of[ok]
    n = len(c)
    lo, hi = min(float(c.min()), 0.0), max(float(c.max()), 0.0)
    span = max(hi - lo, 1e-9)
    x = (np.arange(n) + 0.5) / n * TRIED_W
    y = -(c - lo) / span * TRIED_H  # y grows downwards in a 2D view: larger constraint higher up
    y0 = -(0.0 - lo) / span * TRIED_H
    feasible = c <= 0
    colors = [FEASIBLE_RGB if f else INFEASIBLE_RGB for f in feasible]
    labels = [f"simulation {i + 1} (generation {int(gi)}): constraint {ci:.3g}, "
              f"{'avoids' if f else 'keeps'} the accident"
              for i, (gi, ci, f) in enumerate(zip(gen_of, c, feasible, strict=True))]
    rec.log(f"{base}/tried/runs", rr.Points2D(np.stack([x, y], axis=1), colors=colors, radii=1.2,
                                               labels=labels, show_labels=False), static=True)
    dash = [np.array([[a, y0], [min(a + 3.0, TRIED_W), y0]]) for a in np.arange(0.0, TRIED_W, 6.0)]
    rec.log(f"{base}/tried/avoided_below", rr.LineStrips2D(dash, colors=[(200, 200, 200)], radii=0.3),
            static=True)
    axes = np.array([[0.0, -TRIED_H - 6.0], [0.0, 4.0], [TRIED_W + 4.0, 4.0]])
    rec.log(f"{base}/tried/axes", rr.LineStrips2D([axes], colors=[(120, 120, 120)], radii=0.3), static=True)
    notes = [(TRIED_W / 2, 12.0, f"{n} simulations in the order run →"),
             (TRIED_W * 0.16, y0 + 7.0, "below: accident avoided"),
             (TRIED_W * 0.16, -TRIED_H - 6.0, f"{int(feasible.sum())} of {n} avoid it")]
    rec.log(f"{base}/tried/notes",
            rr.Points2D([[a, b] for a, b, _ in notes], radii=0.01, colors=[(220, 220, 220)],
                        labels=[t for *_, t in notes], show_labels=True), static=True)
    if outcome:
        rec.log(f"{base}/tried/ended",
                rr.Points2D([[TRIED_W * 0.72, -TRIED_H - 6.0]], radii=0.01, colors=[(255, 215, 0)],
                            labels=[f"ended: {outcome}"], show_labels=True), static=True)


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
