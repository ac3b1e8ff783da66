"""MDR series: two recordings streamed side by side, binned in time, channel by channel.

Both recordings are aligned at their first message (t = 0): the earliest log time, from the
file's summary statistics, or, when the file has no summary (a log still being written or cut
short), the earliest log time among the messages read in the first reorder window. Time is
cut into bins of ``bin_s`` seconds, centred on multiples of
``bin_s`` (bin j covers [(j - 1/2) bin_s, (j + 1/2) bin_s)): a periodic channel whose period
is a multiple of the bin width, published in phase with the first message (the common
case, e.g. 10 Hz with 0.1 s bins), then sits mid-bin, and timing jitter does not push its
messages across a bin edge in one recording only. Within a bin, the k-th message
of a channel in one recording, in log-time order (file order breaks ties), pairs with the k-th
message of that channel in the other, so two files that hold the same messages in a
different file order diff to zero; a message without a partner scores 1; the bin's MDR is
the mean over its messages. Bins in which neither recording has a message on the channel carry no value.

One refinement, on unless ``adjacent_pairing=False`` (``--strict-bins``): messages left
unpaired in bin j pair, in order, with the *other* recording's messages left unpaired in
bin j + 1 before anything scores 1. A message published within its jitter of a bin edge
lands on different sides of the edge in the two runs; without this, such a channel scores
1 in almost every bin and its real deviation is invisible. The pair's MDR counts in bin j.

Memory stays flat: only the bins within ``reorder_window_s`` of the slower stream's
position are held. MCAP does not require file order to follow log time, and a pipeline may
write one channel late (a buffered logger, a channel appended after the run). A message
that arrives for a bin already scored would be scored on its own, unpaired; instead the pass
stops and starts again with a window wide enough for it (at least twice as wide), so the
series never depend on file order. Files in log-time order, like every file rocas writes,
take one pass; ``SeriesResult.disorder_s`` says how far each file strays and
``reorder_window_s`` which window the result needed.
"""

from __future__ import annotations

import dataclasses
import json
import math
import operator
from array import array
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from google.protobuf import descriptor_pb2
from google.protobuf.message import DecodeError

from rocas.analysis.align import MAX_SPAN_S, Alignment, align, unflush
from rocas.analysis.mdr import EXACT, Tolerance, mdr, repeated_lengths
from rocas.analysis.noise import FieldRules, masked_mdr
from rocas.errors import RecordingError
from rocas.recording.model import ChannelInfo
from rocas.recording.reader import Recording

ACCIDENT, REFERENCE = 0, 1
#: A message whose payload equals the one before it on its channel, logged within this of it,
#: was logged twice [s].
REPEAT_S = 0.002


@dataclass(frozen=True)
class ChannelSeries:
    """The MDR series of one channel.

    Attributes:
        topic: channel topic.
        times_s: (n,) centre time of each bin that holds a message [s since alignment].
        mdr: (n,) MDR of each such bin, in [0, 1].
        messages: (n, 2) message counts per bin in (accident, reference).
        only_in: "accident" or "reference" when the channel exists in one recording only.
        first_differing_s: (n,) the log time of the earliest message of each bin that differs
            (a pair that scores, or an unpaired message that scores 1) [s since alignment],
            inf in a bin without one; None when not computed.
        entered: (n,) bool, True for a bin where the channel's content grew in both runs at
            once and the two began to differ: the previous bin's messages were equal, and
            from it to this one the first message of each run gained the same number of
            elements in its repeated fields (an obstacle came into view in both). None when
            not computed.
    """

    topic: str
    times_s: np.ndarray
    mdr: np.ndarray
    messages: np.ndarray
    only_in: str | None = None
    entered: np.ndarray | None = None
    first_differing_s: np.ndarray | None = None


#: A message in a bin: (log time [ns], arrival, channel, payload, decoder, message). A message
#: read without decoding it carries its decoder and :data:`_UNDECODED`; a decoded one carries
#: ``None`` and its message.
_Entry = tuple[int, int, ChannelInfo, bytes, Callable[[bytes], Any] | None, Any]
_UNDECODED = object()


class _Undecodable(Exception):
    """A payload read without decoding it does not decode: the pass must be read decoded."""


