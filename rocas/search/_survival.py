"""NSGA-II's survival with a tie-break that is the same on every CPU (imports pymoo).

pymoo's rank-and-crowding survival orders the split front with ``np.argsort(kind="quicksort")``,
which numpy runs through a SIMD sort on AVX-512 machines and a scalar one elsewhere; the two put
equal crowding distances (every boundary point has an infinite one) in different orders, so the
same seed kept other survivors on another machine. Here the front is shuffled with the
algorithm's random state, as pymoo does, and then sorted *stably*: ties keep their shuffled
order on every machine.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pymoo.operators.survival.rank_and_crowding import RankAndCrowding

#: genomes are rounded to this grid when they are drawn (see :func:`quantize`)
GENOME_GRID = 1e-9


class StableRankAndCrowding(RankAndCrowding):
    """:class:`RankAndCrowding` with a machine-independent order of equal crowding distances."""

    def _do(self, problem: Any, pop: Any, *args: Any, random_state: Any = None,
            n_survive: int | None = None, **kwargs: Any) -> Any:
        objectives = pop.get("F").astype(float, copy=False)
        survivors: list[int] = []
        for rank, front in enumerate(self.nds.do(objectives, n_stop_if_ranked=n_survive)):
            excess = len(survivors) + len(front) - n_survive
            crowding = self.crowding_func.do(objectives[front, :], n_remove=max(excess, 0))
            keep = np.arange(len(front))
            if excess > 0:
                shuffled = random_state.permutation(len(front))
                by_crowding = shuffled[np.argsort(-crowding[shuffled], kind="stable")]
                keep = by_crowding[: len(front) - excess]
            for j, i in enumerate(front):
                pop[i].set("rank", rank)
                pop[i].set("crowding", crowding[j])
            survivors.extend(front[keep])
        return pop[survivors]


def quantize(genomes: np.ndarray) -> np.ndarray:
    """Genomes (P, G) rounded to :data:`GENOME_GRID`.

    pymoo's SBX crossover and polynomial mutation call ``np.power``, whose last bit depends on
    the CPU's SIMD path. Rounding every drawn genome to a 1e-9 grid (a real variable's value to
    a billionth of its range) removes that difference unless a value falls within an ulp of a
    grid boundary (about one gene in 10^7), so the same seed searches the same genomes on
    every machine.
    """
    return np.rint(genomes / GENOME_GRID) * GENOME_GRID
