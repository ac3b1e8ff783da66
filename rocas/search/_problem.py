"""The pymoo problem behind :func:`rocas.search.ga.run_search` (imports pymoo)."""

from __future__ import annotations

from typing import Any

import numpy as np
from pymoo.core.problem import Problem


class SearchProblem(Problem):
    """Genomes in [0, 1]^n; objectives and the constraint are computed outside, batch-wise,
    and handed over in ``pending`` just before pymoo's evaluator asks for them."""

    def __init__(self, n_var: int, n_obj: int) -> None:
        super().__init__(n_var=n_var, n_obj=n_obj, n_ieq_constr=1, xl=0.0, xu=1.0)
        self.pending: tuple[np.ndarray, np.ndarray] | None = None

    def _evaluate(self, x: np.ndarray, out: dict[str, Any], *args: Any, **kw: Any) -> None:
        assert self.pending is not None and len(self.pending[0]) == len(x)
        out["F"], out["G"] = self.pending

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["pending"] = None
        return state
