"""Differential analysis (Phase III): two recordings -> the initial deviating module."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rocas.analysis.align import Alignment, describe
from rocas.analysis.align import align as align_recordings
from rocas.analysis.changepoints import ChangePointConfig, ChangePoints, detect
from rocas.analysis.checks import account_warnings, check_pair, span_warnings
from rocas.analysis.cmg import (
    MODULE,
    ChannelModuleGraph,
    CmgSpec,
    build_cmg,
    control_channel,
    declares_topology,
    load_cmg,
    no_topology_hint,
)
from rocas.analysis.entries import change_points_from, entries_to_pass
from rocas.analysis.mdr import Tolerance
from rocas.analysis.noise import FieldRules
from rocas.analysis.pinpoint import PinpointResult, find_initial_module, past_the_window
from rocas.analysis.series import ChannelAccount, ChannelSeries, SeriesResult, compute_series
from rocas.errors import RecordingError, TopologyError, UsageError
from rocas.recording.decoding import DecoderCache
from rocas.recording.formats import open_recording
from rocas.recording.model import ChannelInfo
from rocas.recording.reader import Recording

REORDER_WINDOW_S = 1.0  # how far out of log-time order a message may be written for one pass [s]


@dataclass(frozen=True)
class ChannelDiff:
    """One channel's row of the diff report.

    Attributes:
        topic: channel topic.
        writers: modules writing it; readers: modules reading it.
        series: its MDR series.
        change_points: its change points (t* = ``change_points.first_s``).
        mdr_before: mean MDR before t* (whole series when there is no t*); None if empty.
        mdr_after: mean MDR from t* on; None without t*.
        only_in: "accident"/"reference" for a channel present in one recording only.
        schema: the schema name.
        entered_s: when content entered the channel in both runs at once, the two runs being
            the same until then (:func:`entries_to_pass`) [s]; None otherwise.
        after_entry: the change points found from that bin on (None without an entry).
    """

    topic: str
    writers: tuple[str, ...]
    readers: tuple[str, ...]
    series: ChannelSeries
    change_points: ChangePoints
    mdr_before: float | None
    mdr_after: float | None
    only_in: str | None
    schema: str
    entered_s: float | None = None
    after_entry: ChangePoints | None = None

    @property
    def change_point_s(self) -> float | None:
        return self.change_points.first_s


@dataclass(frozen=True)
class DiffResult:
    """The result of :func:`diff`, rendered by the CLI (table, JSON, Rerun).

    Attributes:
        accident: path of the accident recording; reference: of the reference recording.
        channels: one ChannelDiff per topic, sorted by topic.
        cmg: the channel-module graph used.
        pinpoint: Algorithm 1's result (deviating module, walk, removed edges).
        bin_s: bin width [s]; delta_s: Algorithm 1's window [s].
        messages_read: decoded messages (accident, reference).
        warnings: damage and skips found while reading, one line each.
        entries: Algorithm 1's result with the departures where content entered both runs
            passed over (:func:`entries_to_pass`), when there were any; None otherwise.
        control_onset_s: the time of the control channel's first differing bin [s] (None:
            its messages are the same in both recordings).
        alignment: how the reference was put on the accident's clock.
        compared_s: (start, end) of the span both recordings cover [s since t = 0].
        accounts: topic -> messages set aside, repeated or outside the span, and where a
            channel falls silent (channels with something to report).
        rules: topic -> how its messages were compared (fields set aside, learned float
            tolerances), for the channels that have any.
        noisy_start: the two runs differ at their start (learning was on).
        first_differing_s: topic -> log time of the first differing message in the bin of its
            t* [s] (orders modules whose change points share a bin).
        last_alike_s: topic -> its last compared bin before t*, where that is more than a bin
            before (its departure lies anywhere after it) [s].
        timing_s: how far apart the two runs log one message [s] (0 on one tick).
    """

    accident: str
    reference: str
    channels: tuple[ChannelDiff, ...]
    cmg: ChannelModuleGraph
    pinpoint: PinpointResult
    bin_s: float
    delta_s: float
    messages_read: tuple[int, int]
    warnings: tuple[str, ...] = field(default=())
    entries: PinpointResult | None = None
    control_onset_s: float | None = None
    alignment: Alignment | None = None
    compared_s: tuple[float, float] | None = None
    accounts: dict[str, ChannelAccount] = field(default_factory=dict)
    rules: dict[str, FieldRules] = field(default_factory=dict)
    noisy_start: bool = False
    first_differing_s: dict[str, float] = field(default_factory=dict)
    last_alike_s: dict[str, float] = field(default_factory=dict)
    timing_s: float = 0.0

    def comparison_notes(self) -> list[str]:
        """How the two recordings were compared: the alignment, the span, and what the start
        taught (fields set aside, learned tolerances), one line each."""
        lines = []
        if self.alignment is not None:
            lines.append(f"Aligned: {describe(self.alignment)}.")
        if self.compared_s is not None:
            lo, hi = self.compared_s
            lines.append(f"Compared: {lo:.2f}-{hi:.2f} s (the span both recordings cover).")
        ignored = self.ignored_fields
        if ignored:
            n = sum(len(p) for p in ignored.values())
            shown = "; ".join(f"{t}: {', '.join(p[:4])}{' ...' if len(p) > 4 else ''}"
                              for t, p in list(ignored.items())[:4])
            lines.append(f"Set aside ({n} fields that differ in nearly every message of the shared "
                         f"start: stamps, counters, ids): {shown}"
                         + (f"; and {len(ignored) - 4} more channels" if len(ignored) > 4 else "")
                         + ".")
        tol = self.learned_tolerances
        if tol:
            n = sum(len(p) for p in tol.values())
            lines.append(f"Noise learned from the shared start: {n} float fields on {len(tol)} "
                         "channels compared within twice their largest difference there "
                         "(--json lists them; --exact turns this off).")
        return lines

    @property
    def ignored_fields(self) -> dict[str, tuple[str, ...]]:
        """topic -> the leaf paths left out of its messages (learned or asked for)."""
        return {t: tuple(sorted(r.ignored)) for t, r in sorted(self.rules.items()) if r.ignored}

    @property
    def learned_tolerances(self) -> dict[str, dict[str, float]]:
        """topic -> leaf path -> the absolute tolerance learned from the shared start."""
        return {t: dict(sorted(r.atol.items())) for t, r in sorted(self.rules.items()) if r.atol}

    @property
    def deviating_module(self) -> str | None:
        return self.pinpoint.deviating_module

    @property
    def control_channel(self) -> str:
        return self.pinpoint.control_channel

    @property
    def named_at_entry(self) -> bool:
        """Whether Algorithm 1's module departs first where content entered both runs: its
        t* is the entry time of a channel it writes whose entry was passed over."""
        m = self.pinpoint.deviating_module
        t = self.pinpoint.t_star.get((MODULE, m)) if m else None
        return t is not None and any(
            m in c.writers and c.entered_s is not None and abs(c.entered_s - t) < 1e-9
            for c in self.channels)

    def walk_without(self, modules: Collection[str], past_entries: bool = False) -> PinpointResult:
        """Algorithm 1 again, with every channel that ``modules`` write (other than the
        control channel) counted as not departed: the walk another method's evidence asks for
        when it rules those modules out as the accident's cause (module substitution: their
        ground truth leaves the accident in place). ``past_entries``: each channel's change
        point after content entered both runs, as :attr:`entries` walks. The channels' change
        points are the diff's; nothing is read again."""
        quiet = {c for m in modules for c in self.cmg.channels_written_by(m)} - {self.control_channel}
        return find_initial_module(self.cmg, self._t_star(quiet, past_entries), self.control_channel,
                                   self.delta_s, control_onset_s=self.control_onset_s,
                                   bin_s=self.bin_s, first_differing_s=self.first_differing_s,
                                   last_alike_s=self.last_alike_s, timing_s=self.timing_s)

    def walk_past_window(self, written_by: Collection[str], reach_s: float | None = None
                         ) -> PinpointResult:
        """Algorithm 1's walk continued from an input of the module it named that a module of
        ``written_by`` writes and that departed before the window (at most ``reach_s`` before
        the module, when given; :func:`~rocas.analysis.pinpoint.past_the_window`); Algorithm
        1's own result when there is none."""
        if self.pinpoint.deviating_module is None:
            return self.pinpoint
        return past_the_window(self.cmg, self._t_star(), self.pinpoint, self.delta_s, written_by,
                               reach_s)

    def _t_star(self, quiet: Collection[str] = (), past_entries: bool = False
                ) -> dict[str, float | None]:
        """Each channel's first change point [s] (after content entered both runs, with
        ``past_entries``), None for the channels of ``quiet``."""
        def t(c: ChannelDiff) -> float | None:
            if past_entries and c.after_entry is not None:
                return c.after_entry.first_s
            return c.change_point_s

        return {c.topic: (None if c.topic in quiet else t(c)) for c in self.channels}

    @property
    def complete(self) -> bool:
        """Whether the answer used the whole of both recordings and nothing in them needed a
        warning (False whenever :attr:`warnings` has a line)."""
        return not self.warnings

    def to_json(self) -> dict[str, Any]:
        """The ``--json`` object (keys documented in docs/cli.md)."""
        p = self.pinpoint
        return {
            "deviating_module": p.deviating_module,
            "complete": self.complete,
            "control_channel": p.control_channel,
            "path": list(p.path),
            "fallback": p.fallback,
            "delta_s": self.delta_s,
            "bin_s": self.bin_s,
            "accident": self.accident,
            "reference": self.reference,
            "channels": [
                {
                    "topic": c.topic,
                    "writers": list(c.writers),
                    "readers": list(c.readers),
                    "schema": c.schema,
                    "change_point_s": c.change_point_s,
                    "change_points_s": list(c.change_points.times_s),
                    "entered_s": c.entered_s,
                    "change_point_after_entry_s": (c.after_entry.first_s
                                                   if c.after_entry is not None else None),
                    "mdr_before": c.mdr_before,
                    "mdr_after": c.mdr_after,
                    "only_in": c.only_in,
                    "bins": len(c.series.mdr),
                    "penalty": c.change_points.penalty,
                    "noise_std": c.change_points.noise_std,
                    "converges_s": list(c.change_points.converges_s),
                }
                for c in self.channels
            ],
            "modules": [
                {
                    "name": m,
                    "change_point_s": p.t_star.get((MODULE, m)),
                    "reachable": m in p.reachable,
                    "excluded_because": p.exclusions.get(m),
                }
                for m in self.cmg.modules
            ],
            "removed_edges": [
                {"from": e.source[1], "to": e.target[1], "reason": e.reason}
                for e in p.removed_edges
            ],
            "entries": None if self.entries is None else {
                "deviating_module": self.entries.deviating_module,
                "path": list(self.entries.path),
                "fallback": self.entries.fallback,
                "named_at_entry": self.named_at_entry,
                "channels": {c.topic: c.entered_s for c in self.channels
                             if c.entered_s is not None},
            },
            "messages_read": {"accident": self.messages_read[0],
                              "reference": self.messages_read[1]},
            "alignment": None if self.alignment is None else self.alignment.to_json(),
            "compared_s": None if self.compared_s is None else list(self.compared_s),
            "noisy_start": self.noisy_start,
            "ignored_fields": {t: list(p) for t, p in self.ignored_fields.items()},
            "learned_tolerances": self.learned_tolerances,
            "messages_set_aside": {
                t: {"without_partner": list(a.aside), "repeated": list(a.repeated),
                    "outside_span": list(a.outside),
                    "falls_silent_s": {"accident": a.stops_s[0], "reference": a.stops_s[1]}}
                for t, a in sorted(self.accounts.items())},
            "warnings": list(self.warnings),
        }


