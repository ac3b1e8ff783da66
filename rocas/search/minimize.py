"""Shrinking a fix: fewest parameters (delta-debugging style), then smallest magnitudes.

Both steps take ``holds(mutations) -> [bool]`` over a *batch*, so every step's candidates
can run in parallel on an executor; the result depends only on ``holds``.
"""

from __future__ import annotations

from collections.abc import Callable

from rocas.search.space import Mutation, MutationSpace

BatchPredicate = Callable[[list[Mutation]], list[bool]]


def shrink_set(mutation: Mutation, holds: BatchPredicate) -> tuple[Mutation, int]:
    """Drop variables one at a time while the fix still holds.

    Each round tries every single-variable removal in one batch and keeps the first (in
    name order) that still holds, until none can be removed: a 1-minimal fix.

    Returns:
        (the shrunk mutation, the number of evaluations it took).
    """
    current = mutation
    evaluations = 0
    while len(current.values) > 1:
        trials = [current.without(n) for n in current.names]
        ok = holds(trials)
        evaluations += len(trials)
        for trial, good in zip(trials, ok, strict=True):
            if good:
                current = trial
                break
        else:
            break
    return current, evaluations


def shrink_magnitudes(
    mutation: Mutation, space: MutationSpace, holds: BatchPredicate, steps: int = 6
) -> tuple[Mutation, int]:
    """Move each real-valued change towards its original value while the fix holds.

    For every real variable, ``steps`` rounds of bisection between the original value
    (which fails, or the variable would have been dropped) and the current value; each
    round evaluates the midpoints of all variables in one batch and keeps those that hold.
    Integer variables are bisected the same way on their integer range.

    Returns:
        (the shrunk mutation, the number of evaluations it took).
    """
    current = mutation
    names = [n for n in current.names if space.variable(n).kind in ("real", "int")]
    lo = {n: space.variable(n).original for n in names}  # fails
    evaluations = 0
    for _ in range(steps):
        trials: list[tuple[str, Mutation]] = []
        for n in names:
            var = space.variable(n)
            mid = (float(lo[n]) + float(current.values[n])) / 2.0  # type: ignore[arg-type]
            if var.kind == "int":
                mid = round(mid)
                if mid in (lo[n], current.values[n]):
                    continue
            trials.append((n, current.with_value(n, mid)))
        if not trials:
            break
        ok = holds([m for _, m in trials])
        evaluations += len(trials)
        for (n, m), good in zip(trials, ok, strict=True):
            if good:
                current = current.with_value(n, m.values[n])
            else:
                lo[n] = m.values[n]
    return current, evaluations
