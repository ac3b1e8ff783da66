"""Content that enters both runs at once: departures the diff passes over (docs/algorithms.md).

Two runs that differ in an entity differ on a channel from the moment that entity is in it.
When it is there from the first message, the difference is the series' level from the start
and no change point marks it. When it comes into view later, both runs are the same until
then and the series steps up at that bin; :func:`entries_to_pass` finds such steps, and
:func:`change_points_from` finds a channel's change points from its entry on.
"""

from __future__ import annotations

import math

import numpy as np

from rocas.analysis.changepoints import ChangePointConfig, ChangePoints, detect
from rocas.analysis.cmg import ChannelModuleGraph
from rocas.analysis.series import ChannelSeries

#: Longest a module takes to pass on content that entered its input [s]: about two cycles of
#: a 10 Hz pipeline. A module whose output gains elements later than this has decided
#: something (a planner's decision about an obstacle it has seen for a while), which is a
#: departure like any other.
ENTRY_LAG_S = 0.2


def entries_to_pass(
    series: dict[str, ChannelSeries], graph: ChannelModuleGraph
) -> dict[str, int]:
    """The channels whose first difference is content entering both runs, and the bin it
    entered at (an index into the channel's series).

    Two runs that differ in an entity differ on a channel from the moment that entity is in
    it. When it is there from the first message, the difference is the series' level from
    the start, and no change point marks it (the paper's premise: the first seconds are the
    baseline). When it comes into view later (an obstacle entering perception's range in
    both runs at the same tick, a bus in one and a truck in the other), the two executions
    are the same up to that tick, and the series steps up there. That step is the same
    difference met later: the executions' common start, not a module departing from the
    other run. So an entry (:attr:`ChannelSeries.entered` at the channel's first differing
    bin) is passed over, and the channel's change points are found from it on
    (:func:`change_points_from`), when it is the executions' first difference (no channel
    differs in an earlier bin), or when it follows, within :data:`ENTRY_LAG_S`, an entry
    passed over on a channel its writer reads (the entry travelling down the pipeline).
    Once a channel has differed in another way, no later entry is passed over.

    Returns:
        topic -> index of the bin where content entered it.
    """
    firsts: list[tuple[float, str, int | None]] = []
    for topic, s in series.items():
        differing = np.flatnonzero(s.mdr > 0)
        if len(differing) == 0:
            continue
        k = int(differing[0])
        entry = k if s.entered is not None and bool(s.entered[k]) else None
        firsts.append((float(s.times_s[k]), topic, entry))
    if not firsts:
        return {}
    firsts.sort()
    start = firsts[0][0]
    # the first difference that is not an entry ends the common start
    stop = min((t for t, _, entry in firsts if entry is None), default=math.inf)
    passed: dict[str, int] = {}
    for t, topic, entry in firsts:
        if entry is None or t > stop:
            continue
        inputs = [c for w in graph.writers_of(topic) for c in graph.channels_read_by(w)]
        if t == start or any(
            c in passed and t - series[c].times_s[passed[c]] <= ENTRY_LAG_S + 1e-9 for c in inputs
        ):
            passed[topic] = entry
    return passed


def entries_text(channels: dict[str, float], module: str | None) -> str:
    """One sentence on the departures passed over (``channels``: topic -> entry time [s]) and
    what the walk names without them."""
    parts = [f"{t} at {at:.2f} s" for t, at in sorted(channels.items(), key=lambda x: (x[1], x[0]))]
    return (f"content entered both runs and began to differ on {', '.join(parts)}, the runs "
            "being the same until then; with those departures passed over as the runs' common "
            f"start, the walk names {module or 'no module'}")


def change_points_from(s: ChannelSeries, cfg: ChangePointConfig, start: int) -> ChangePoints:
    """The change points of ``s`` found on its bins from index ``start`` on (indices into the
    whole series; the baseline window starts at that bin)."""
    if start == 0:
        return detect(s.mdr, s.times_s, cfg)
    cps = detect(s.mdr[start:], s.times_s[start:], cfg)
    return ChangePoints(cps.times_s, tuple(start + i for i in cps.indices), cps.penalty,
                        cps.noise_std, cps.rises)