#: a channel without change points whose mean MDR is this many noise deviations above zero
#: has departed at its first differing bin
BASELINE_DEPARTURE_SIGMAS = 3.0


def _means(values: np.ndarray, cps: ChangePoints) -> tuple[float | None, float | None]:
    if len(values) == 0:
        return None, None
    k = cps.first_index
    if k is None:
        return float(values.mean()), None
    return float(values[:k].mean()), float(values[k:].mean())


def _schema_name(pair: tuple[ChannelInfo | None, ChannelInfo | None]) -> str:
    info = pair[0] or pair[1]
    return info.schema_name if info else ""


def _channels_for_topology(
    accident: str, acc: list[ChannelInfo], reference: str, ref: list[ChannelInfo],
    *, has_cmg: bool,
) -> tuple[list[ChannelInfo], tuple[str, ...]]:
    """The channel declarations the CMG is built from, and a note when the reference's
    topology stands in for the accident's.

    The accident's declarations come first (a topic only the reference has takes the
    reference's). The topology is a property of the stack, not of one run, so when the
    accident declares none and the reference does, the reference's is used if the two
    recordings have the same channels; with different channels it would be a guess, and
    (without a --cmg file) the accident is refused with an error that says so.
    """
    topics_a = {c.topic for c in acc}
    topics_b = {c.topic for c in ref}
    both = acc + [c for c in ref if c.topic not in topics_a]
    if declares_topology(acc) or not declares_topology(ref):
        return both, ()
    if topics_a == topics_b:
        return ref, (
            f"{accident} declares no channel topology; using the one {reference} declares "
            "(the two recordings have the same channels)",
        )
    if has_cmg:  # the file supplies what it names; the rest as usual
        return both, ()
    only = [
        f"only in the {role}: {', '.join(sorted(topics))}"
        for role, topics in (("accident", topics_a - topics_b), ("reference", topics_b - topics_a))
        if topics
    ]
    raise TopologyError(
        f"{accident} declares no channel topology, and the one {reference} declares does not "
        f"apply to it because their channels differ ({'; '.join(only)})",
        no_topology_hint(f"'rocas cmg {reference} --format json' prints the reference's in "
                         "that format, to complete"),
    )


