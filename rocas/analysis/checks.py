"""Checks on a diffed pair: whether the two recordings are two runs of the same thing
(:func:`check_pair`), and what the streamed pass left out of the comparison, as warning
lines (:func:`span_warnings`, :func:`account_warnings`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from rocas.analysis.align import Alignment, describe
from rocas.analysis.changepoints import ChangePointConfig
from rocas.analysis.changepoints import median as changepoint_median
from rocas.analysis.series import REPEAT_S
from rocas.errors import RecordingError

#: Bins at the start of each channel, with messages in both recordings, over which two runs
#: of the same thing must still agree (the paper's premise: a deviation comes later).
START_BINS = 10
#: Largest median, over shared channels, of the mean MDR in those bins for a pair diffed
#: without a warning. Two runs of one catalog scenario measure at most 0.07 (the demo pair 0),
#: two different catalog accidents 0.33 to 0.61; a stack whose headers carry wall-clock
#: stamps measures more (tests/foreign_stack.py: 0.38), so this alone only warns.
MAX_START_MDR = 0.2
#: Relative difference of the two spans above which a pair that already differs at the
#: start is refused as two different drives [fraction of the longer span].
MAX_SPAN_DIFFERENCE = 0.05


def check_pair(
    res: Any, accident: str, reference: str, cfg: ChangePointConfig, *,
    allow_unrelated: bool = False, intact: bool = True,
) -> tuple[str, ...]:
    """Check that two recordings are two runs of the same thing; returns warning lines.

    Refused (RecordingError): a recording whose messages all share one log time (no stretch
    of time to compare); a pair sharing fewer than half of their channels; a pair whose
    shared channels already differ at the start (the median, over shared channels, of the
    mean MDR in each channel's first :data:`START_BINS` bins with messages in both
    recordings is over :data:`MAX_START_MDR`: runs of one scenario agree there, aligned at
    their first messages) *and* whose spans differ by more than :data:`MAX_SPAN_DIFFERENCE`.
    ``allow_unrelated`` turns those two refusals into warnings. Warned: a pair that differs
    at the start with equal spans (wall-clock stamps in headers look like that too), a
    recording shorter than the change points' baseline window. (What one file covers beyond
    the other is not compared; :func:`span_warnings` says so.)

    Args:
        res: the pair's :class:`~rocas.analysis.series.SeriesResult`.
        intact: both recordings were read whole (a damaged one's span says nothing about the
            drive, so the spans then refuse nothing).
    """
    out: list[str] = []
    names = (accident, reference)
    for path, span, n in zip(names, res.span_s, res.messages_read, strict=True):
        if span <= 0:
            raise RecordingError(
                f"{path} holds {n} readable message{'s' if n != 1 else ''}, all at one log "
                "time: there is no run over time to compare",
                "diff recordings that cover the drive up to the accident",
            )
        if span < cfg.baseline_s:
            out.append(
                f"{path} covers only {span:.2f} s, less than the {cfg.baseline_s:g} s baseline "
                "the change points are judged against"
            )
    short, long_ = sorted(res.span_s)
    refuse: list[str] = []
    topics = res.channels
    shared = [t for t, (a, b) in topics.items() if a is not None and b is not None]
    if 2 * len(shared) < len(topics):
        refuse.append(f"they share only {len(shared)} of their {len(topics)} channels")
    start_mdr = []
    for t in shared:
        s = res.series[t]
        both = (s.messages[:, 0] > 0) & (s.messages[:, 1] > 0)
        if both.any():
            start_mdr.append(float(s.mdr[both][:START_BINS].mean()))
    median = changepoint_median(np.asarray(start_mdr)) if start_mdr else 0.0
    if median > MAX_START_MDR:
        differ = (f"at the start, where two runs of one scenario agree, their shared channels "
                  f"already differ (median MDR {median:.2f} over each channel's first "
                  f"{START_BINS} bins, more than {MAX_START_MDR:g})")
        if intact and long_ - short > MAX_SPAN_DIFFERENCE * long_:
            refuse.append(f"{differ}, and they cover {res.span_s[0]:.2f} s and "
                          f"{res.span_s[1]:.2f} s")
        else:
            out.append(f"{accident} and {reference} may not be two runs of the same thing: "
                       f"{differ}; if they are, the difference is sensor noise or wall-clock "
                       "stamps (--atol/--rtol loosen float fields)")
    if refuse:
        what = (f"{accident} and {reference} do not look like two runs of the same thing: "
                + "; ".join(refuse))
        if not allow_unrelated:
            raise RecordingError(
                what,
                "diff an accident against a run of the same scenario, or pass "
                "--allow-unrelated to diff these anyway",
            )
        out.append(what + " (diffed anyway: --allow-unrelated)")
    return tuple(out)


def span_warnings(res: Any, alignment: Alignment, accident: str, reference: str
                   ) -> tuple[str, ...]:
    """What lies outside the span both recordings cover (one line per file that has some)."""
    out = []
    lo, hi = res.compared_s
    half = res.bin_s / 2
    for side, (path, other) in enumerate(((accident, reference), (reference, accident))):
        start, end = alignment.starts_s[side], res.ends_s[side]
        parts = []
        if start < lo - half:
            parts.append(f"its first {lo - start:.2f} s")
        if end > hi + half:
            parts.append(f"its last {end - hi:.2f} s")
        if parts:
            out.append(f"{path}: {' and '.join(parts)} lie outside the span both recordings "
                       f"cover (compared {lo:.2f}-{hi:.2f} s, aligned as {describe(alignment)}); "
                       f"{other} has nothing there to compare with")
    return tuple(out)


def account_warnings(res: Any) -> tuple[str, ...]:
    """Messages set aside or left out, and channels that fall silent, one line per kind."""
    def listing(items: list[tuple[str, tuple[int, int]]]) -> str:
        shown = [f"{t} ({a} in the accident, {b} in the reference)" for t, (a, b) in items[:4]]
        more = f" and {len(items) - 4} more channels" if len(items) > 4 else ""
        return ", ".join(shown) + more

    accounts = sorted(res.accounts.items())
    out = []
    aside = [(t, a.aside) for t, a in accounts if any(a.aside)]
    if aside:
        n = sum(x + y for _, (x, y) in aside)
        out.append(f"{n} messages had no partner in the other recording while it published "
                   f"the channel close by (lost there, or another rate), and were set aside: "
                   f"{listing(aside)}")
    rep = [(t, a.repeated) for t, a in accounts if any(a.repeated)]
    if rep:
        n = sum(x + y for _, (x, y) in rep)
        out.append(f"{n} messages were logged twice (the same payload again within "
                   f"{REPEAT_S * 1000:g} ms) and counted once: {listing(rep)}")
    for t, a in accounts:
        for side, role, other in ((0, "accident", "reference"), (1, "reference", "accident")):
            stop = a.stops_s[side]
            if stop is not None:
                out.append(f"channel {t} falls silent at {stop:.2f} s in the {role} while the "
                           f"{other} goes on publishing it; its messages after that count as "
                           "differing (a module that stopped, or a log cut short)")
    return tuple(out)
