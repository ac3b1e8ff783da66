"""MDR series: two recordings streamed side by side, binned in time, channel by channel.

Both recordings are aligned at their first message (t = 0): the earliest log time in the
file's summary statistics, or the first message read when the file has no summary (a
truncated log). Time is cut into bins of ``bin_s`` seconds, centred on multiples of
``bin_s`` (bin j covers [(j - 1/2) bin_s, (j + 1/2) bin_s)): a periodic channel whose period
is a multiple of the bin width, published in phase with the first message (the common
case, e.g. 10 Hz with 0.1 s bins), then sits mid-bin, and timing jitter does not push its
messages across a bin edge in one recording only. Within a bin, the k-th message
of a channel in one recording pairs with the k-th message of that channel in the other;
a message without a partner scores 1; the bin's MDR is the mean over its messages.
Bins in which neither recording has a message on the channel carry no value.

One refinement, on unless ``adjacent_pairing=False`` (``--strict-bins``): messages left
unpaired in bin j pair, in order, with the *other* recording's messages left unpaired in
bin j + 1 before anything scores 1. A message published within its jitter of a bin edge
lands on different sides of the edge in the two runs; without this, such a channel scores
1 in almost every bin and its real deviation is invisible. The pair's MDR counts in bin j.

Memory stays flat: only the bins within ``reorder_window_s`` of the slower stream's
position are held.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rocas.analysis.mdr import EXACT, Tolerance, mdr
from rocas.errors import RecordingError
from rocas.recording.reader import ChannelInfo, DecodedMessage, Recording

ACCIDENT, REFERENCE = 0, 1


@dataclass(frozen=True)
class ChannelSeries:
    """The MDR series of one channel.

    Attributes:
        topic: channel topic.
        times_s: (n,) centre time of each bin that holds a message [s since alignment].
        mdr: (n,) MDR of each such bin, in [0, 1].
        messages: (n, 2) message counts per bin in (accident, reference).
        only_in: "accident" or "reference" when the channel exists in one recording only.
    """

    topic: str
    times_s: np.ndarray
    mdr: np.ndarray
    messages: np.ndarray
    only_in: str | None = None


@dataclass
class _Pending:
    """A bin whose score waits for the next bin (which may take its leftovers)."""

    index: int
    scores: list[float]
    leftover_side: int
    leftover: list[Any]
    counts: tuple[int, int]


@dataclass
class _Acc:
    bins: list[int] = field(default_factory=list)
    values: list[float] = field(default_factory=list)
    counts: list[tuple[int, int]] = field(default_factory=list)
    pending: _Pending | None = None

    def finish_pending(self) -> None:
        p = self.pending
        if p is None:
            return
        n = len(p.scores) + len(p.leftover)
        if n:
            self.bins.append(p.index)
            self.values.append((sum(p.scores) + len(p.leftover)) / n)
            self.counts.append(p.counts)
        self.pending = None

    def add_bin(
        self, index: int, a_msgs: list[Any], b_msgs: list[Any], tol: Tolerance, adjacent: bool
    ) -> None:
        """Score bin ``index`` (bins arrive in increasing order)."""
        paired = min(len(a_msgs), len(b_msgs))
        scores = [mdr(x, y, tol) for x, y in zip(a_msgs[:paired], b_msgs[:paired], strict=True)]
        side = ACCIDENT if len(a_msgs) > paired else REFERENCE
        leftover = (a_msgs if side == ACCIDENT else b_msgs)[paired:]
        counts = (len(a_msgs), len(b_msgs))
        p = self.pending
        if (
            adjacent and p is not None and p.index == index - 1 and p.leftover and leftover
            and p.leftover_side != side
        ):
            k = min(len(p.leftover), len(leftover))
            for x, y in zip(p.leftover[:k], leftover[:k], strict=True):
                a, b = (x, y) if p.leftover_side == ACCIDENT else (y, x)
                p.scores.append(mdr(a, b, tol))
            p.leftover = p.leftover[k:]
            leftover = leftover[k:]
        self.finish_pending()
        self.pending = _Pending(index, scores, side, leftover, counts)


@dataclass(frozen=True)
class SeriesResult:
    """All channels' series plus what was read.

    Attributes:
        series: topic -> ChannelSeries, sorted by topic.
        channels: topic -> (accident ChannelInfo | None, reference ChannelInfo | None).
        messages_read: (accident, reference) decoded message counts.
        bin_s: bin width [s].
    """

    series: dict[str, ChannelSeries]
    channels: dict[str, tuple[ChannelInfo | None, ChannelInfo | None]]
    messages_read: tuple[int, int]
    bin_s: float




def compute_series(
    accident: Recording,
    reference: Recording,
    *,
    bin_s: float = 0.1,
    tolerance: Tolerance = EXACT,
    reorder_window_s: float = 1.0,
    adjacent_pairing: bool = True,
) -> SeriesResult:
    """Stream both recordings and compute each channel's MDR series.

    Raises:
        RecordingError: a topic's schema differs between the two files.
    """
    if not (bin_s > 0 and math.isfinite(bin_s)):
        raise ValueError("bin_s must be a positive number of seconds")
    window_bins = max(1, math.ceil(reorder_window_s / bin_s))
    starts = [accident.summary_start_time_ns(), reference.summary_start_time_ns()]
    channels: dict[str, list[ChannelInfo | None]] = {}
    open_bins: dict[int, dict[str, tuple[list[Any], list[Any]]]] = {}
    acc: dict[str, _Acc] = {}
    read = [0, 0]
    bin_ns = bin_s * 1e9

    def bin_of(side: int, msg: DecodedMessage) -> int:
        if starts[side] is None:
            starts[side] = msg.log_time_ns
        return max(0, math.floor((msg.log_time_ns - starts[side]) / bin_ns + 0.5))

    def note_channel(side: int, info: ChannelInfo) -> None:
        pair = channels.get(info.topic)
        if pair is None:
            pair = channels[info.topic] = [None, None]
        known = pair[side]
        if known is None or known.id != info.id:
            other = pair[1 - side]
            if other is not None and (
                other.schema_name != info.schema_name or other.schema_data != info.schema_data
                or other.message_encoding != info.message_encoding
            ):
                raise RecordingError(
                    f"channel {info.topic} has a different schema in the two recordings "
                    f"({_schema_label(pair[ACCIDENT] or info)} vs "
                    f"{_schema_label(pair[REFERENCE] or info)})",
                    "compare recordings of the same stack version",
                )
            pair[side] = info

    def flush(below: int) -> None:
        for b in sorted(k for k in open_bins if k < below):
            for topic, (xs, ys) in open_bins.pop(b).items():
                acc.setdefault(topic, _Acc()).add_bin(b, xs, ys, tolerance, adjacent_pairing)

    streams: list[Iterator[DecodedMessage]] = [accident.decoded(), reference.decoded()]
    heads: list[DecodedMessage | None] = [next(streams[0], None), next(streams[1], None)]
    head_bins = [bin_of(s, h) if h is not None else math.inf for s, h in enumerate(heads)]
    since_flush = 0
    while heads[0] is not None or heads[1] is not None:
        side = ACCIDENT if head_bins[ACCIDENT] <= head_bins[REFERENCE] else REFERENCE
        msg = heads[side]
        assert msg is not None
        b = int(head_bins[side])
        note_channel(side, msg.channel)
        slot = open_bins.setdefault(b, {}).setdefault(msg.channel.topic, ([], []))
        slot[side].append(msg.message)
        read[side] += 1
        nxt = next(streams[side], None)
        heads[side] = nxt
        head_bins[side] = bin_of(side, nxt) if nxt is not None else math.inf
        since_flush += 1
        if since_flush >= 256:
            since_flush = 0
            low = min(head_bins)
            if low != math.inf:
                flush(int(low) - window_bins)
    flush(2**62)
    for a in acc.values():
        a.finish_pending()

    series: dict[str, ChannelSeries] = {}
    for topic in sorted(channels):
        pair = channels[topic]
        only = None
        if pair[ACCIDENT] is None:
            only = "reference"
        elif pair[REFERENCE] is None:
            only = "accident"
        a = acc.get(topic, _Acc())
        order = np.argsort(np.asarray(a.bins, dtype=np.int64), kind="stable")
        series[topic] = ChannelSeries(
            topic=topic,
            times_s=np.asarray(a.bins, dtype=np.float64)[order] * bin_s,
            mdr=np.asarray(a.values, dtype=np.float64)[order],
            messages=np.asarray(a.counts, dtype=np.int64).reshape(-1, 2)[order],
            only_in=only,
        )
    return SeriesResult(
        series=series,
        channels={t: (p[0], p[1]) for t, p in channels.items()},
        messages_read=(read[0], read[1]),
        bin_s=bin_s,
    )


def _schema_label(info: ChannelInfo) -> str:
    return f"{info.message_encoding}:{info.schema_name or '<no schema>'}"