def _message(e: _Entry) -> Any:
    """The decoded message of an entry (decoding it now if it was read undecoded)."""
    decode = e[4]
    if decode is None:
        return e[5]
    try:
        return decode(e[3])
    except Exception as exc:  # a foreign file can hold anything
        raise _Undecodable from exc


def _decoded(e: _Entry) -> _Entry:
    return e if e[4] is None else (e[0], e[1], e[2], e[3], None, _message(e))


def _entered(before: tuple[_Entry, _Entry], now: tuple[_Entry, _Entry]) -> bool:
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


def _score(a: _Entry, b: _Entry, tol: Tolerance | FieldRules) -> float:
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
    leftover: list[tuple[int, _Entry]]  # (side, entry), in log-time order
    counts: tuple[int, int]
    entered: bool = False
    first_diff: float = math.inf  # earliest log time of a differing pair [ns, aligned]


def _match(xs: list[_Entry], ys: list[_Entry], reach_ns: float
           ) -> tuple[list[tuple[_Entry, _Entry]], list[_Entry], list[_Entry]]:
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
class _Acc:
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
    equal_before: tuple[_Entry, _Entry] | None = None

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
        self, index: int, a_msgs: list[_Entry], b_msgs: list[_Entry], tol: Any,
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
            kept: list[tuple[int, _Entry]] = []
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


@dataclass(frozen=True)
class ChannelAccount:
    """What became of one channel's messages besides the pairs scored.

    Attributes:
        aside: (accident, reference) messages without a partner that were set aside, the
            other run having messages on the channel close by (lost there, or another rate).
        repeated: (accident, reference) messages logged twice (the same payload again within
            a quarter bin), left out.
        outside: (accident, reference) messages outside the span both files cover.
        stops_s: (accident, reference) the channel's last message, when the other run goes on
            publishing it for longer than its silence rule allows before the span ends [s];
            None otherwise.
    """

    aside: tuple[int, int] = (0, 0)
    repeated: tuple[int, int] = (0, 0)
    outside: tuple[int, int] = (0, 0)
    stops_s: tuple[float | None, float | None] = (None, None)

    @property
    def clean(self) -> bool:
        return (not any(self.aside) and not any(self.repeated)
                and self.stops_s == (None, None))


@dataclass(frozen=True)
class SeriesResult:
    """All channels' series plus what was read.

    Attributes:
        series: topic -> ChannelSeries, sorted by topic.
        channels: topic -> (accident ChannelInfo | None, reference ChannelInfo | None).
        messages_read: (accident, reference) decoded message counts.
        bin_s: bin width [s].
        disorder_s: (accident, reference) the most any message's log time lies behind a
            message read before it in the same file [s]; 0 for a file in log-time order.
        reorder_window_s: the reorder window the result was computed with [s]: the one
            asked for, or a wider one when a file's disorder needed it.
        span_s: (accident, reference) last minus first log time of the messages read [s].
        warnings: what the pass found that the result depends on, one line each.
        compared_s: (start, end) of the span both files cover, on the accident's clock [s
            since t = 0]; the series hold nothing outside it.
        ends_s: (accident, reference) each file's last message [s since t = 0, aligned].
        accounts: topic -> what became of its messages besides the scored pairs (only
            channels with something to report).
        timing_s: how far apart in log time the two runs write one message: over the
            channels with a message in both, the median of each channel's largest gap between
            the two copies of a message [s]; 0 for two runs on one tick (every simulated pair).
    """

    series: dict[str, ChannelSeries]
    channels: dict[str, tuple[ChannelInfo | None, ChannelInfo | None]]
    messages_read: tuple[int, int]
    bin_s: float
    disorder_s: tuple[float, float] = (0.0, 0.0)
    reorder_window_s: float = 1.0
    span_s: tuple[float, float] = (0.0, 0.0)
    warnings: tuple[str, ...] = ()
    compared_s: tuple[float, float] = (0.0, 0.0)
    ends_s: tuple[float, float] = (0.0, 0.0)
    accounts: dict[str, ChannelAccount] = field(default_factory=dict)
    timing_s: float = 0.0


class _TooLate(Exception):
    """A message arrived for a bin already scored; ``window_s`` would have held it."""

    def __init__(self, window_s: float) -> None:
        super().__init__(window_s)
        self.window_s = window_s