def diff(
    accident: str | os.PathLike[str],
    reference: str | os.PathLike[str],
    *,
    cmg: str | os.PathLike[str] | CmgSpec | None = None,
    control_channel_topic: str | None = None,
    bin_s: float = 0.1,
    delta_s: float = 3.0,
    atol: float = 0.0,
    rtol: float = 0.0,
    change_points: ChangePointConfig | None = None,
    strict_bins: bool = False,
    allow_unrelated: bool = False,
    progress: Callable[[int, int], None] | None = None,
    align: str = "auto",
    ignore_fields: Sequence[str] = (),
    learn_noise: bool = True,
) -> DiffResult:
    """Diff two recordings channel by channel and find the initial deviating module.

    Args:
        accident: the accident recording (its channel metadata gives the topology; when it
            declares none, the reference's is used if both have the same channels).
        reference: the accident-free reference recording.
        cmg: a CMG JSON path or parsed spec that supplies or overrides the topology.
        control_channel_topic: the channel Algorithm 1 starts from (overrides metadata).
        bin_s: bin width of the MDR series [s].
        delta_s: Algorithm 1's reaction window [s].
        atol: absolute tolerance for floating-point leaves.
        rtol: relative tolerance for floating-point leaves.
        change_points: change point detection settings.
        strict_bins: pair messages only within their own bin (no adjacent-bin pairing).
        allow_unrelated: diff a pair that does not look like two runs of the same thing
            (:func:`check_pair`) with a warning instead of refusing it.
        progress: called now and then with (bytes read, bytes in both files) while the
            recordings are read.
        align: how the reference is put on the accident's clock: "auto" (by identical
            messages, else by each channel's first message), "first" (each file's first
            message), "log-time" (no offset) or a topic (its first message in each file);
            :mod:`rocas.analysis.align`.
        ignore_fields: leaf paths to leave out of every message (``PATH`` or ``TOPIC:PATH``,
            shell wildcards), besides those learned.
        learn_noise: on a pair noisy at its start, learn per field what "the same" means
            there (:mod:`rocas.analysis.noise`); False: the paper's exact MDR.

    Raises:
        InputError: unreadable recordings or CMG file, schema mismatches, a pair that is not
            two runs of the same thing, a recording without a stretch of time to compare.
        TopologyError: no topology, or no control channel.
    """
    _check_settings(bin_s, delta_s, atol, rtol)
    spec = load_cmg(cmg) if isinstance(cmg, (str, os.PathLike)) else cmg
    cfg = change_points or ChangePointConfig()
    rec_a, rec_b = _open_pair(accident, reference, control_channel_topic, spec)
    read = _read_pair(rec_a, rec_b, Tolerance(atol, rtol), cfg, bin_s=bin_s, align=align,
                      ignore_fields=ignore_fields, learn_noise=learn_noise,
                      adjacent=not strict_bins, progress=progress)
    res, alignment = read.series, read.alignment
    _refuse_nothing_to_compare(res, alignment, (accident, rec_a), (reference, rec_b))
    topology = _topology(accident, rec_a, reference, rec_b, spec, control_channel_topic)
    pair_warnings = check_pair(res, str(accident), str(reference), cfg,
                               allow_unrelated=allow_unrelated,
                               intact=rec_a.report.intact and rec_b.report.intact)
    rows = _channel_rows(res, topology.graph, topology.control, cfg)
    walks = _walks(res, rows, topology.graph, topology.control, delta_s, bin_s)
    warnings = tuple(rec_a.report.warnings(str(accident)) + rec_b.report.warnings(str(reference)))
    warnings += res.warnings + pair_warnings + topology.warnings
    warnings += _pass_warnings(res, rows.rows, alignment, str(accident), str(reference))
    return DiffResult(
        accident=str(accident), reference=str(reference), channels=rows.rows,
        cmg=topology.graph, pinpoint=walks.pinpoint, bin_s=bin_s, delta_s=delta_s,
        messages_read=res.messages_read, warnings=warnings, entries=walks.entries,
        control_onset_s=walks.control_onset_s, alignment=alignment, compared_s=res.compared_s,
        accounts=res.accounts, rules=read.rules, noisy_start=read.noisy,
        first_differing_s=walks.first_differing_s, last_alike_s=walks.last_alike_s,
        timing_s=res.timing_s,
    )


