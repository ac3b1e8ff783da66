"""The regression test's sequential stop: phase V runs the original configuration on the
perturbed variants in looks of REGRESSION_LOOK and stops as soon as the minimal fix and the
original are separated with confidence.

The two configurations run on the same variants, so the comparison is paired: only the
variants where exactly one of them avoids the accident say anything about which is better
(McNemar's idea). Under "neither is better" each such discordant variant goes either way with
probability 1/2, so the count where only the fix avoids it is Binomial(discordant, 1/2), and
the exact one-sided tail is the p-value. The test looks after every REGRESSION_LOOK variants
and in each direction; with a Bonferroni split of REGRESSION_ALPHA over the looks and the two
directions, the chance of stopping with a wrong direction when neither is better is at most
REGRESSION_ALPHA over the whole sequence (group-sequential, no assumption on how the looks
depend on each other).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

#: variants per look of the regression test (a quarter of the default 200)
REGRESSION_LOOK = 50
#: the chance of stopping early in the wrong direction, over all looks and both directions
REGRESSION_ALPHA = 0.01


def looks(variants: int, look: int | None = None) -> list[int]:
    """How many variants the original has run at each look: every ``look`` (None:
    REGRESSION_LOOK) variants, the last at ``variants``."""
    look = REGRESSION_LOOK if look is None else look
    return list(range(look, variants, look)) + [variants] if variants else []


def sign_test(wins: int, losses: int) -> float:
    """One-sided exact p-value that ``wins`` of ``wins + losses`` discordant pairs go one way
    when each goes either way with probability 1/2: P(X >= wins), X ~ Binomial(n, 1/2)."""
    n = wins + losses
    if n == 0:
        return 1.0
    return sum(math.comb(n, k) for k in range(wins, n + 1)) / 2 ** n


def regression_test(original_ok: Sequence[bool], fixed_ok: Sequence[bool], variants: int,
                    look: int | None = None, alpha: float | None = None) -> dict[str, Any]:
    """The test after the original has run on the first ``len(original_ok)`` of ``variants``
    variants (``fixed_ok``: the minimal fix on the same variants and possibly more; each flag
    True when the run avoided the accident); ``look`` and ``alpha``: None for REGRESSION_LOOK
    and REGRESSION_ALPHA.

    Returns ``variants`` (how many were compared), ``fix_only`` and ``original_only`` (the
    discordant variants), ``p_value`` (the smaller one-sided p-value), ``alpha_per_look`` (the
    level each look and direction is held to), ``decision`` ("fix_better", "fix_worse" or None
    while not separated) and ``stopped_early`` (decided before the last look, so the original
    need not run on the rest)."""
    m = len(original_ok)
    alpha = REGRESSION_ALPHA if alpha is None else alpha
    schedule = looks(variants, look)
    per_look = alpha / (2 * max(1, len(schedule)))
    fix_only = sum(f and not o for o, f in zip(original_ok, fixed_ok[:m], strict=True))
    original_only = sum(o and not f for o, f in zip(original_ok, fixed_ok[:m], strict=True))
    p_better, p_worse = sign_test(fix_only, original_only), sign_test(original_only, fix_only)
    decision = ("fix_better" if p_better <= per_look else "fix_worse" if p_worse <= per_look
                else None)
    if m not in schedule:  # only the planned looks may stop (the level is split over them)
        decision = None
    return {"variants": m, "fix_only": fix_only, "original_only": original_only,
            "p_value": min(p_better, p_worse), "alpha_per_look": per_look, "decision": decision,
            "stopped_early": decision is not None and m < variants}