def compute_series(
    accident: Recording,
    reference: Recording,
    *,
    bin_s: float = 0.1,
    tolerance: Tolerance = EXACT,
    reorder_window_s: float = 1.0,
    adjacent_pairing: bool = True,
    progress: Callable[[int, int], None] | None = None,
    alignment: Alignment | None = None,
    rules: dict[str, FieldRules] | None = None,
    resume: tuple[Iterator[Any] | None, Iterator[Any] | None] = (None, None),
) -> SeriesResult:
    """Stream both recordings and compute each channel's MDR series.

    ``reorder_window_s`` is how far behind in log time a message may arrive (file order)
    and still be paired in one pass; a file that strays further costs another pass with a
    window wide enough for it (module docstring). ``progress``, if given, is called now and
    then with (bytes read, bytes in both files) of the current pass. ``alignment`` puts the
    reference on the accident's clock (None: :func:`~rocas.analysis.align.align` with its
    defaults); ``rules``: topic -> how its messages are compared, instead of ``tolerance``;
    ``resume``: each recording's undecoded pass as alignment began it, for the first pass.

    Raises:
        RecordingError: a topic's schema differs between the two files, or a recording's log
            times span more than :data:`MAX_SPAN_S`.
    """
    if not (bin_s > 0 and math.isfinite(bin_s)):
        raise ValueError("bin_s must be a positive number of seconds")
    if not (reorder_window_s > 0 and math.isfinite(reorder_window_s)):
        raise ValueError("reorder_window_s must be a positive number of seconds")
    warnings: tuple[str, ...] = ()
    if alignment is None:
        alignment, learned, _, warnings, resume = align(
            accident, reference, method="first", bin_s=bin_s, tolerance=tolerance, learn=False)
        rules = learned if rules is None else rules
    window_s = reorder_window_s
    lazy = True
    while True:
        try:
            res = _one_pass(accident, reference, bin_s, tolerance, window_s, adjacent_pairing,
                            alignment, rules or {}, lazy, progress, resume)
            resume = (None, None)
        except (_Undecodable, _TooLate, RecordingError) as exc:
            if lazy:
                # a pass that decodes only differing payloads holds undecodable messages
                # as well; where one of them may have mattered (it did not decode, or the
                # pass stopped early), the pass is read decoded, which leaves them out
                lazy = False
            elif isinstance(exc, _TooLate):
                # each pass at least doubles the window: once it spans the files' log times
                # nothing can be late, so the loop ends (a span is at most MAX_SPAN_S)
                window_s = max(2.0 * window_s, exc.window_s)
            else:
                raise
        else:
            if warnings:
                res = dataclasses.replace(res, warnings=warnings + res.warnings)
            return res


#: A message as a pass streams it: (channel, log time [ns], payload, decoder) read undecoded
#: (as :meth:`Recording.undecoded` yields it), or (channel, log time [ns], payload, None,
#: message) decoded.
_Streamed = tuple[Any, ...]


def _stream(rec: Recording, lazy: bool) -> Iterator[_Streamed]:
    if lazy:
        return rec.undecoded()
    return ((m.channel, m.log_time_ns, m.payload, None, m.message) for m in rec.decoded())