def _check_settings(bin_s: float, delta_s: float, atol: float, rtol: float) -> None:
    """Refuse a bin width, window or tolerance out of range (UsageError)."""
    if not bin_s > 0:
        raise UsageError(f"--bin must be positive, got {bin_s:g}")
    if not delta_s >= 0:
        raise UsageError(f"--delta must be zero or positive, got {delta_s:g}")
    if atol < 0 or rtol < 0:
        raise UsageError("--atol and --rtol must be zero or positive")


def _open_pair(accident: str | os.PathLike[str], reference: str | os.PathLike[str],
               control_channel_topic: str | None, spec: CmgSpec | None
               ) -> tuple[Recording, Recording]:
    """Open both recordings (one decoder cache), and refuse a control channel (asked for, or
    named by the CMG file) that neither summary lists before anything is read."""
    decoders = DecoderCache()
    rec_a: Recording = open_recording(accident, decoders)
    rec_b: Recording = open_recording(reference, decoders)
    for chosen, origin in ((control_channel_topic, "--control-channel"),
                           (spec and spec.control_channel, spec and spec.path)):
        if chosen:
            _refuse_unknown_channel_early(chosen, str(origin), rec_a, rec_b, both_names=(
                f"{accident} or {reference}"))
    return rec_a, rec_b


