"""Pairing and scoring one channel's messages bin by bin (the inner step of
:mod:`rocas.analysis.series`, whose docstring describes the whole pass).

A bin's messages of one channel pair across the two runs (:func:`_match`: the same payload
first, then the nearest in time within reach), each pair scores its MDR, and what is left may
pair with the other run's leftovers in the next bin. :class:`ChannelBins` keeps a channel's
scored bins; once both files are read, :meth:`ChannelBins.finish` decides for each message
left without a partner whether the other run was silent around it (it scores 1) or only
missed it (it is set aside).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rocas.analysis.mdr import Tolerance, mdr, repeated_lengths
from rocas.analysis.noise import FieldRules, masked_mdr
from rocas.recording.reader import ChannelInfo

ACCIDENT, REFERENCE = 0, 1


#: A message in a bin: (log time [ns], arrival, channel, payload, decoder, message). A message
#: read without decoding it carries its decoder and :data:`UNDECODED`; a decoded one carries
#: ``None`` and its message.
Entry = tuple[int, int, ChannelInfo, bytes, Callable[[bytes], Any] | None, Any]
UNDECODED = object()


class Undecodable(Exception):
    """A payload read without decoding it does not decode: the pass must be read decoded."""


def _message(e: Entry) -> Any:
    """The decoded message of an entry (decoding it now if it was read undecoded)."""
    decode = e[4]
    if decode is None:
        return e[5]
    try:
        return decode(e[3])
    except Exception as exc:  # a foreign file can hold anything
        raise Undecodable from exc


def _decoded(e: Entry) -> Entry:
    return e if e[4] is None else (e[0], e[1], e[2], e[3], None, _message(e))


def _entered(before: tuple[Entry, Entry], now: tuple[Entry, Entry]) -> bool:
    """Whether the content of a channel grew the same way in both runs from ``before`` (the
    first messages of a bin whose messages were equal) to ``now`` (this bin's first messages,
    which differ): equal repeated-field lengths in the two runs at each bin, and from one bin
    to the next no length shrinks and at least one grows."""
    la0 = repeated_lengths(_message(before[0]))
    # equal payloads are one message (decoded once)
    lb0 = la0 if before[0][3] == before[1][3] else repeated_lengths(_message(before[1]))
    la1, lb1 = (repeated_lengths(_message(e)) for e in now)
    if la0 != lb0 or la1 != lb1 or len(la0) != len(la1):
        return False
    return all(x >= y for x, y in zip(la1, la0, strict=True)) and la1 != la0


def _score(a: Entry, b: Entry, tol: Tolerance | FieldRules) -> float:
    """MDR of two messages of one channel; equal payloads (one schema) are equal trees.
    ``tol``: a tolerance for every float leaf, or the channel's learned rules.

    Equal payloads are not compared; read undecoded, one of them is decoded (both when their
    decoders differ) only to learn that it decodes, as a decoded pass would have.
    """
    pa = a[3]
    if pa and pa == b[3]:
        if a[4] is not None:
            _message(a)
            if b[4] is not None and b[4] is not a[4]:
                _message(b)
        elif b[4] is not None:
            _message(b)
        return 0.0
    if isinstance(tol, FieldRules):
        return masked_mdr(_message(a), _message(b), tol)
    return mdr(_message(a), _message(b), tol)


@dataclass
class _Pending:
    """A bin whose score waits for the next bin (which may take its leftovers)."""

    index: int
    scores: list[float]
    leftover: list[tuple[int, Entry]]  # (side, entry), in log-time order
    counts: tuple[int, int]
    entered: bool = False
    first_diff: float = math.inf  # earliest log time of a differing pair [ns, aligned]


def _match(xs: list[Entry], ys: list[Entry], reach_ns: float
           ) -> tuple[list[tuple[Entry, Entry]], list[Entry], list[Entry]]:
    """Pair one bin's messages of a channel (each list in log-time order).

    Two lists of one length whose payloads are equal pair by pair pair in order (every bin
    of two runs that agree). Otherwise the same message in both (equal payloads) pairs first,
    then each message left with the nearest in time left in the other list, in order, if it
    lies within ``reach_ns`` (a message jittered across a bin edge, or whose partner is in
    the next bin, is not paired with another message). Returns (the pairs, in the accident's
    order, the accident's and the reference's messages left over).
    """
    n = len(xs)
    if n == len(ys) and all(x[3] == y[3] for x, y in zip(xs, ys, strict=True)):
        return list(zip(xs, ys, strict=True)), [], []
    match: list[int | None] = [None] * n
    used = [False] * len(ys)
    by_payload: dict[bytes, list[int]] = {}
    for j, y in enumerate(ys):
        if y[3]:
            by_payload.setdefault(y[3], []).append(j)
    for i, x in enumerate(xs):  # the same message in both runs
        js = by_payload.get(x[3])
        while js:
            j = js.pop(0)
            if not used[j]:
                match[i], used[j] = j, True
                break
    for i, x in enumerate(xs):  # the rest: the nearest in time still free, within reach
        if match[i] is None:
            best = min((j for j in range(len(ys)) if not used[j]),
                       key=lambda j: (abs(ys[j][0] - x[0]), j), default=None)
            if best is not None and abs(ys[best][0] - x[0]) <= reach_ns:
                match[i], used[best] = best, True
    pairs = [(x, ys[j]) for x, j in zip(xs, match, strict=True) if j is not None]
    return (pairs, [x for x, j in zip(xs, match, strict=True) if j is None],
            [y for j, y in enumerate(ys) if not used[j]])


@dataclass
class ChannelBins:
    """One channel's bins as the pass scores them. An unpaired message is not scored here:
    :meth:`finish` decides, once both files are read, whether the other run was silent on
    the channel around it (it then scores 1) or only missed it (lost, or another rate)."""

    reach_ns: float = 0.05e9  # how far apart in time two differing messages may pair [ns]
    bins: list[int] = field(default_factory=list)
    sums: list[float] = field(default_factory=list)
    paired: list[int] = field(default_factory=list)
    unpaired: list[list[tuple[int, int]]] = field(default_factory=list)  # (aligned t, side)
    counts: list[tuple[int, int]] = field(default_factory=list)
    entered: list[bool] = field(default_factory=list)
    first_diff: list[float] = field(default_factory=list)
    #: the largest gap in log time between two runs' copies of one message [ns]
    same_gap: int = 0
    pending: _Pending | None = None
    #: the first messages of the last bin, when its messages were equal pair by pair
    equal_before: tuple[Entry, Entry] | None = None

    def finish_pending(self) -> None:
        p = self.pending
        if p is None:
            return
        if p.scores or p.leftover:
            self.bins.append(p.index)
            self.sums.append(sum(p.scores))
            self.paired.append(len(p.scores))
            self.unpaired.append([(e[0], side) for side, e in p.leftover])
            self.counts.append(p.counts)
            self.entered.append(p.entered)
            self.first_diff.append(p.first_diff)
        self.pending = None

    def add_bin(
        self, index: int, a_msgs: list[Entry], b_msgs: list[Entry], tol: Any,
        adjacent: bool
    ) -> None:
        """Score bin ``index`` (bins arrive in increasing order)."""
        counts = (len(a_msgs), len(b_msgs))
        pairs, left_a, left_b = _match(a_msgs, b_msgs, self.reach_ns)
        if self.equal_before is not None and pairs and pairs[0][0][3] != pairs[0][1][3]:
            # decoded once here: their score and whether content entered both read them
            pairs[0] = (_decoded(pairs[0][0]), _decoded(pairs[0][1]))
        scores = [_score(x, y, tol) for x, y in pairs]
        for x, y in pairs:
            if x[0] != y[0] and x[3] == y[3]:
                self.same_gap = max(self.same_gap, abs(x[0] - y[0]))
        # decoded now: an unpaired message counts only if it decodes, and may pair next bin
        leftover = sorted([(ACCIDENT, _decoded(e)) for e in left_a]
                          + [(REFERENCE, _decoded(e)) for e in left_b], key=lambda se: se[1][0])
        equal = bool(pairs) and counts[0] == counts[1] and not any(scores)
        entered = (self.equal_before is not None and bool(pairs) and counts[0] == counts[1]
                   and not equal and _entered(self.equal_before, pairs[0]))
        self.equal_before = pairs[0] if equal else None
        p = self.pending
        if adjacent and p is not None and p.index == index - 1 and p.leftover and leftover:
            # a message left in the last bin pairs with the other run's nearest message left
            # in this one, within reach (one jittered across the edge between them)
            taken: set[int] = set()
            kept: list[tuple[int, Entry]] = []
            for side, x in p.leftover:
                best = min((k for k, (s2, y) in enumerate(leftover)
                            if s2 != side and k not in taken),
                           key=lambda k: (abs(leftover[k][1][0] - x[0]), k), default=None)
                if best is not None and abs(leftover[best][1][0] - x[0]) <= self.reach_ns:
                    taken.add(best)
                    y = leftover[best][1]
                    a, b = (x, y) if side == ACCIDENT else (y, x)
                    score = _score(a, b, tol)
                    p.scores.append(score)
                    if score:
                        p.first_diff = min(p.first_diff, x[0], y[0])
                else:
                    kept.append((side, x))
            p.leftover = kept
            leftover = [se for k, se in enumerate(leftover) if k not in taken]
        self.finish_pending()
        first_diff = min((min(x[0], y[0]) for (x, y), sc in zip(pairs, scores, strict=True)
                          if sc), default=math.inf)
        self.pending = _Pending(index, scores, leftover, counts, entered, first_diff)

    def finish(self, times: tuple[np.ndarray, np.ndarray], end_ns: float, bin_ns: float,
               origin: int) -> tuple[list[int], list[float], list[tuple[int, int]], list[bool],
                          tuple[int, int], tuple[int, int]]:
        """The channel's series once both files are read: each unpaired message scores 1
        where the other run was silent on the channel around it (:func:`_silent`), and is set
        aside otherwise (lost on the other side, stamped at another time, or the channel runs
        at another rate there), or when it lies past the end of the span both files cover
        (``end_ns``).

        Args:
            times: (accident, reference) sorted aligned log times of the channel [ns since
                ``origin``].
            end_ns: end of the compared span [ns since ``origin``].
            origin: t = 0 on the accident's clock [ns].

        Returns:
            (bins, values, counts, entered, the earliest differing message of each bin [s
            since ``origin``, inf without one], set aside per side, outside the span per side).
        """
        bins, values, counts, entered, firsts = [], [], [], [], []
        aside, outside = [0, 0], [0, 0]
        for b, total, n, loose, c, e, f in zip(self.bins, self.sums, self.paired, self.unpaired,
                                               self.counts, self.entered, self.first_diff,
                                               strict=True):
            scored = 0
            first = f - origin
            for t_abs, side in loose:
                t = t_abs - origin
                if t > end_ns + bin_ns / 2:
                    outside[side] += 1
                elif _silent(times[1 - side], times[side], t):
                    scored += 1
                    first = min(first, t)
                else:
                    aside[side] += 1
            if n + scored == 0:
                continue
            bins.append(b)
            values.append((total + scored) / (n + scored))
            counts.append(c)
            entered.append(e)
            firsts.append(first / 1e9)
        return (bins, values, counts, entered, firsts, (aside[0], aside[1]),
                (outside[0], outside[1]))


#: Half-width of the window around an unpaired message in which the two runs' messages on its
#: channel are counted [s].
SILENT_WINDOW_S = 0.5
#: The other run was silent around an unpaired message when it wrote fewer than this fraction
#: of the messages this run wrote on the channel within :data:`SILENT_WINDOW_S` of it.
SILENT_RATE = 0.25


def _count(times: np.ndarray, lo: float, hi: float) -> int:
    return int(np.searchsorted(times, hi, side="right") - np.searchsorted(times, lo, side="left"))


def _silent(other: np.ndarray, mine: np.ndarray, t: int) -> bool:
    """Whether the other run was silent on a channel around an unpaired message of this one at
    ``t`` [ns]: within :data:`SILENT_WINDOW_S` of it, it wrote fewer than :data:`SILENT_RATE`
    times the messages this run wrote there. A lost message, a channel at half rate, one
    stamped when its buffer was flushed, or jitter leave the other run's count close to this
    one's; a module that stopped publishing, or a channel that only one run writes then,
    leave it near zero. ``other``, ``mine``: sorted aligned log times [ns]."""
    w = SILENT_WINDOW_S * 1e9
    return _count(other, t - w, t + w) < SILENT_RATE * _count(mine, t - w, t + w)