def _one_pass(
    accident: Recording,
    reference: Recording,
    bin_s: float,
    tolerance: Tolerance,
    window_s: float,
    adjacent_pairing: bool,
    alignment: Alignment,
    rules: dict[str, FieldRules],
    lazy: bool,
    progress: Callable[[int, int], None] | None = None,
    resume: tuple[Iterator[Any] | None, Iterator[Any] | None] = (None, None),
) -> SeriesResult:
    """One streamed pass with a fixed reorder window; raises :class:`_TooLate` if it is short.
    ``lazy``: read the messages undecoded and decode only those whose payload differs from
    their partner's (raises :class:`_Undecodable` if one does not decode)."""
    window_bins = max(1, math.ceil(window_s / bin_s))
    channels: dict[str, list[ChannelInfo | None]] = {}
    # bin -> topic -> (accident, reference) entries
    open_bins: dict[int, dict[str, tuple[list[_Entry], list[_Entry]]]] = {}
    acc: dict[str, _Acc] = {}
    read = [0, 0]
    latest = [-math.inf, -math.inf]
    disorder_ns = [0.0, 0.0]
    bin_ns = bin_s * 1e9
    scored_below = 0  # every bin below this one has been scored
    origin = alignment.origin_ns
    streams = [r if r is not None and lazy else _stream(rec, lazy)
               for r, rec in zip(resume, (accident, reference), strict=True)]
    first = [math.inf, math.inf]
    last = [-math.inf, -math.inf]
    max_span_ns = MAX_SPAN_S * 1e9
    recs = (accident, reference)
    total_bytes = accident.size + reference.size
    # per side: topic -> offset to the accident's clock [ns]; aligned log times; the last
    # payload and its time (repeats)
    times: tuple[dict[str, array], dict[str, array]] = ({}, {})  # 8 bytes a message
    repeated: tuple[dict[str, int], dict[str, int]] = ({}, {})
    before: tuple[dict[str, int], dict[str, int]] = ({}, {})
    repeat_ns = REPEAT_S * 1e9

    def span_error(side: int) -> None:
        lo, hi = first[side], last[side]
        raise RecordingError(
            f"{recs[side].path}: log times span {(hi - lo) / 86400e9:.4g} days "
            f"({lo} to {hi} ns): a clock that wrapped past 2^64 ns or a corrupted timestamp, "
            "not one drive",
            "check the recording's timestamps with 'mcap info'; rocas compares runs of at "
            f"most {MAX_SPAN_S / 86400:g} days",
        )

    def bin_of(side: int, t_aligned: int) -> int:
        b = math.floor((t_aligned - origin) / bin_ns + 0.5)
        if 0 <= b < scored_below:
            # earlier than bins already scored: a window as wide as this file's disorder so
            # far (plus rounding) holds it
            behind = latest[side] - t_aligned
            raise _TooLate(behind / 1e9 + 2 * bin_s if math.isfinite(behind) else 0.0)
        return b

    def note_channel(side: int, info: ChannelInfo) -> None:
        pair = channels.get(info.topic)
        if pair is None:
            pair = channels[info.topic] = [None, None]
        known = pair[side]
        if known is None or known.id != info.id:
            other = pair[1 - side]
            if other is not None and not _same_schema(other, info):
                a_info, b_info = (info, other) if side == ACCIDENT else (other, info)
                raise RecordingError(
                    f"channel {info.topic} has a different schema in the two recordings "
                    f"({_schema_difference(a_info, b_info)})",
                    "compare recordings of the same stack version",
                )
            pair[side] = info

    def flush(below: int) -> None:
        nonlocal scored_below
        for b in sorted(k for k in open_bins if k < below):
            for topic, (xs, ys) in open_bins.pop(b).items():
                xs.sort(key=_LOG_TIME_THEN_ARRIVAL)
                ys.sort(key=_LOG_TIME_THEN_ARRIVAL)
                a = acc.get(topic)
                if a is None:
                    a = acc[topic] = _Acc(reach_ns=bin_ns / 2)
                a.add_bin(b, xs, ys, rules.get(topic, tolerance), adjacent_pairing)
        scored_below = max(scored_below, below)

    # (side, topic) -> its messages back at their times, for channels stamped at flush time
    unflushed = {key: unflush(period, flush)
                 for key, (period, flush) in alignment.flush_plan().items()}

    # per side: topic -> [offset to the accident's clock, last payload, its aligned time,
    # aligned times since t = 0] (one look-up a message)
    per_topic: tuple[dict[str, list[Any]], dict[str, list[Any]]] = ({}, {})

    def topic_state(side: int, topic: str) -> list[Any]:
        st = per_topic[side][topic] = [alignment.offset_ns(topic, side), None, 0, array("q")]
        times[side][topic] = st[3]
        return st

    def head(side: int) -> tuple[_Streamed | None, float, int]:
        """The side's next message, its bin (inf at the end) and its aligned time."""
        msg = next(streams[side], None)
        if msg is None:
            return None, math.inf, 0
        topic = msg[0].topic
        if unflushed and (at := unflushed.get((side, topic))) is not None:
            msg = (msg[0], at(msg[1]), *msg[2:])
        t = msg[1]
        st = per_topic[side].get(topic) or topic_state(side, topic)
        t_al = t + st[0]
        if t < first[side]:
            first[side] = t
        if t > last[side]:
            last[side] = t
        if last[side] - first[side] > max_span_ns or abs(t_al - origin) > max_span_ns:
            span_error(side)
        return msg, bin_of(side, t_al), t_al

    (h0, b0, a0), (h1, b1, a1) = head(0), head(1)
    heads: list[_Streamed | None] = [h0, h1]
    head_bins = [b0, b1]
    head_times = [a0, a1]
    # per side, the ChannelInfos noted so far by id (held here, so that no id is reused)
    noted: tuple[dict[int, ChannelInfo], dict[int, ChannelInfo]] = ({}, {})
    since_flush = 0
    while heads[0] is not None or heads[1] is not None:
        side = ACCIDENT if head_bins[ACCIDENT] <= head_bins[REFERENCE] else REFERENCE
        msg = heads[side]
        assert msg is not None
        ch, t, payload, decode = msg[0], msg[1], msg[2], msg[3]
        b = int(head_bins[side])
        t_al = head_times[side]
        if id(ch) not in noted[side]:
            note_channel(side, ch)
            noted[side][id(ch)] = ch
        read[side] += 1
        topic = ch.topic
        st = per_topic[side][topic]
        if t < latest[side]:
            disorder_ns[side] = max(disorder_ns[side], latest[side] - t)
        else:
            latest[side] = t
        if b < 0:
            # before the span both files cover: nothing in the other run to compare with
            before[side][topic] = before[side].get(topic, 0) + 1
        elif st[1] == payload and abs(t_al - st[2]) < repeat_ns:
            repeated[side][topic] = repeated[side].get(topic, 0) + 1
        else:
            st[1] = payload
            st[2] = t_al
            st[3].append(t_al - origin)
            bin_slots = open_bins.get(b)
            if bin_slots is None:
                bin_slots = open_bins[b] = {}
            slot = bin_slots.get(topic)
            if slot is None:
                slot = bin_slots[topic] = ([], [])
            slot[side].append((t_al, read[side], ch, payload, decode,
                               _UNDECODED if decode is not None else msg[4]))
        heads[side], head_bins[side], head_times[side] = head(side)
        since_flush += 1
        if since_flush >= 256:
            since_flush = 0
            if progress is not None:
                progress(accident.report.bytes_read + reference.report.bytes_read, total_bytes)
            low = min(head_bins)
            if low != math.inf:
                flush(int(low) - window_bins)
    flush(2**62)
    for a in acc.values():
        a.finish_pending()

    # the span both files cover, on the accident's clock
    ref_off = round(alignment.offset_s * 1e9)
    end_ns = min(last[ACCIDENT], last[REFERENCE] + ref_off) if read[0] and read[1] else origin
    series: dict[str, ChannelSeries] = {}
    accounts: dict[str, ChannelAccount] = {}
    for topic in sorted(channels):
        pair = channels[topic]
        only = None
        if pair[ACCIDENT] is None:
            only = "reference"
        elif pair[REFERENCE] is None:
            only = "accident"
        a = acc.get(topic, _Acc())
        ts = (np.sort(np.frombuffer(times[0].get(topic, array("q")), dtype=np.int64)),
              np.sort(np.frombuffer(times[1].get(topic, array("q")), dtype=np.int64)))
        bins, values, counts, entered, firsts, aside, outside = a.finish(
            ts, end_ns - origin, bin_ns, origin)
        outside = (outside[0] + before[0].get(topic, 0), outside[1] + before[1].get(topic, 0))
        series[topic] = ChannelSeries(
            topic=topic,
            times_s=np.asarray(bins, dtype=np.float64) * bin_s,
            mdr=np.asarray(values, dtype=np.float64),
            messages=np.asarray(counts, dtype=np.int64).reshape(-1, 2),
            only_in=only,
            entered=np.asarray(entered, dtype=bool),
            first_differing_s=np.asarray(firsts, dtype=np.float64),
        )
        account = ChannelAccount(
            aside=aside,
            repeated=(repeated[0].get(topic, 0), repeated[1].get(topic, 0)),
            outside=outside,
            stops_s=_stops(ts, end_ns - origin, bin_ns),
        )
        if account != ChannelAccount():
            accounts[topic] = account
    return SeriesResult(
        series=series,
        channels={t: (p[0], p[1]) for t, p in channels.items()},
        messages_read=(read[0], read[1]),
        bin_s=bin_s,
        disorder_s=(disorder_ns[0] / 1e9, disorder_ns[1] / 1e9),
        reorder_window_s=window_s,
        span_s=tuple(  # type: ignore[arg-type]
            (last[s] - first[s]) / 1e9 if read[s] else 0.0 for s in (ACCIDENT, REFERENCE)),
        compared_s=(0.0, max(0.0, (end_ns - origin) / 1e9)),
        ends_s=((last[ACCIDENT] - origin) / 1e9 if read[0] else 0.0,
                (last[REFERENCE] + ref_off - origin) / 1e9 if read[1] else 0.0),
        accounts=accounts,
        timing_s=_median_gap(acc) / 1e9,
    )