@dataclass(frozen=True)
class _Read:
    """The pair as read: how the reference was put on the accident's clock, topic -> how its
    messages were compared, whether the pair is noisy at its start, and the MDR series."""

    alignment: Alignment
    rules: dict[str, FieldRules]
    noisy: bool
    series: SeriesResult


def _read_pair(rec_a: Recording, rec_b: Recording, tolerance: Tolerance,
               cfg: ChangePointConfig, *, bin_s: float, align: str,
               ignore_fields: Sequence[str], learn_noise: bool, adjacent: bool,
               progress: Callable[[int, int], None] | None) -> _Read:
    """Align the pair, learn from its start how to compare it, and stream it into series
    (the alignment's warnings first among the series' warnings)."""
    alignment, rules, noisy, align_warnings, resume = align_recordings(
        rec_a, rec_b, method=align, bin_s=bin_s, baseline_s=cfg.baseline_s,
        tolerance=None if tolerance.exact else tolerance, learn=learn_noise,
        ignore=ignore_fields)
    res = compute_series(
        rec_a, rec_b, bin_s=bin_s, tolerance=tolerance,
        reorder_window_s=REORDER_WINDOW_S, adjacent_pairing=adjacent, progress=progress,
        alignment=alignment, rules=rules, resume=resume,
    )
    res = dataclasses.replace(res, warnings=align_warnings + res.warnings)
    return _Read(alignment, rules, noisy, res)


