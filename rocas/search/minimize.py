"""Shrinking fixes: fewest parameters (delta-debugging style), then smallest magnitudes.

Several fixes shrink in lockstep: every round of every fix goes into one batch, so a round
costs one batch of simulations however many fixes and variables take part (a batch grows
slowly with its size: ``tests/benchmarks/bench_sim.py`` printed 0.77 s for 1 run of a 30 s
scenario, 0.92 s for 8 and 1.75 s for 64 on 2026-11-21, docs/benchmarks.md). The predicate
is ``holds([(i, mutation), ...]) -> [bool]``, where ``i`` says which fix a trial belongs to
(fixes may be accepted under different limits); the result depends only on ``holds``, not on
how a batch is run.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from rocas.search.space import Mutation, MutationSpace, Value

BatchPredicate = Callable[[list[Mutation]], list[bool]]
IndexedPredicate = Callable[[list[tuple[int, Mutation]]], list[bool]]


def shrink_sets(mutations: Sequence[Mutation], holds: IndexedPredicate
                ) -> tuple[list[Mutation], int]:
    """Drop variables one at a time from each fix while it still holds.

    Each round tries every single-variable removal of every fix still shrinking, in one
    batch, and keeps for each fix the first removal (in name order) that holds, until none
    can be removed: each result is 1-minimal.

    Returns:
        (the shrunk mutations in the given order, the number of evaluations it took).
    """
    current = list(mutations)
    active = [i for i, m in enumerate(current) if len(m.values) > 1]
    evaluations = 0
    while active:
        trials = [(i, current[i].without(n)) for i in active for n in current[i].names]
        ok = holds(trials)
        evaluations += len(trials)
        still = []
        for i in active:
            kept = next((m for (j, m), good in zip(trials, ok, strict=True) if j == i and good),
                        None)
            if kept is not None:
                current[i] = kept
                if len(kept.values) > 1:
                    still.append(i)
        active = still
    return current, evaluations


def _grid(lo: float, hi: float, points: int, integer: bool) -> list[Value]:
    """``points`` values strictly between lo and hi, ordered from lo towards hi."""
    grid = [lo + (hi - lo) * j / (points + 1) for j in range(1, points + 1)]
    if not integer:
        return grid
    out: list[Value] = []
    for g in grid:
        r = round(g)
        if r not in (lo, hi) and r not in out:
            out.append(r)
    return out


def shrink_all_magnitudes(
    mutations: Sequence[Mutation], space: MutationSpace, holds: IndexedPredicate,
    points: int = 7, rounds: int = 2, contiguous: bool = False,
    on_round: Callable[[list[Mutation]], None] | None = None,
) -> tuple[list[Mutation], int]:
    """Move each real or integer change of each fix towards its original value while it holds.

    Per variable the interval between the original value (which fails, or the variable would
    have been dropped) and the current value is searched on ``points`` evenly spaced values
    per round: the one nearest the original that holds becomes the value, its lower neighbour
    the new failing end. ``rounds`` rounds narrow the interval to 1/(points + 1)**rounds (7
    points, 2 rounds: 1/64, the resolution of six bisection steps in two batches instead of
    six). All variables of all fixes go into one batch per round; a variable's trials keep the
    fix's other values as they were at the start of the round.

    With ``contiguous`` a value is taken only when every grid value between it and the
    current one holds as well: the change shrinks along the interval it holds on and stops at
    the first value that fails, instead of jumping over failing values to an isolated one
    nearer the original (an accident-free pocket between accidents, a race won by a hair).
    ``on_round`` is called with the mutations after each round that changed any.

    Returns:
        (the shrunk mutations in the given order, the number of evaluations it took).
    """
    current = list(mutations)
    lo: dict[tuple[int, str], float] = {}
    for i, m in enumerate(current):
        for n in m.names:
            var = space.variable(n)
            if var.kind in ("real", "int"):
                lo[(i, n)] = float(var.original)  # type: ignore[arg-type]
    evaluations = 0
    for _ in range(rounds):
        groups: list[tuple[int, str, list[Value]]] = []
        trials: list[tuple[int, Mutation]] = []
        for (i, n), low in lo.items():
            grid = _grid(low, float(current[i].values[n]), points,  # type: ignore[arg-type]
                         space.variable(n).kind == "int")
            if grid:
                groups.append((i, n, grid))
                trials += [(i, current[i].with_value(n, g)) for g in grid]
        if not trials:
            break
        ok = iter(holds(trials))
        evaluations += len(trials)
        updates: dict[int, dict[str, Value]] = {}
        for i, n, grid in groups:
            good = [next(ok) for _ in grid]
            if contiguous:
                first = next((k for k in range(len(good)) if all(good[k:])), None)
            else:
                first = next((k for k, g in enumerate(good) if g), None)
            if first is None:
                lo[(i, n)] = float(grid[-1])
            else:
                updates.setdefault(i, {})[n] = grid[first]
                if first:
                    lo[(i, n)] = float(grid[first - 1])
        for i, values in updates.items():
            current[i] = Mutation({**current[i].values, **values})
        if updates and on_round is not None:
            on_round(list(current))
    return current, evaluations


def shrink_set(mutation: Mutation, holds: BatchPredicate) -> tuple[Mutation, int]:
    """:func:`shrink_sets` for one fix."""
    out, n = shrink_sets([mutation], lambda trials: holds([m for _, m in trials]))
    return out[0], n


def shrink_magnitudes(mutation: Mutation, space: MutationSpace, holds: BatchPredicate,
                      points: int = 7, rounds: int = 2, contiguous: bool = False,
                      on_round: Callable[[Mutation], None] | None = None
                      ) -> tuple[Mutation, int]:
    """:func:`shrink_all_magnitudes` for one fix."""
    out, n = shrink_all_magnitudes([mutation], space,
                                   lambda trials: holds([m for _, m in trials]), points, rounds,
                                   contiguous, None if on_round is None else lambda ms: on_round(ms[0]))
    return out[0], n
