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
import math
import operator
from array import array
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rocas.analysis.align import MAX_SPAN_S, Alignment, align, unflush
from rocas.analysis.mdr import EXACT, Tolerance
from rocas.analysis.noise import FieldRules
from rocas.analysis.pairing import (
    ACCIDENT,
    REFERENCE,
    SILENT_WINDOW_S,
    UNDECODED,
    ChannelBins,
    Entry,
    Undecodable,
)
from rocas.analysis.schemas import same_schema, schema_difference
from rocas.errors import RecordingError
from rocas.recording.model import ChannelInfo
from rocas.recording.reader import Recording

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
        except (Undecodable, _TooLate, RecordingError) as exc:
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
    their partner's (raises :class:`Undecodable` if one does not decode)."""
    streams = [r if r is not None and lazy else _stream(rec, lazy)
               for r, rec in zip(resume, (accident, reference), strict=True)]
    # (side, topic) -> its messages back at their times, for channels stamped at flush time
    unflushed = {key: unflush(period, flush)
                 for key, (period, flush) in alignment.flush_plan().items()}
    sides = tuple(
        _Side(side, rec, stream, alignment,
              {topic: at for (s, topic), at in unflushed.items() if s == side})
        for side, (rec, stream) in enumerate(zip((accident, reference), streams, strict=True)))
    bins = _Bins(alignment.origin_ns, bin_s, window_s, rules, tolerance, adjacent_pairing)
    channels: dict[str, list[ChannelInfo | None]] = {}
    _read_in_step((sides[0], sides[1]), bins, channels, progress)
    bins.flush(2**62)
    for a in bins.acc.values():
        a.finish_pending()
    return _result((sides[0], sides[1]), bins, channels, alignment, window_s)


class _Side:
    """One recording as a pass reads it: its stream, how far it has got, and per channel
    what it has read (mutable, one per file and pass).

    Attributes:
        side: :data:`ACCIDENT` or :data:`REFERENCE`.
        first, last: the earliest and latest log time read [ns, the file's clock].
        latest: the latest log time read so far in file order [ns]; ``disorder_ns`` the most
            a message's log time lay behind it.
        read: messages read.
        per_topic: topic -> [offset to the accident's clock [ns], the last payload, its
            aligned time [ns], the aligned times [ns since t = 0]] (one look-up a message).
        times: topic -> the aligned times of its messages kept [ns since t = 0] (8 bytes a
            message).
        repeated, before: topic -> messages logged twice, and messages before the span both
            files cover.
        noted: the ChannelInfos checked so far, by id (held here, so that no id is reused).
    """

    def __init__(self, side: int, rec: Recording, stream: Iterator[_Streamed],
                 alignment: Alignment, unflushed: dict[str, Callable[[int], int]]) -> None:
        self.side = side
        self.rec = rec
        self.stream = stream
        self.alignment = alignment
        self.origin = alignment.origin_ns
        self.unflushed = unflushed  # topic -> its messages back at their times
        self.max_span_ns = MAX_SPAN_S * 1e9
        self.repeat_ns = REPEAT_S * 1e9
        self.first: float = math.inf
        self.last: float = -math.inf
        self.latest: float = -math.inf
        self.disorder_ns = 0.0
        self.read = 0
        self.per_topic: dict[str, list[Any]] = {}
        self.times: dict[str, array] = {}
        self.repeated: dict[str, int] = {}
        self.before: dict[str, int] = {}
        self.noted: dict[int, ChannelInfo] = {}

    def _topic_state(self, topic: str) -> list[Any]:
        st = self.per_topic[topic] = [self.alignment.offset_ns(topic, self.side), None, 0,
                                      array("q")]
        self.times[topic] = st[3]
        return st

    def next(self, bins: _Bins) -> tuple[_Streamed | None, float, int]:
        """The next message in file order (None at the end), its bin of ``bins`` (inf at the
        end) and its aligned log time [ns]."""
        msg = next(self.stream, None)
        if msg is None:
            return None, math.inf, 0
        topic = msg[0].topic
        if self.unflushed and (at := self.unflushed.get(topic)) is not None:
            msg = (msg[0], at(msg[1]), *msg[2:])
        t = msg[1]
        st = self.per_topic.get(topic) or self._topic_state(topic)
        t_al = t + st[0]
        if t < self.first:
            self.first = t
        if t > self.last:
            self.last = t
        if self.last - self.first > self.max_span_ns or abs(t_al - self.origin) > self.max_span_ns:
            self._span_error()
        return msg, bins.bin_of(self, t_al), t_al

    def _span_error(self) -> None:
        lo, hi = self.first, self.last
        raise RecordingError(
            f"{self.rec.path}: log times span {(hi - lo) / 86400e9:.4g} days "
            f"({lo} to {hi} ns): a clock that wrapped past 2^64 ns or a corrupted timestamp, "
            "not one drive",
            "check the recording's timestamps with 'mcap info'; rocas compares runs of at "
            f"most {MAX_SPAN_S / 86400:g} days",
        )

    def count(self, topic: str, t: int, b: int, t_al: int, payload: bytes) -> bool:
        """Count a message read (log time ``t`` in bin ``b``); whether it is to be compared:
        not before the span both files cover, and not logged twice."""
        self.read += 1
        st = self.per_topic[topic]
        if t < self.latest:
            self.disorder_ns = max(self.disorder_ns, self.latest - t)
        else:
            self.latest = t
        if b < 0:
            # before the span both files cover: nothing in the other run to compare with
            self.before[topic] = self.before.get(topic, 0) + 1
            return False
        if st[1] == payload and abs(t_al - st[2]) < self.repeat_ns:
            self.repeated[topic] = self.repeated.get(topic, 0) + 1
            return False
        st[1] = payload
        st[2] = t_al
        st[3].append(t_al - self.origin)
        return True