def _refuse_nothing_to_compare(res: Any, alignment: Alignment,
                               accident: tuple[str | os.PathLike[str], Recording],
                               reference: tuple[str | os.PathLike[str], Recording]) -> None:
    """Refuse a pair with a recording that holds no readable message, or whose two files (on
    one clock, as aligned) share no span of time (RecordingError). ``accident``,
    ``reference``: (path, recording)."""
    empty = [
        (role, path, rec)
        for role, (path, rec), n in (("accident", accident, res.messages_read[0]),
                                     ("reference", reference, res.messages_read[1]))
        if n == 0
    ]
    if empty:
        # one recording without a message would make every channel "only in" the other,
        # each with MDR 1, and the verdict would be about the file, not the accident
        damage = [w for _, path, rec in empty for w in rec.report.warnings(str(path))]
        what = (
            "neither recording holds a readable message" if len(empty) == 2
            else f"the {empty[0][0]} recording {empty[0][1]} holds no readable message"
        )
        raise RecordingError(
            what + (f": {damage[0]}" if damage else ""),
            f"check the {'files' if len(empty) == 2 else 'file'} with 'mcap info'",
        )
    if res.compared_s[1] <= 0 and min(res.span_s) > 0:
        # the two files (on one clock, as aligned) do not overlap: nothing can be compared
        raise RecordingError(
            f"{accident[0]} and {reference[0]} share no span of time: aligned as "
            f"{describe(alignment)}, the {'reference' if alignment.starts_s[1] >= 0 else 'accident'}"
            f" starts after the other ends (the accident covers "
            f"{alignment.starts_s[0]:.2f} to {res.ends_s[0]:.2f} s, the reference "
            f"{alignment.starts_s[1]:.2f} to {res.ends_s[1]:.2f} s)",
            "diff recordings of the same drive; if they are on one clock with no identical "
            "message, try --align first or --align log-time",
        )


@dataclass(frozen=True)
class _Topology:
    """The pair's channel-module graph, the channel Algorithm 1 starts from, and the warning
    lines building them gave (channels a --cmg file names that neither recording has, the
    reference's topology standing in for the accident's)."""

    graph: ChannelModuleGraph
    control: str
    warnings: tuple[str, ...]


