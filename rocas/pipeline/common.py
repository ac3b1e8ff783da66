"""What the search phases share: generation and candidate records for the progress bars and
the run directory, and a score cache for shrinking."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from rocas.pipeline.results import CandidateRecord, GenerationRecord
from rocas.search.ga import Candidate, GenerationStats
from rocas.search.space import Mutation


def gen_info(s: GenerationStats, second: str) -> dict[str, Any]:
    """A generation for the progress bars and the run directory. ``best_feasible`` is the
    smallest second objective among its accident-free members, and ``best_objective`` names
    that objective (``second``): f2 (how unlike the original the world became) in the physical
    search, h2 (how large the fix) in the cyber one."""
    obj = np.asarray(s.objectives, dtype=float)
    feas = np.asarray(s.constraints) <= 0
    best = (float(np.min(obj[feas, 1])) if obj.ndim == 2 and obj.shape[1] > 1 and len(feas) == len(obj)
            and feas.any() else None)
    return {"generation": s.generation, "evaluations": s.evaluations, "feasible": s.feasible,
            "best_constraint": s.best_constraint, "best_feasible": best, "best_objective": second}


def gen_json(s: GenerationStats, second: str) -> GenerationRecord:
    """A generation as the run directory keeps it (:func:`gen_info` and every member's
    objectives and constraints)."""
    return GenerationRecord(**gen_info(s, second),
                            objectives=tuple(tuple(row) for row in s.objectives.tolist()),
                            constraints=tuple(s.constraints.tolist()))


def cand_json(c: Candidate) -> CandidateRecord:
    """A search candidate as the run directory keeps it."""
    return CandidateRecord(mutation=dict(c.mutation.values), objectives=tuple(c.objectives),
                           constraint=c.constraint, generation=c.generation)



class Scores:
    """(objectives, constraint) per mutation, each simulated once: seeded with what a search
    already scored, the rest run in one batch per call."""

    def __init__(self, batch: Callable[[list[Mutation]], list[tuple[tuple[float, ...], float]]],
                 known: list[Candidate]) -> None:
        self._batch = batch
        self._scores = {c.mutation: (c.objectives, c.constraint) for c in known}
        self.simulated = 0

    def of(self, ms: list[Mutation]) -> list[tuple[tuple[float, ...], float]]:
        todo = list(dict.fromkeys(m for m in ms if m not in self._scores))
        if todo:
            self._scores.update(zip(todo, self._batch(todo), strict=True))
            self.simulated += len(todo)
        return [self._scores[m] for m in ms]