def _median_gap(acc: dict[str, _Acc]) -> float:
    gaps = sorted(a.same_gap for a in acc.values() if a.same_gap)
    if not gaps:
        return 0.0
    k = len(gaps) // 2
    return float(gaps[k]) if len(gaps) % 2 else (gaps[k - 1] + gaps[k]) / 2.0


def _stops(times: tuple[np.ndarray, np.ndarray], end_ns: float, bin_ns: float
           ) -> tuple[float | None, float | None]:
    """Per side, the channel's last message when the channel falls silent there for good while
    the other run goes on publishing it for more than :data:`SILENT_WINDOW_S` of the compared
    span [s since t = 0]; None otherwise."""
    out: list[float | None] = [None, None]
    for side in (ACCIDENT, REFERENCE):
        mine, other = times[side], times[1 - side]
        if not len(mine) or not len(other):
            continue
        end_other = min(float(other[-1]), end_ns)
        if end_other - float(mine[-1]) > max(SILENT_WINDOW_S * 1e9, bin_ns):
            out[side] = float(mine[-1]) / 1e9
    return out[0], out[1]


#: the order of a bin's entries (log time, arrival, ...): the message is never compared
_LOG_TIME_THEN_ARRIVAL = operator.itemgetter(0, 1)


def _schema_label(info: ChannelInfo) -> str:
    return f"{info.message_encoding}:{info.schema_name or '<no schema>'}"