def _topology(accident: str | os.PathLike[str], rec_a: Recording,
              reference: str | os.PathLike[str], rec_b: Recording, spec: CmgSpec | None,
              control_channel_topic: str | None) -> _Topology:
    """The CMG from the recordings' channel declarations (``spec`` supplying or overriding
    them), and its control channel."""
    channel_infos, topology_note = _channels_for_topology(
        str(accident), list(rec_a.channels.values()),
        str(reference), list(rec_b.channels.values()),
        has_cmg=spec is not None,
    )
    both = f"{accident} or {reference}"
    cmg_warnings: list[str] = []
    if spec is not None:
        recorded = {c.topic for c in channel_infos}
        cmg_warnings = spec.missing_channel_warnings(recorded, both)
        spec = spec.restricted_to(recorded)
    graph = build_cmg(channel_infos, spec, where=both)
    ctrl = control_channel(graph, control_channel_topic, spec, where=both)
    return _Topology(graph, ctrl, tuple(cmg_warnings) + topology_note)


@dataclass(frozen=True)
class _Rows:
    """Each channel's row, with the t* Algorithm 1 walks on: ``t_star`` topic -> first
    departure [s] (None: none), ``t_after`` the same past the bins where content entered
    both runs, and ``entries`` topic -> the bin index of such an entry."""

    rows: tuple[ChannelDiff, ...]
    t_star: dict[str, float | None]
    t_after: dict[str, float | None]
    entries: dict[str, int]


def _channel_rows(res: Any, graph: ChannelModuleGraph, ctrl: str, cfg: ChangePointConfig
                  ) -> _Rows:
    """Each channel's change points, departure and row of the report, in topic order."""
    rows: list[ChannelDiff] = []
    t_star: dict[str, float | None] = {}
    entries = entries_to_pass(res.series, graph)
    t_after: dict[str, float | None] = {}
    for topic, s in res.series.items():
        cps = detect(s.mdr, s.times_s, cfg)
        t_star[topic] = t_after[topic] = _departure(s, cps, is_control=topic == ctrl)
        entry = entries.get(topic)
        after = None if entry is None else change_points_from(s, cfg, entry)
        if after is not None:
            t_after[topic] = after.first_s
        before, after_mean = _means(s.mdr, cps)
        topo = graph.topology.get(topic)
        rows.append(
            ChannelDiff(
                topic=topic,
                writers=topo.writers if topo else (),
                readers=topo.readers if topo else (),
                series=s,
                change_points=cps,
                mdr_before=before,
                mdr_after=after_mean,
                only_in=s.only_in,
                schema=_schema_name(res.channels[topic]),
                entered_s=None if entry is None else float(s.times_s[entry]),
                after_entry=after,
            )
        )
    return _Rows(tuple(rows), t_star, t_after, entries)


def _departure(s: ChannelSeries, cps: ChangePoints, is_control: bool) -> float | None:
    """When a channel departed [s]: its first change point; without one (the control channel
    aside), its first differing bin when the runs start alike and then differ well above the
    channel's noise (its baseline holds the departure, which the window can then see). A pair
    noisy from its first bin on (another stack's sensors) is left alone, and a channel whose
    only change points fall (the runs converging) has no departure."""
    if cps.times_s or is_control:
        return cps.first_s
    nz = np.flatnonzero(s.mdr > 0)
    base = float(np.mean(s.mdr)) if len(s.mdr) else 0.0
    if len(nz) and nz[0] > 0 and base >= BASELINE_DEPARTURE_SIGMAS * cps.noise_std > 0:
        return float(s.times_s[nz[0]])
    return cps.first_s


@dataclass(frozen=True)
class _Walks:
    """Algorithm 1's result, and its result past content entries (None without any), with
    what they were given: the control channel's first differing bin [s] (None: its messages
    are the same) and topic -> the first differing message / the last alike bin [s]."""

    pinpoint: PinpointResult
    entries: PinpointResult | None
    control_onset_s: float | None
    first_differing_s: dict[str, float]
    last_alike_s: dict[str, float]