class _Bins:
    """The bins a pass holds open (bin -> topic -> (accident, reference) entries) and each
    channel's scored bins (``acc``); every bin below ``scored_below`` has been scored."""

    def __init__(self, origin_ns: int, bin_s: float, window_s: float,
                 rules: dict[str, FieldRules], tolerance: Tolerance, adjacent: bool) -> None:
        self.origin = origin_ns
        self.bin_s = bin_s
        self.bin_ns = bin_s * 1e9
        self.window_bins = max(1, math.ceil(window_s / bin_s))
        self.rules = rules
        self.tolerance = tolerance
        self.adjacent = adjacent
        self.open: dict[int, dict[str, tuple[list[Entry], list[Entry]]]] = {}
        self.acc: dict[str, ChannelBins] = {}
        self.scored_below = 0

    def bin_of(self, side: _Side, t_aligned: int) -> int:
        """The bin of an aligned log time [ns]; raises :class:`_TooLate` for a bin already
        scored."""
        b = math.floor((t_aligned - self.origin) / self.bin_ns + 0.5)
        if 0 <= b < self.scored_below:
            # earlier than bins already scored: a window as wide as this file's disorder so
            # far (plus rounding) holds it
            behind = side.latest - t_aligned
            raise _TooLate(behind / 1e9 + 2 * self.bin_s if math.isfinite(behind) else 0.0)
        return b

    def flush(self, below: int) -> None:
        """Score every open bin below ``below``."""
        for b in sorted(k for k in self.open if k < below):
            for topic, (xs, ys) in self.open.pop(b).items():
                xs.sort(key=_LOG_TIME_THEN_ARRIVAL)
                ys.sort(key=_LOG_TIME_THEN_ARRIVAL)
                a = self.acc.get(topic)
                if a is None:
                    a = self.acc[topic] = ChannelBins(reach_ns=self.bin_ns / 2)
                a.add_bin(b, xs, ys, self.rules.get(topic, self.tolerance), self.adjacent)
        self.scored_below = max(self.scored_below, below)


def _read_in_step(sides: tuple[_Side, _Side], bins: _Bins,
                  channels: dict[str, list[ChannelInfo | None]],
                  progress: Callable[[int, int], None] | None) -> None:
    """Read both files in step, the one whose next message falls in the earlier bin first
    (the accident on a tie), put each message to compare in its open bin, and every 256
    messages score the bins the reorder window has left behind. ``channels``: topic ->
    (accident, reference) ChannelInfo, filled as channels appear."""
    total_bytes = sides[0].rec.size + sides[1].rec.size
    open_bins = bins.open
    (h0, b0, a0), (h1, b1, a1) = sides[0].next(bins), sides[1].next(bins)
    heads: list[_Streamed | None] = [h0, h1]
    head_bins = [b0, b1]
    head_times = [a0, a1]
    since_flush = 0
    while heads[0] is not None or heads[1] is not None:
        side = ACCIDENT if head_bins[ACCIDENT] <= head_bins[REFERENCE] else REFERENCE
        s = sides[side]
        msg = heads[side]
        assert msg is not None
        ch, payload, decode = msg[0], msg[2], msg[3]
        b = int(head_bins[side])
        t_al = head_times[side]
        if id(ch) not in s.noted:
            _note_channel(channels, side, ch)
            s.noted[id(ch)] = ch
        topic = ch.topic
        if s.count(topic, msg[1], b, t_al, payload):
            bin_slots = open_bins.get(b)
            if bin_slots is None:
                bin_slots = open_bins[b] = {}
            slot = bin_slots.get(topic)
            if slot is None:
                slot = bin_slots[topic] = ([], [])
            slot[side].append((t_al, s.read, ch, payload, decode,
                               UNDECODED if decode is not None else msg[4]))
        heads[side], head_bins[side], head_times[side] = s.next(bins)
        since_flush += 1
        if since_flush >= 256:
            since_flush = 0
            if progress is not None:
                progress(sides[0].rec.report.bytes_read + sides[1].rec.report.bytes_read,
                         total_bytes)
            low = min(head_bins)
            if low != math.inf:
                bins.flush(int(low) - bins.window_bins)