def _schema_difference(a: ChannelInfo, b: ChannelInfo) -> str:
    la, lb = _schema_label(a), _schema_label(b)
    if la == lb:
        return f"{la} in both, defined differently"
    return f"{la} vs {lb}"


def _same_schema(a: ChannelInfo, b: ChannelInfo) -> bool:
    """Whether two channels carry the same message type, as defined by their schemas.

    Equal bytes are the same schema. Otherwise a protobuf schema is compared as the
    definitions of the message's file and the files it imports, whatever their order in the
    FileDescriptorSet (loggers order dependencies differently), and a JSON schema as JSON.
    """
    if (a.message_encoding, a.schema_encoding, a.schema_name) != (
        b.message_encoding, b.schema_encoding, b.schema_name
    ):
        return False
    if a.schema_data == b.schema_data:
        return True
    ca, cb = _canonical_schema(a), _canonical_schema(b)
    return ca is not None and ca == cb


def _canonical_schema(info: ChannelInfo) -> object | None:
    """An order-free form of the schema, or None when it cannot be read."""
    try:
        if info.schema_encoding == "protobuf":
            fds = descriptor_pb2.FileDescriptorSet.FromString(info.schema_data)
            files = {f.name: f for f in fds.file}
            root = next(
                f.name for f in fds.file for m in f.message_type
                if info.schema_name == ".".join(filter(None, (f.package, m.name)))
                or info.schema_name.startswith(".".join(filter(None, (f.package, m.name))) + ".")
            )
            needed, todo = set(), [root]
            while todo:
                name = todo.pop()
                if name not in needed:
                    needed.add(name)
                    todo.extend(files[name].dependency)
            return tuple(
                (name, files[name].SerializeToString(deterministic=True)) for name in sorted(needed)
            )
        if info.schema_encoding == "jsonschema":
            return json.dumps(json.loads(info.schema_data), sort_keys=True)
    except (StopIteration, KeyError, ValueError, DecodeError):
        return None
    return None
