"""Two recordings put on one clock before they are compared, and what their start teaches.

Real loggers do not start together: one starts a second late, one file holds a latched
message from before the run, one channel is stamped on another clock. rocas reads the first
:data:`HEAD_S` seconds of each file once (undecoded) and puts the reference's log times on
the accident's clock (``--align``):

- ``auto`` (default): by **content**. A payload that occurs once in the head of each file, on
  the same topic, is the same message; the offset on which most such matches agree (within
  half a bin; at least :data:`MIN_MATCHES` of them and half of all matches) is the files'
  offset, the median of the agreeing matches. Without such agreement (two noisy runs share no
  payload), by **first messages**: the median, over the topics both heads hold, of the
  difference of each topic's first log time (a latched message moves one topic, not the
  median).
- ``first``: each file's first message (rocas's rule before alignment existed);
  ``log-time``: no offset (both files on one clock); ``TOPIC``: that topic's first message in
  each file.

A topic whose own content matches agree on another offset than the files' (a channel stamped
on another clock) gets that offset, and the result lists it.

The comparison starts at the later of the two files' first messages, on the accident's
clock (t = 0): before it one file has nothing to compare with. From the same heads, the
message pairs of each channel's first ``baseline_s`` seconds teach what "the same" means for
a noisy pair (:mod:`rocas.analysis.noise`).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rocas.analysis.mdr import Tolerance
from rocas.analysis.noise import (
    MIN_START_PAIRS,
    FieldLearner,
    FieldRules,
    leaf_pairs,
    leaf_paths,
    noisy_start,
    with_ignored,
)
from rocas.errors import RecordingError, UsageError
from rocas.recording.reader import Recording

#: Longest stretch of log time one recording may span [s]. A longer one is a clock that
#: wrapped past 2**64 ns or a corrupted timestamp, never a drive: it is refused, since its
#: bins (and the reorder window it would need) say nothing about the run.
MAX_SPAN_S = 30 * 86400.0
#: Log time read from the start of each file to align them and learn their noise [s].
HEAD_S = 8.0
#: Messages per topic and side whose payloads are matched between the heads (enough to agree
#: on an offset; the first ones, so a late start of up to the head's length still overlaps).
HASHED_PER_TOPIC = 256
#: Payloads kept per topic and side from the head, to learn the noise from.
KEEP_PER_TOPIC = 400
#: Payload bytes kept per side from the head.
KEEP_BYTES = 64 << 20
#: Fewest content matches that agree on an offset for it to be taken.
MIN_MATCHES = 3
#: Fewest matches on one topic for it to get its own offset.
MIN_CHANNEL_MATCHES = 5
#: Payload bytes of a head held to go on with its pass instead of reading it again.
RESUME_BYTES = 64 << 20
#: Start pairs used per channel to learn its noise.
MAX_START_PAIRS = 60

ALIGN_METHODS = ("auto", "first", "log-time")


@dataclass(frozen=True)
class Alignment:
    """How the reference was put on the accident's clock.

    Attributes:
        method: "content", "first messages", "file starts", "log time" or "first message of
            TOPIC".
        offset_s: added to the reference's log times [s].
        matches: content matches that agree with the offset (0 unless method is content).
        channel_shifts_s: (side, topic) -> added to that recording's log times of that
            topic, before the offset [s]: a channel on another clock than the rest of its
            file (its identical messages agree on another offset; the file where the channel
            starts later after its first message is the one corrected).
        origin_ns: t = 0 of the comparison, on the accident's clock [ns]: the later of the
            two files' first messages.
        starts_s: (accident, reference) first message of each file [s relative to t = 0].
        flushed: (side, topic, the channel's period [s], the flush period [s]) of each channel
            whose log times in that recording are flush times (most of its messages share
            their log time with the one before): its messages are spread back over the flush
            period in their order, one period apart (:func:`flushed_channels`).
    """

    method: str
    offset_s: float
    matches: int
    channel_shifts_s: dict[tuple[int, str], float]
    origin_ns: int
    starts_s: tuple[float, float]
    flushed: tuple[tuple[int, str, float, float], ...] = ()

    def flush_plan(self) -> dict[tuple[int, str], tuple[int, int]]:
        """(side, topic) -> (the channel's period, the flush period) [ns] for the channels
        whose log times are the times their buffer was flushed in that recording."""
        return {(side, topic): (round(p * 1e9), round(f * 1e9))
                for side, topic, p, f in self.flushed}

    def offset_ns(self, topic: str, side: int = 1) -> int:
        """What puts a message of ``topic`` from recording ``side`` (0 accident, 1 reference)
        on the accident's clock [ns]."""
        base = self.offset_s if side else 0.0
        return round((base + self.channel_shifts_s.get((side, topic), 0.0)) * 1e9)

    def to_json(self) -> dict[str, Any]:
        return {"method": self.method, "offset_s": self.offset_s, "matches": self.matches,
                "channel_clocks": [{"recording": ("accident", "reference")[side], "topic": topic,
                                    "shift_s": shift}
                                   for (side, topic), shift in sorted(self.channel_shifts_s.items())],
                "starts_s": {"accident": self.starts_s[0], "reference": self.starts_s[1]},
                "flushed": [{"recording": ("accident", "reference")[side], "topic": topic,
                             "period_s": p, "flush_period_s": f}
                            for side, topic, p, f in self.flushed]}


@dataclass
class _TopicHead:
    first_ns: int
    hashes: dict[tuple[int, int], list[int]] = field(default_factory=dict)  # key -> [n, t]
    kept: list[tuple[int, bytes, Callable[[bytes], Any]]] = field(default_factory=list)
    hashed: int = 0  # messages whose payload went into hashes

    def count(self, payload: bytes, t: int) -> None:
        """One more message with this payload at ``t`` (the first one's time is kept)."""
        self.hashed += 1
        key = (len(payload), hash(payload))
        slot = self.hashes.get(key)
        if slot is None:
            self.hashes[key] = [1, t]
        else:
            slot[0] += 1


@dataclass
class _Head:
    topics: dict[str, _TopicHead]
    earliest_ns: int | None
    #: the pass the head began, to go on with: its messages read so far, then the rest (None
    #: when they took more than :data:`RESUME_BYTES`; the pass then reads the file again)
    resume: Iterator[Any] | None = None


def _read_head(rec: Recording) -> _Head:
    topics: dict[str, _TopicHead] = {}
    first_read: int | None = None
    earliest: int | None = None
    kept_bytes = 0
    limit = round(HEAD_S * 1e9)
    stream = rec.undecoded()
    seen: list[Any] | None = []
    seen_bytes = 0
    ended = True
    try:
        for msg in stream:
            ch, t, payload, decode = msg
            if seen is not None:
                seen.append(msg)
                seen_bytes += len(payload)
                if seen_bytes > RESUME_BYTES:
                    seen = None
            if first_read is None:
                first_read = t
            if t > first_read + limit:
                ended = False
                break
            earliest = t if earliest is None else min(earliest, t)
            if abs(t - first_read) > MAX_SPAN_S * 1e9:
                lo, hi = min(t, first_read), max(t, first_read)
                raise RecordingError(
                    f"{rec.path}: log times span {(hi - lo) / 86400e9:.4g} days ({lo} to {hi} "
                    "ns): a clock that wrapped past 2^64 ns or a corrupted timestamp, not one "
                    "drive",
                    "check the recording's timestamps with 'mcap info'; rocas compares runs of "
                    f"at most {MAX_SPAN_S / 86400:g} days")
            th = topics.get(ch.topic)
            if th is None:
                th = topics[ch.topic] = _TopicHead(t)
            elif t < th.first_ns:
                th.first_ns = t
            if th.hashed < HASHED_PER_TOPIC:
                th.count(payload, t)
            if len(th.kept) < KEEP_PER_TOPIC and kept_bytes + len(payload) <= KEEP_BYTES:
                th.kept.append((t, payload, decode))
                kept_bytes += len(payload)
    except BaseException:
        _close(stream)
        raise
    if seen is None:
        _close(stream)
        return _Head(topics, earliest)
    return _Head(topics, earliest, iter(seen) if ended else itertools.chain(seen, stream))


def _close(stream: Any) -> None:
    close = getattr(stream, "close", None)
    if close is not None:
        close()


def _shared_payloads(head_a: _Head, head_b: _Head, topics: list[str]) -> bool:
    """Whether at least a tenth of the hashed head messages of the two files, on the topics
    both have, have a byte-identical copy in the other head."""
    shared = total = 0
    for t in topics:
        ha, hb = head_a.topics[t].hashes, head_b.topics[t].hashes
        total += sum(n for n, _ in ha.values())
        shared += sum(n for key, (n, _) in ha.items() if key in hb)
    return total > 0 and 10 * shared >= total


def _agreeing(offsets: list[int], width_ns: float) -> list[int]:
    """The largest group of ``offsets`` within ``width_ns`` of each other (the earliest such
    group among equals), sorted."""
    xs = sorted(offsets)
    best_lo, best_n, j = 0, 0, 0
    for i, x in enumerate(xs):
        while x - xs[j] > width_ns:
            j += 1
        if i - j + 1 > best_n:
            best_lo, best_n = j, i - j + 1
    return xs[best_lo:best_lo + best_n]


def _median_int(xs: list[int]) -> int:
    s = sorted(xs)
    k = len(s) // 2
    return s[k] if len(s) % 2 else (s[k - 1] + s[k]) // 2


def _content_offsets(a: _Head, b: _Head) -> dict[str, list[int]]:
    """topic -> accident minus reference log time of each payload found once in each head."""
    out: dict[str, list[int]] = {}
    for topic, ta in a.topics.items():
        tb = b.topics.get(topic)
        if tb is None:
            continue
        votes = [sa[1] - sb[1] for key, sa in ta.hashes.items()
                 if sa[0] == 1 and (sb := tb.hashes.get(key)) is not None and sb[0] == 1]
        if votes:
            out[topic] = votes
    return out


def align(accident: Recording, reference: Recording, *, method: str = "auto",
          bin_s: float = 0.1, baseline_s: float = 3.0, tolerance: Tolerance | None = None,
          learn: bool = True, ignore: Iterable[str] = ()
          ) -> tuple[Alignment, dict[str, FieldRules], bool, tuple[str, ...],
                     tuple[Iterator[Any] | None, Iterator[Any] | None]]:
    """Align the two recordings and learn each channel's comparison rules from their start.

    Args:
        method: "auto", "first", "log-time", or a topic (its first message in each file).
        bin_s: the series' bin width [s]; content matches agree within half of it.
        baseline_s: length of each channel's start the noise is learned from [s].
        tolerance: ``--atol``/``--rtol`` (None: none given; floats then get learned
            tolerances on a noisy pair).
        learn: learn tolerances and fields to set aside on a noisy pair (False: the paper's
            exact MDR, ``ignore`` patterns still apply).
        ignore: ``--ignore-field`` patterns (``PATH`` or ``TOPIC:PATH``, shell wildcards).

    Returns:
        (the alignment, topic -> rules for the topics that have any, whether the pair is
        noisy at its start, warning lines, each recording's undecoded pass as the head began
        it, to go on with (:meth:`Recording.undecoded`'s items; None: read it again)).

    Raises:
        UsageError: ``method`` names a topic that is not in both files' heads.
    """
    head_a, head_b = _read_head(accident), _read_head(reference)
    flushed = flushed_channels(head_a, head_b)
    for side, topic, period, flush in flushed:
        _unflush((head_a, head_b)[side].topics[topic], round(period * 1e9), round(flush * 1e9))
    starts, warnings = _starts(((accident, head_a), (reference, head_b)))
    sa, sb = starts
    if sa is None or sb is None:
        alignment = Alignment("file starts", 0.0, 0, {}, sa or sb or 0, (0.0, 0.0))
        return alignment, {}, False, warnings, (head_a.resume, head_b.resume)
    found = _offset(method, head_a, head_b, sa, sb, bin_s)
    offset = found.offset_ns
    origin = max(sa, sb + offset)
    alignment = Alignment(found.how, offset / 1e9, found.matches, found.channel_shifts_s, origin,
                          ((sa - origin) / 1e9, (sb + offset - origin) / 1e9), flushed)
    rules, noisy = _learn(head_a, head_b, alignment, bin_s, baseline_s, tolerance, learn,
                          list(ignore))
    return alignment, rules, noisy, warnings, (head_a.resume, head_b.resume)


def _starts(sides: tuple[tuple[Recording, _Head], tuple[Recording, _Head]]
            ) -> tuple[tuple[int | None, int | None], tuple[str, ...]]:
    """Each file's first log time [ns]: the earlier of its summary's start time and its
    head's earliest message (None for a file with neither), and a warning line for a file
    whose summary lists a start after the first message read."""
    warnings: list[str] = []
    starts: list[int | None] = []
    for rec, head in sides:
        listed = rec.summary_start_time_ns()
        start = head.earliest_ns
        if listed is not None and start is not None and listed > start:
            warnings.append(f"{rec.path}: the summary section's start time lies after the first "
                            "message; aligned at the earliest message read instead")
        elif listed is not None:
            start = listed if start is None else min(start, listed)
        starts.append(start)
    return (starts[0], starts[1]), tuple(warnings)


@dataclass(frozen=True)
class _Offset:
    """An offset found for the reference (:attr:`Alignment.method`'s ``how``, the offset
    [ns], the content matches that agree with it, and channels on another clock [s])."""

    how: str
    offset_ns: int
    matches: int = 0
    channel_shifts_s: dict[tuple[int, str], float] = field(default_factory=dict)


def _offset(method: str, head_a: _Head, head_b: _Head, sa: int, sb: int, bin_s: float
            ) -> _Offset:
    """The offset ``method`` asks for (``sa``, ``sb``: the files' starts [ns])."""
    if method == "auto":
        return _auto_offset(head_a, head_b, sa, sb, bin_s)
    if method == "first":
        return _Offset("file starts", sa - sb)
    if method == "log-time":
        return _Offset("log time", 0)
    ta, tb = head_a.topics.get(method), head_b.topics.get(method)
    if ta is None or tb is None:
        raise UsageError(
            f"--align {method}: that channel has no message in the first {HEAD_S:g} s of "
            f"{'either recording' if ta is None and tb is None else 'one recording'}",
            "name a channel both recordings publish from their start, or use --align auto")
    return _Offset(f"first message of {method}", ta.first_ns - tb.first_ns)


def _auto_offset(head_a: _Head, head_b: _Head, sa: int, sb: int, bin_s: float) -> _Offset:
    """``--align auto``: by identical messages when enough of them agree on one offset
    (within half a bin), else by the channels' first messages, refined by the best match of
    content, else by the files' starts."""
    width = bin_s * 1e9 / 2.0
    by_topic = _content_offsets(head_a, head_b)
    shared = sorted(set(head_a.topics) & set(head_b.topics))
    # the channels whose payloads the two runs share (repeated ones, which cannot time an
    # offset) are no noisy channels: the content of the others is compared
    signals = _topic_signals(head_a, head_b, [
        t for t in shared if not _shared_payloads(head_a, head_b, [t])])
    shift = (head_a.earliest_ns or 0) - (head_b.earliest_ns or 0)
    votes = [v for vs in by_topic.values() for v in vs]
    agree = _agreeing(votes, width) if votes else []
    if len(agree) >= MIN_MATCHES and 2 * len(agree) >= len(votes):
        offset = _median_int(agree)
        return _Offset("content", offset, len(agree),
                       _channel_shifts(head_a, head_b, by_topic, offset, width, sa, sb))
    if not shared:
        return _Offset("file starts", sa - sb)
    offset = _median_int([head_a.topics[t].first_ns - head_b.topics[t].first_ns for t in shared])
    best = (_best_offset(list(signals.values()), offset, shift, bin_s, MATCH_RANGE_S)
            if signals else None)
    if best is not None:
        return _Offset("best match of content", best)
    return _Offset("first messages", offset)


def _channel_shifts(head_a: _Head, head_b: _Head, by_topic: dict[str, list[int]], offset: int,
                    width: float, sa: int, sb: int) -> dict[tuple[int, str], float]:
    """(side, topic) -> shift [s] of each channel whose identical messages agree on an offset
    more than ``width`` [ns] from ``offset``: the channel is on another clock in the file
    where it starts later after that file's first message (``sa``, ``sb`` [ns])."""
    channel: dict[tuple[int, str], float] = {}
    for topic, vs in sorted(by_topic.items()):
        own = _agreeing(vs, width)
        if len(own) >= MIN_CHANNEL_MATCHES and 5 * len(own) >= 4 * len(vs):
            o = _median_int(own)
            if abs(o - offset) > width:
                lag_a = head_a.topics[topic].first_ns - sa
                lag_b = head_b.topics[topic].first_ns - sb
                if lag_a > lag_b:
                    channel[(0, topic)] = (offset - o) / 1e9
                else:
                    channel[(1, topic)] = (o - offset) / 1e9
    return channel


#: A channel is flushed in a recording when at least this fraction of its messages in the head
#: share their log time with the message before.
FLUSHED_FRACTION = 0.5


def _times(th: _TopicHead) -> np.ndarray:
    """The topic's kept log times, sorted [ns since its first]."""
    return np.sort(np.array([t - th.first_ns for t, _, _ in th.kept], dtype=np.int64))


def flushed_channels(head_a: _Head, head_b: _Head) -> tuple[tuple[int, str, float, float], ...]:
    """The channels stamped at flush time in one recording and not in the other: (side, topic,
    the channel's period in the other recording, the flush period) [s]. Their log times say
    when a logger wrote a buffer, not when each message was published; the other recording's
    period and the order within each flush give the messages back their times."""
    out = []
    heads = (head_a, head_b)
    for side in (0, 1):
        for topic, th in sorted(heads[side].topics.items()):
            other = heads[1 - side].topics.get(topic)
            if other is None or len(th.kept) < 10 or len(other.kept) < 10:
                continue
            mine, theirs = np.diff(_times(th)), np.diff(_times(other))
            if (np.count_nonzero(mine == 0) < FLUSHED_FRACTION * len(mine)
                    or np.count_nonzero(theirs == 0) >= FLUSHED_FRACTION * len(theirs)):
                continue
            gaps = mine[mine > 0]
            period = float(np.median(theirs[theirs > 0])) if np.any(theirs > 0) else 0.0
            if len(gaps) and period > 0:
                out.append((side, topic, period / 1e9, float(np.median(gaps)) / 1e9))
    return tuple(out)


def unflush(period_ns: int, flush_ns: int) -> Callable[[int], int]:
    """A function that gives a flushed channel's messages, fed in file order, their times
    back: one channel period after the one before in their flush, counted from the flush
    before (the first flush counts from one flush period before it); never later than the
    flush itself."""
    state: list[int] = []  # [this flush's log time, the last flush's, index within this flush]

    def at(t: int) -> int:
        if not state:
            state.extend((t, t - flush_ns, -1))
        if t != state[0]:
            state[1], state[0], state[2] = state[0], t, -1
        state[2] += 1
        return min(t, state[1] + (state[2] + 1) * period_ns)

    return at


def _unflush(th: _TopicHead, period_ns: int, flush_ns: int) -> None:
    """A head's flushed channel with its messages back at their times (as the pass reads
    them), its hashes and first time recomputed from them."""
    at = unflush(period_ns, flush_ns)
    th.kept = [(at(t), p, d) for t, p, d in th.kept]
    th.hashes, th.hashed = {}, 0
    for t, p, _ in th.kept:
        th.count(p, t)
    if th.kept:
        th.first_ns = min(t for t, _, _ in th.kept)


#: How far from the first-message offset the best match of content is looked for [s].
MATCH_RANGE_S = 3.0
#: Head messages per topic whose content the best match compares.
MATCH_MESSAGES = 120
#: The best match of content replaces the first-message offset only when its cost is below this
#: fraction of that offset's cost (measured on a noisy catalog pair whose logger started a
#: tick late: 0.41 at the true offset against 0.68 at the first messages', 0.6).
MATCH_GAIN = 0.75


def _signals(th: _TopicHead, base: int
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """A topic's head as (log times [ns since ``base``], (n, k) float leaves, (n, m) integer
    leaves) of the messages that decode, for those with the most common numbers of them
    (k + m >= 1; bools count as integers, strings and bytes are left out)."""
    rows: list[tuple[int, np.ndarray, np.ndarray]] = []
    for t, payload, decode in th.kept[:MATCH_MESSAGES]:
        try:
            message = decode(payload)
        except Exception:  # noqa: BLE001 - a foreign file can hold anything
            continue
        floats, ints = [], []
        for _, is_float, v, _ in leaf_pairs(message, message, "", False):
            x = np.ravel(np.asarray(v))
            if is_float or x.dtype.kind == "f":
                floats.append(x.astype(np.float64))
            elif x.dtype.kind in "iub":
                ints.append(x.astype(np.float64))
        f = np.concatenate(floats) if floats else np.zeros(0)
        i = np.concatenate(ints) if ints else np.zeros(0)
        if len(f) + len(i):
            rows.append((t - base, f, i))
    if len(rows) < 10:
        return None
    sizes: dict[tuple[int, int], int] = {}
    for _, f, i in rows:
        sizes[(len(f), len(i))] = sizes.get((len(f), len(i)), 0) + 1
    k = max(sizes, key=lambda n: (sizes[n], n))
    kept = sorted(((t, f, i) for t, f, i in rows if (len(f), len(i)) == k), key=lambda r: r[0])
    return (np.array([t for t, _, _ in kept], dtype=np.int64),
            np.stack([f for _, f, _ in kept]), np.stack([i for _, _, i in kept]))


def _match_cost(a: tuple[np.ndarray, np.ndarray, np.ndarray],
                b: tuple[np.ndarray, np.ndarray, np.ndarray], offset: int, reach: float
                ) -> float | None:
    """How unlike each accident message is the reference message nearest to it with
    ``offset`` applied (within ``reach`` ns): the mean over its leaves of the float leaves'
    differences scaled by their spread (at most 3) and the integer leaves' inequality (0 or
    1); None when fewer than five messages pair."""
    ta = a[0]
    tb = b[0] + offset
    k = np.clip(np.searchsorted(tb, ta), 1, len(tb) - 1)
    nearer = np.where(np.abs(tb[k - 1] - ta) <= np.abs(tb[k] - ta), k - 1, k)
    close = np.abs(tb[nearer] - ta) <= reach
    if close.sum() < 5:
        return None
    parts = []
    fa, fb = a[1], b[1]
    if fa.shape[1]:
        scale = np.nanstd(np.concatenate([fa, fb]), axis=0)
        use = np.isfinite(scale) & (scale > 0)
        if use.any():
            with np.errstate(invalid="ignore"):
                d = np.abs(fa[close][:, use] - fb[nearer[close]][:, use]) / scale[use]
            parts.append(np.minimum(np.nan_to_num(d, nan=0.0), 3.0))
    ia, ib = a[2], b[2]
    if ia.shape[1]:
        moving = np.ptp(np.concatenate([ia, ib]), axis=0) > 0
        if moving.any():
            parts.append((ia[close][:, moving] != ib[nearer[close]][:, moving]).astype(float))
    if not parts:
        return None
    return float(np.concatenate(parts, axis=1).mean())


def _topic_signals(head_a: _Head, head_b: _Head, topics: list[str]
                   ) -> dict[str, tuple[Any, Any]]:
    """topic -> (accident, reference) :func:`_signals` of the topics both can compare."""
    out = {}
    base_a, base_b = head_a.earliest_ns or 0, head_b.earliest_ns or 0
    for t in topics:
        a = _signals(head_a.topics[t], base_a)
        b = _signals(head_b.topics[t], base_b)
        if a is not None and b is not None and a[1].shape[1] == b[1].shape[1] \
                and a[2].shape[1] == b[2].shape[1]:
            out[t] = (a, b)
    return out


def _best_offset(pairs: list[tuple[Any, Any]], start: int, shift: int, bin_s: float,
                 range_s: float) -> int | None:
    """The offset near ``start`` (within ``range_s``, in steps of half a bin) at which the
    pairs' content (:func:`_signals`, times relative to each head's first message, ``shift``
    the difference of those) matches best; None when it is not clearly better
    (:data:`MATCH_GAIN`) than ``start`` itself. Refined by the median gap of the messages it
    pairs."""
    reach = bin_s * 1e9 / 2
    step = round(bin_s * 1e9 / 2)
    n = round(range_s * 1e9 / step)

    def cost(offset: int) -> float | None:
        parts = [c for a, b in pairs
                 if (c := _match_cost(a, b, offset - shift, reach)) is not None]
        return sum(parts) / len(parts) if len(parts) * 2 >= len(pairs) else None

    base = cost(start)
    scored = [(c, abs(i), start + i * step) for i in range(-n, n + 1)
              if (c := cost(start + i * step)) is not None]
    if not scored or base is None:
        return None
    c, _, best = min(scored)
    if not c < MATCH_GAIN * base:
        return None
    gaps = []
    for a, b in pairs:
        ta, tb = a[0], b[0] + best - shift
        k = np.clip(np.searchsorted(tb, ta), 1, len(tb) - 1)
        nearer = np.where(np.abs(tb[k - 1] - ta) <= np.abs(tb[k] - ta), k - 1, k)
        d = ta - tb[nearer]
        gaps.extend(int(x) for x in d[np.abs(d) <= reach])
    return best + _median_int(gaps) if gaps else best


def _start_pairs(ta: _TopicHead, tb: _TopicHead, off_a: int, off: int, lo: float, hi: float,
                 width: float) -> list[tuple[tuple[int, bytes, Any], tuple[int, bytes, Any]]]:
    """Each accident message of [lo, hi] paired with the nearest unpaired reference message
    within ``width`` (times on the accident's clock: ``off_a`` and ``off`` added, in order)."""
    xs = sorted(((t + off_a, p, d) for t, p, d in ta.kept if lo <= t + off_a <= hi),
                key=lambda m: m[0])
    ys = sorted((m for m in tb.kept if lo <= m[0] + off <= hi), key=lambda m: m[0])
    pairs = []
    j = 0
    for x in xs:
        while j < len(ys) and ys[j][0] + off < x[0] - width:
            j += 1
        if j < len(ys) and abs(ys[j][0] + off - x[0]) <= width:
            pairs.append((x, ys[j]))
            j += 1
            if len(pairs) >= MAX_START_PAIRS:
                break
    return pairs


def _learn(head_a: _Head, head_b: _Head, alignment: Alignment, bin_s: float, baseline_s: float,
           tolerance: Tolerance | None, learn: bool, ignore: list[str]
           ) -> tuple[dict[str, FieldRules], bool]:
    learners: dict[str, FieldLearner] = {}
    samples: dict[str, Any] = {}
    lo = alignment.origin_ns - bin_s * 1e9 / 2
    hi = alignment.origin_ns + baseline_s * 1e9
    pairs_of = {}
    for topic, ta in head_a.topics.items():
        tb = head_b.topics.get(topic)
        if tb is None:
            continue
        pairs = _start_pairs(ta, tb, alignment.offset_ns(topic, 0), alignment.offset_ns(topic),
                             lo, hi, bin_s * 1e9 / 2)
        pairs_of[topic] = pairs
        learner = learners[topic] = FieldLearner()
        for i, (x, y) in enumerate(pairs):
            same = x[1] == y[1]
            learner.pairs += 1
            learner.identical += same
            learner.first_identical += same and i < MIN_START_PAIRS
    noisy = noisy_start(learners.values())
    default = tolerance if tolerance is not None else Tolerance()
    rules: dict[str, FieldRules] = {}
    for topic, learner in learners.items():
        r = FieldRules(default=default)
        if learn and noisy and learner.identical < learner.pairs:
            fresh = FieldLearner()
            for x, y in pairs_of[topic]:
                if x[2] is not y[2]:
                    break  # two schemas (one decoder each): the pass refuses the channel
                try:
                    ma, mb = x[2](x[1]), y[2](y[1])
                except Exception:  # a foreign file can hold anything; the pass counts it
                    continue
                samples.setdefault(topic, ma)
                fresh.add(ma, mb, x[1] == y[1])
            r = fresh.rules(default, learn_floats=tolerance is None)
        if ignore:
            sample = samples.get(topic)
            if sample is None:
                sample = _first_decoded(head_a.topics[topic]) or _first_decoded(
                    head_b.topics[topic])
            if sample is not None:
                r = with_ignored(r, topic, ignore, leaf_paths(sample))
        if not r.trivial:
            rules[topic] = r
    if ignore:  # topics in one head only
        for head in (head_a, head_b):
            for topic, th in head.topics.items():
                if topic not in learners and (m := _first_decoded(th)) is not None:
                    r = with_ignored(FieldRules(default=default), topic, ignore, leaf_paths(m))
                    if not r.trivial:
                        rules.setdefault(topic, r)
    return rules, noisy


def _first_decoded(th: _TopicHead) -> Any | None:
    for _, payload, decode in th.kept[:3]:
        try:
            return decode(payload)
        except Exception:  # noqa: BLE001 - a foreign file can hold anything
            continue
    return None


def describe(alignment: Alignment) -> str:
    """One line on the alignment, for the terminal."""
    what = f"reference {alignment.offset_s:+.3f} s ({alignment.method}"
    if alignment.matches:
        what += f": {alignment.matches} identical messages agree"
    what += ")"
    if alignment.channel_shifts_s:
        what += "; on another clock: " + ", ".join(
            f"{t} in the {('accident', 'reference')[side]} {o:+.3f} s"
            for (side, t), o in sorted(alignment.channel_shifts_s.items()))
    return what