def _walks(res: Any, rows: _Rows, graph: ChannelModuleGraph, ctrl: str, delta_s: float,
           bin_s: float) -> _Walks:
    """Algorithm 1 on the channels' departures, and again past content entries."""
    ctrl_series = res.series.get(ctrl)
    differing = np.flatnonzero(ctrl_series.mdr > 0) if ctrl_series is not None else ()
    onset = float(ctrl_series.times_s[differing[0]]) if len(differing) else None
    within = _first_differing(res.series, rows.t_star)
    alike = _last_alike(res.series, rows.t_star, bin_s)
    pin = find_initial_module(graph, rows.t_star, ctrl, delta_s, control_onset_s=onset,
                              bin_s=bin_s, first_differing_s=within, last_alike_s=alike,
                              timing_s=res.timing_s)
    pin_entries = None
    if rows.entries:
        pin_entries = find_initial_module(
            graph, rows.t_after, ctrl, delta_s, control_onset_s=onset, bin_s=bin_s,
            first_differing_s=_first_differing(res.series, rows.t_after),
            last_alike_s=_last_alike(res.series, rows.t_after, bin_s),
            timing_s=res.timing_s)
    return _Walks(pin, pin_entries, onset, within, alike)


def _pass_warnings(res: Any, rows: tuple[ChannelDiff, ...], alignment: Alignment,
                   accident: str, reference: str) -> tuple[str, ...]:
    """What the comparison left out or had to widen: channels in one recording only, what
    lies outside the shared span, messages set aside, and a wider reorder window."""
    warnings = tuple(
        f"channel {c.topic} is only in the {c.only_in} recording" for c in rows if c.only_in
    )
    warnings += span_warnings(res, alignment, accident, reference)
    warnings += account_warnings(res)
    if res.reorder_window_s > REORDER_WINDOW_S:
        warnings += tuple(
            f"{path}: messages are written up to {late:.1f} s out of log-time order; paired "
            f"with a {res.reorder_window_s:.1f} s reorder window instead of "
            f"{REORDER_WINDOW_S:g} s (more memory, another pass over the files)"
            for path, late in zip((accident, reference), res.disorder_s, strict=True)
            if late > REORDER_WINDOW_S
        )
    return warnings


def _last_alike(series: dict[str, ChannelSeries], t_star: dict[str, float | None],
                bin_s: float) -> dict[str, float]:
    """topic -> the last compared bin before its t* when it is more than one bin before (a
    gap: messages lost or set aside there, or a channel slower than the bins) [s]."""
    out = {}
    for topic, t in t_star.items():
        s = series.get(topic)
        if t is None or s is None or not len(s.times_s):
            continue
        k = int(np.searchsorted(s.times_s, t - 1e-9))
        if 0 < k <= len(s.times_s) and t - s.times_s[k - 1] > bin_s * 1.5:
            out[topic] = float(s.times_s[k - 1])
    return out


def _first_differing(series: dict[str, ChannelSeries], t_star: dict[str, float | None]
                     ) -> dict[str, float]:
    """topic -> the log time of the first differing message in the bin of its t* [s]."""
    out = {}
    for topic, t in t_star.items():
        s = series.get(topic)
        if t is None or s is None or s.first_differing_s is None or not len(s.times_s):
            continue
        k = int(np.searchsorted(s.times_s, t - 1e-9))
        if k < len(s.times_s) and abs(s.times_s[k] - t) < 1e-9 \
                and np.isfinite(s.first_differing_s[k]):
            out[topic] = float(s.first_differing_s[k])
    return out


def _refuse_unknown_channel_early(
    topic: str, origin: str, rec_a: Recording, rec_b: Recording, both_names: str
) -> None:
    """Refuse a control channel that neither recording's summary lists, before reading them.

    Only summaries that pass their checks are consulted; without them the check happens
    after the pass, as before.
    """
    listed: set[str] = set()
    for rec in (rec_a, rec_b):
        summary, _ = rec.summary()
        if summary is None or not summary.channels:
            return
        listed |= {ch.topic for ch in summary.channels.values()}
    if topic not in listed:
        raise TopologyError(
            f"control channel {topic!r} (from {origin}) is not in {both_names}",
            f"choose one of: {', '.join(sorted(listed))}",
        )