def _note_channel(channels: dict[str, list[ChannelInfo | None]], side: int,
                  info: ChannelInfo) -> None:
    """Note a channel of one side; refuses a topic whose schema the other side defines
    differently."""
    pair = channels.get(info.topic)
    if pair is None:
        pair = channels[info.topic] = [None, None]
    known = pair[side]
    if known is None or known.id != info.id:
        other = pair[1 - side]
        if other is not None and not same_schema(other, info):
            a_info, b_info = (info, other) if side == ACCIDENT else (other, info)
            raise RecordingError(
                f"channel {info.topic} has a different schema in the two recordings "
                f"({schema_difference(a_info, b_info)})",
                "compare recordings of the same stack version",
            )
        pair[side] = info


def _result(sides: tuple[_Side, _Side], bins: _Bins,
            channels: dict[str, list[ChannelInfo | None]], alignment: Alignment,
            window_s: float) -> SeriesResult:
    """The pass's result once both files are read and every bin is scored."""
    acc_side, ref_side = sides
    origin = alignment.origin_ns
    both_read = bool(acc_side.read and ref_side.read)
    # the span both files cover, on the accident's clock
    ref_off = round(alignment.offset_s * 1e9)
    end_ns = min(acc_side.last, ref_side.last + ref_off) if both_read else origin
    series, accounts = _channel_results(sides, bins, channels, end_ns - origin)
    return SeriesResult(
        series=series,
        channels={t: (p[0], p[1]) for t, p in channels.items()},
        messages_read=(acc_side.read, ref_side.read),
        bin_s=bins.bin_s,
        disorder_s=(acc_side.disorder_ns / 1e9, ref_side.disorder_ns / 1e9),
        reorder_window_s=window_s,
        span_s=tuple(  # type: ignore[arg-type]
            (s.last - s.first) / 1e9 if s.read else 0.0 for s in sides),
        compared_s=(0.0, max(0.0, (end_ns - origin) / 1e9)),
        ends_s=((acc_side.last - origin) / 1e9 if acc_side.read else 0.0,
                (ref_side.last + ref_off - origin) / 1e9 if ref_side.read else 0.0),
        accounts=accounts,
        timing_s=_median_gap(bins.acc) / 1e9,
    )


def _channel_results(sides: tuple[_Side, _Side], bins: _Bins,
                     channels: dict[str, list[ChannelInfo | None]], end_ns: float
                     ) -> tuple[dict[str, ChannelSeries], dict[str, ChannelAccount]]:
    """Each channel's series and (when it has something to report) account, by topic.
    ``end_ns``: end of the compared span [ns since t = 0]."""
    bin_s, bin_ns = bins.bin_s, bins.bin_ns
    series: dict[str, ChannelSeries] = {}
    accounts: dict[str, ChannelAccount] = {}
    for topic in sorted(channels):
        pair = channels[topic]
        only = None
        if pair[ACCIDENT] is None:
            only = "reference"
        elif pair[REFERENCE] is None:
            only = "accident"
        a = bins.acc.get(topic, ChannelBins())
        ts = (np.sort(np.frombuffer(sides[0].times.get(topic, array("q")), dtype=np.int64)),
              np.sort(np.frombuffer(sides[1].times.get(topic, array("q")), dtype=np.int64)))
        b, values, counts, entered, firsts, aside, outside = a.finish(
            ts, end_ns, bin_ns, bins.origin)
        outside = (outside[0] + sides[0].before.get(topic, 0),
                   outside[1] + sides[1].before.get(topic, 0))
        series[topic] = ChannelSeries(
            topic=topic,
            times_s=np.asarray(b, dtype=np.float64) * bin_s,
            mdr=np.asarray(values, dtype=np.float64),
            messages=np.asarray(counts, dtype=np.int64).reshape(-1, 2),
            only_in=only,
            entered=np.asarray(entered, dtype=bool),
            first_differing_s=np.asarray(firsts, dtype=np.float64),
        )
        account = ChannelAccount(
            aside=aside,
            repeated=(sides[0].repeated.get(topic, 0), sides[1].repeated.get(topic, 0)),
            outside=outside,
            stops_s=_stops(ts, end_ns, bin_ns),
        )
        if account != ChannelAccount():
            accounts[topic] = account
    return series, accounts


def _median_gap(acc: dict[str, ChannelBins]) -> float:
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
