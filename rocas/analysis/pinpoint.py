"""Algorithm 1 of the paper: pinpoint the initial deviating module on the CMG.

1. t*(channel) is the channel's first change point (None when it never deviated);
   t*(module) is the earliest t* among the channels the module writes.
2. Every edge (u, v) is removed unless t*(u) lies in [t*(v) - delta, t*(v)]; an edge
   with an undefined t* on either end is removed.
3. From the control channel, walk the reversed graph; the deviating module is the
   reachable module with the earliest t*. Ties (modules whose change points fall into the
   same bin, as when a whole pipeline reacts within one tick) go to the module farthest
   upstream along the walk, since deviations travel downstream; then by name.

When the control channel itself has no change point, step 3 has no start: either the ego's
commands were the same in both executions (the deviation upstream never reached the
actuators, as when the ego stands with its emergency stop on in both), or they differ from the
first messages on, so their difference is the channel's baseline (as when the trigger actor is
in view and decides the ego's first move). The walk then starts from the whole set of modules
the control channel depends on, unpruned (the channels between them differ from the start as
well, without change points), less the modules that read the control channel (they report the
vehicle's response to the commands, as the chassis does). When the commands differ, only a
module whose change point falls within the window before their first differing bin can
explain it. The answer is the one with the earliest change point, ties as above by distance
from the control channel and then by name, and :attr:`PinpointResult.fallback` says the answer
was found this way and why.

A change point of the control channel in the recordings' first bin after their start (given the
bin width) is the same case: the commands differ from their first messages on, and only the
first bin, which both executions share, makes it a change point. No stretch before it shows
the two executions alike, so the channels upstream, which differ from the start as well, have
no change point that times their departure (their first seconds, the baseline their noise is
measured on, already hold it), and the paper's pruning would cut the walk at the commands.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass

from rocas.analysis.cmg import CHANNEL, MODULE, ChannelModuleGraph, Node


@dataclass(frozen=True)
class RemovedEdge:
    """An edge Algorithm 1 removed, and why.

    Attributes:
        source: (kind, name) of u.
        target: (kind, name) of v.
        reason: plain-language reason.
    """

    source: Node
    target: Node
    reason: str


@dataclass(frozen=True)
class PinpointResult:
    """What Algorithm 1 found.

    Attributes:
        deviating_module: the initial deviating module, or None.
        control_channel: where the walk started.
        t_star: node -> t* [s] (None when undefined).
        reachable: modules reachable from the control channel in the reversed pruned graph.
        removed_edges: every removed edge with its reason.
        path: node names from the control channel to the deviating module.
        exclusions: module -> why it is not the answer (for modules with a defined t*).
        fallback: why the control channel gave the walk no start (it has no change point),
            when the answer was taken from the modules it depends on; None for the paper's walk.
    """

    deviating_module: str | None
    control_channel: str
    t_star: dict[Node, float | None]
    reachable: frozenset[str]
    removed_edges: tuple[RemovedEdge, ...]
    path: tuple[str, ...]
    exclusions: dict[str, str]
    fallback: str | None = None


def _fmt(t: float | None) -> str:
    return "none" if t is None else f"{t:g} s"


def _why_not(
    module: str,
    t_module: float,
    deviating: str | None,
    t_star: Mapping[Node, float | None],
    depth: Mapping[Node, int],
    control_channel: str,
    within: tuple[float, float] | None = None,
) -> str:
    """Why a reachable module with a change point is not the answer (see the tie rule).
    ``within``: (the module's, the answer's) first differing message in their common bin."""
    if deviating is None:
        return "reachable"
    t_dev = t_star[(MODULE, deviating)]
    if t_dev is None or t_module > t_dev:
        return (f"reachable, but its change point ({_fmt(t_module)}) is later than "
                f"{deviating}'s ({_fmt(t_dev)})")
    if within is not None and within[0] > within[1]:
        return (f"reachable, with its change point in the same bin as {deviating}'s "
                f"({_fmt(t_module)}), but its first differing message ({within[0]:.3f} s) came "
                f"after {deviating}'s ({within[1]:.3f} s)")
    # same change point (the same bin): the tie goes to the module farther upstream
    if depth.get((MODULE, module), 0) < depth.get((MODULE, deviating), 0):
        return (f"reachable, with the same change point as {deviating} ({_fmt(t_module)}), "
                f"but {deviating} is farther upstream from {control_channel} and deviations "
                "travel downstream")
    return (f"reachable, with the same change point as {deviating} ({_fmt(t_module)}) at the "
            f"same distance from {control_channel}; the tie goes to {deviating} by name")


def find_initial_module(
    cmg: ChannelModuleGraph,
    channel_t_star: Mapping[str, float | None],
    control_channel: str,
    delta_s: float = 3.0,
    control_onset_s: float | None = None,
    bin_s: float | None = None,
    past_window: bool = True,
    first_differing_s: Mapping[str, float] | None = None,
    last_alike_s: Mapping[str, float] | None = None,
    timing_s: float = 0.0,
) -> PinpointResult:
    """Run Algorithm 1.

    Args:
        cmg: the channel-module graph.
        channel_t_star: topic -> first change point [s] or None.
        control_channel: the channel to start from.
        delta_s: reaction window delta [s].
        control_onset_s: when the control channel has no change point but its messages
            differ, the time of its first differing bin [s]: then only a change point at or
            before it, and at most ``delta_s`` before it, can explain the commands' difference.
        bin_s: the series' bin width [s]: a first change point of the control channel at or
            before it (the first bin after the start) counts as no change point, the commands
            differing from ``control_onset_s`` on. None: every change point counts.
        past_window: when the walk names the control channel's own writer, go on from an input
            of it that departed before the window (see :func:`_past_the_window`); False: the
            paper's walk as written.
        first_differing_s: topic -> log time of the first message that differs in the bin of
            its t* [s]: modules whose change points fall into one bin are ordered by it before
            the tie rule (jitter moves a message across a bin edge; the message's own time
            still says which came first). None: bins only.
        last_alike_s: topic -> the last bin before its t* in which the channel was compared
            and alike [s]. When a channel has no compared bin just before its t* (messages lost
            there, the channel at half rate or at 1 Hz), its departure lies anywhere after that
            bin: a module upstream of the earliest one whose departure may lie at or before the
            earliest's t* is named instead (deviations travel downstream). None: t* only.
        timing_s: how far apart the two runs log one message [s]: first differing messages
            closer than this within one bin are a tie (the upstream rule decides).
    """
    t_star = _node_t_star(cmg.successors, channel_t_star)
    removed = _removed_edges(cmg, t_star, delta_s, last_alike_s)
    start: Node = (CHANNEL, control_channel)
    fallback = _fallback(cmg.successors, start, t_star.get(start), control_channel,
                         control_onset_s, bin_s, delta_s)
    walk = _walk(cmg.successors, t_star, start, removed, fallback, control_onset_s, delta_s,
                 first_differing_s)
    ranked = _rank(walk)
    deviating = _choose(walk, ranked.candidates, timing_s, last_alike_s)
    path: tuple[str, ...] = ()
    if deviating is not None:
        nodes = _shortest_path(walk.upstream, walk.downstream, start, (MODULE, deviating))
        path = tuple(n for _, n in nodes)
    result = PinpointResult(
        deviating_module=deviating,
        control_channel=control_channel,
        t_star=t_star,
        reachable=ranked.reachable,
        removed_edges=tuple(removed),
        path=path,
        exclusions=_exclusions(cmg, walk, ranked, deviating, removed, control_channel),
        fallback=fallback,
    )
    if past_window and fallback is None and deviating in cmg.writers_of(control_channel):
        return past_the_window(cmg, channel_t_star, result, delta_s)
    return result


def _node_t_star(succ: Mapping[Node, Collection[Node]],
                 channel_t_star: Mapping[str, float | None]) -> dict[Node, float | None]:
    """Step 1: node -> t* [s]: a channel's first change point, a module's the earliest among
    the channels it writes (None when undefined); channels first, in node order."""
    t_star: dict[Node, float | None] = {}
    for node in succ:
        kind, name = node
        if kind == CHANNEL:
            t_star[node] = channel_t_star.get(name)
    for node, outs in succ.items():
        kind, name = node
        if kind == MODULE:
            ts = [t_star[v] for v in outs if t_star.get(v) is not None]
            t_star[node] = min(ts) if ts else None  # type: ignore[type-var]
    return t_star


def _removed_edges(cmg: ChannelModuleGraph, t_star: Mapping[Node, float | None],
                   delta_s: float, last_alike_s: Mapping[str, float] | None
                   ) -> list[RemovedEdge]:
    """Step 2: the edges whose source's t* is undefined or outside the window before their
    target's (an input not seen alike since before its target departed is kept: its
    departure may lie anywhere after its last alike bin), in edge order."""
    removed: list[RemovedEdge] = []
    for u, v in sorted(cmg.edges):
        tu, tv = t_star[u], t_star[v]
        if tu is None or tv is None:
            which = u if tu is None else v
            reason = f"t*({which[1]}) is undefined (no change point)"
        elif tv - delta_s <= tu <= tv:
            continue
        elif (last_alike_s and u[0] == CHANNEL and u[1] in last_alike_s
              and tv - delta_s <= tu and last_alike_s[u[1]] < tv - 1e-9):
            continue  # first seen after tv, but not seen alike since before it (a gap)
        else:
            reason = f"t*({u[1]}) = {tu:g} s is outside [{tv - delta_s:g}, {tv:g}] s"
        removed.append(RemovedEdge(u, v, reason))
    return removed


def _fallback(succ: Mapping[Node, Collection[Node]], start: Node, t_control: float | None,
              control_channel: str, control_onset_s: float | None, bin_s: float | None,
              delta_s: float) -> str | None:
    """Why the control channel gives the walk no start (no change point, or only one in its
    first bin), when it does not; None for the paper's walk (module docstring)."""
    from_start = (t_control is not None and bin_s is not None and control_onset_s is not None
                  and t_control <= bin_s * (1 + 1e-9))
    if start not in succ or not (t_control is None or from_start):
        return None
    fallback = ((f"{control_channel}'s first change point ({_fmt(t_control)}) is its first "
                 "bin after the start, so nothing before it shows the two executions alike "
                 f"(its messages differ from {control_onset_s:g} s on)") if from_start
                else f"{control_channel} has no change point (its messages "
                + (f"differ from {control_onset_s:g} s on" if control_onset_s is not None
                   else "are the same in both recordings") + ")")
    return fallback + ", so the walk starts from every module it depends on" + (
        f" that departs within [{control_onset_s - delta_s:g}, {control_onset_s:g}] s"
        if control_onset_s is not None else "")


@dataclass(frozen=True)
class _Walk:
    """The graph Algorithm 1 walks and what ranks the modules it reaches.

    Attributes:
        succ: the CMG's node -> successors; t_star: node -> t* [s].
        start: the control channel's node.
        fallback: :func:`_fallback`'s reason, or None for the paper's walk.
        control_onset_s, delta_s: the commands' first differing bin and the window [s].
        upstream: node -> the kept edges' sources, in node order (the reversed graph,
            pruned unless the walk has no start: the fallback walks it whole).
        downstream: node -> the kept edges' targets, in edge order.
        depth: node -> edges from ``start`` in the reversed graph (empty without a start).
        first_differing_s: topic -> first differing message in the bin of its t* [s].
    """

    succ: Mapping[Node, Collection[Node]]
    t_star: Mapping[Node, float | None]
    start: Node
    fallback: str | None
    control_onset_s: float | None
    delta_s: float
    upstream: dict[Node, list[Node]]
    downstream: dict[Node, list[Node]]
    depth: dict[Node, int]
    first_differing_s: Mapping[str, float] | None

    def explains(self, tm: float) -> bool:
        """Whether a module departing at ``tm`` can explain the commands (the fallback's
        window before their first difference; always, on the paper's walk)."""
        return (not self.fallback or self.control_onset_s is None
                or self.control_onset_s - self.delta_s <= tm <= self.control_onset_s)

    def within_bin(self, m: str, tm: float) -> float:
        """The module's first differing message at its t* (its t* without that detail)."""
        if not self.first_differing_s:
            return tm
        return min((self.first_differing_s.get(v[1], tm) for v in self.succ[(MODULE, m)]
                    if self.t_star.get(v) == tm), default=tm)


def _walk(succ: Mapping[Node, Collection[Node]], t_star: Mapping[Node, float | None],
          start: Node, removed: list[RemovedEdge], fallback: str | None,
          control_onset_s: float | None, delta_s: float,
          first_differing_s: Mapping[str, float] | None) -> _Walk:
    """Step 3's graph: the reversed graph less the removed edges (all kept for the
    fallback), and each node's distance from the control channel in it."""
    gone = set() if fallback else {(e.source, e.target) for e in removed}
    upstream: dict[Node, list[Node]] = {n: [] for n in succ}
    downstream: dict[Node, list[Node]] = {}
    for u, outs in succ.items():
        downstream[u] = [v for v in outs if (u, v) not in gone]
        for v in downstream[u]:
            upstream[v].append(u)
    depth = _depths(upstream, start) if start in succ else {}
    return _Walk(succ, t_star, start, fallback, control_onset_s, delta_s, upstream, downstream,
                 depth, first_differing_s)


#: A module the walk may name: (t* [s], first differing message [s], minus its depth, name).
_Candidate = tuple[float, float, int, str]


@dataclass(frozen=True)
class _Ranked:
    """The modules the walk reaches, less ``feedback`` (the modules that read the control
    channel, when they are left out), and those of them that may be the answer."""

    feedback: frozenset[str]
    reachable: frozenset[str]
    candidates: list[_Candidate]


def _rank(walk: _Walk) -> _Ranked:
    """The reachable modules with a t* that explains the commands.

    A module that reads the control channel reports the vehicle's response to it (the
    chassis): without a change point on that channel, its deviation may be the commands' or
    the world's, so the fallback leaves it out. With the commands the same in both runs and
    no other module departing, nothing else in the graph explains it, and it is kept (the
    plant's own output changed).
    """
    def without(left_out: frozenset[str]) -> _Ranked:
        reach = frozenset(n for k, n in walk.depth if k == MODULE and n not in left_out)
        return _Ranked(left_out, reach, [
            (tm, walk.within_bin(m, tm), -walk.depth.get((MODULE, m), 0), m) for m in reach
            if (tm := walk.t_star[(MODULE, m)]) is not None and walk.explains(tm)])

    feedback = frozenset(n for k, n in walk.succ.get(walk.start, ()) if k == MODULE
                         ) if walk.fallback else frozenset()
    ranked = without(feedback)
    if not ranked.candidates and feedback and walk.control_onset_s is None:
        ranked = without(frozenset())
    return ranked


def _choose(walk: _Walk, candidates: list[_Candidate], timing_s: float,
            last_alike_s: Mapping[str, float] | None) -> str | None:
    """The candidate with the earliest t* (module docstring's tie rule); first differing
    messages closer than ``timing_s`` are a tie, and a module upstream whose departure may
    lie before the answer's t* (a gap before its own) goes first."""
    deviating = min(candidates)[3] if candidates else None
    if deviating is not None and timing_s > 0:
        first = min(candidates)
        tied = [c for c in candidates if c[0] == first[0] and c[1] <= first[1] + timing_s]
        deviating = min(tied, key=lambda c: (c[2], c[1], c[3]))[3]
    if deviating is not None and last_alike_s:
        t0 = walk.t_star[(MODULE, deviating)]
        d0 = walk.depth.get((MODULE, deviating), 0)

        def may_precede(m: str, tm: float) -> bool:
            lo = min((last_alike_s.get(v[1], tm) for v in walk.succ[(MODULE, m)]
                      if walk.t_star.get(v) == tm), default=tm)
            return tm > t0 and lo < t0 - 1e-9  # type: ignore[operator]

        upstream_first = [c for c in candidates if c[2] < -d0 and may_precede(c[3], c[0])]
        if upstream_first:
            deviating = min(upstream_first, key=lambda c: (c[2], c[0], c[1], c[3]))[3]
    return deviating


def _exclusions(cmg: ChannelModuleGraph, walk: _Walk, ranked: _Ranked, deviating: str | None,
                removed: list[RemovedEdge], control_channel: str) -> dict[str, str]:
    """module -> why it is not the answer, for every other module with a t*."""
    t_star = walk.t_star
    exclusions: dict[str, str] = {}
    for m in cmg.modules:
        tm = t_star[(MODULE, m)]
        if m == deviating or tm is None:
            continue
        if m in ranked.reachable and not walk.explains(tm):
            exclusions[m] = (f"its change point ({_fmt(tm)}) is outside "
                             f"[{walk.control_onset_s - walk.delta_s:g}, "
                             f"{walk.control_onset_s:g}] s, the window "
                             f"before {control_channel} first differs")
        elif m in ranked.reachable:
            t_dev = t_star[(MODULE, deviating)] if deviating else None
            exclusions[m] = _why_not(
                m, tm, deviating, t_star, walk.depth, control_channel,
                (walk.within_bin(m, tm), walk.within_bin(deviating, tm))
                if deviating is not None and t_dev == tm else None)
        elif m in ranked.feedback:
            exclusions[m] = (f"reads {control_channel}, which has no change point to start the "
                             "walk from, so its change may be the vehicle's response to the "
                             "commands")
        else:
            written = set(cmg.channels_written_by(m))
            cut = [
                e for e in removed
                if (e.source[0] == CHANNEL and e.source[1] in written) or e.source == (MODULE, m)
            ]
            why = "; ".join(
                f"edge {e.source[1]} -> {e.target[1]} removed: {e.reason}" for e in cut[:3]
            )
            exclusions[m] = f"not reachable from {control_channel}" + (f" ({why})" if why else "")
    return exclusions


def past_the_window(cmg: ChannelModuleGraph, channel_t_star: Mapping[str, float | None],
                    found: PinpointResult, delta_s: float,
                    written_by: Collection[str] | None = None,
                    reach_s: float | None = None) -> PinpointResult:
    """The walk that named a module, continued past the window.

    Naming a module says only that none of its inputs departed within ``delta_s`` before its
    own change point. When one departed earlier, the module was not the first to deviate: the
    walk goes on from the latest such input (then by name; only inputs that a module of
    ``written_by`` writes, when given, and only those that departed at most ``reach_s`` before
    the module, when given), with the window again, and
    :attr:`PinpointResult.fallback` says so. Algorithm 1 takes this step by itself only for
    the control channel's own writer (the commands' writer deviates only through its inputs);
    deeper in the graph the window keeps its role (an early harmless departure upstream of a
    module that departed within it is passed over) unless other evidence asks for the step
    (module substitution: rocas.pipeline.confidence). Returns ``found`` when there is no such
    input or the walk from it names no other module.
    """
    writer = found.deviating_module
    assert writer is not None
    t_writer = found.t_star[(MODULE, writer)]
    assert t_writer is not None
    early = [(t, c) for c in cmg.channels_read_by(writer)
             if (t := channel_t_star.get(c)) is not None and t < t_writer - delta_s
             and (written_by is None or set(cmg.writers_of(c)) & set(written_by))
             and (reach_s is None or t >= t_writer - reach_s)]
    if not early:
        return found
    t_in, channel = min(early, key=lambda tc: (-tc[0], tc[1]))
    rest = find_initial_module(cmg, channel_t_star, channel, delta_s, past_window=False)
    if rest.deviating_module is None or rest.deviating_module == writer:
        return found
    exclusions = {**found.exclusions, **rest.exclusions}
    exclusions[writer] = (f"its input {channel} departed at {_fmt(t_in)}, more than "
                          f"{delta_s:g} s before its own change point ({_fmt(t_writer)})")
    exclusions.pop(rest.deviating_module, None)
    note = (f"no input of {writer} departed within {delta_s:g} s before "
            + (f"{found.control_channel}" if writer in cmg.writers_of(found.control_channel)
               else f"{writer} departed") + f" ({_fmt(t_writer)}), but {channel} departed "
            f"earlier ({_fmt(t_in)}), so the walk goes on from it")
    return PinpointResult(
        deviating_module=rest.deviating_module,
        control_channel=found.control_channel,
        t_star=found.t_star,
        reachable=found.reachable | rest.reachable,
        removed_edges=found.removed_edges,
        path=found.path + rest.path,
        exclusions=exclusions,
        fallback=note,
    )


def _depths(forward: Mapping[Node, list[Node]], start: Node) -> dict[Node, int]:
    """Breadth-first distance (edges) from ``start`` to every node it reaches, itself included."""
    depth = {start: 0}
    level = [start]
    while level:
        nxt = []
        for v in level:
            for w in forward[v]:
                if w not in depth:
                    depth[w] = depth[v] + 1
                    nxt.append(w)
        level = nxt
    return depth


def _shortest_path(forward: Mapping[Node, list[Node]], backward: Mapping[Node, list[Node]],
                   source: Node, target: Node) -> list[Node]:
    """A shortest path from ``source`` to ``target`` (which it reaches) along ``forward``.

    Where several are shortest, the one networkx's ``shortest_path`` returns on the same
    graph: a breadth-first search from both ends, a level at a time, that grows the smaller
    frontier (the forward one on a tie) and stops at the first node both have seen, each
    node remembering the neighbour it was first reached from (tests/analysis/test_pinpoint.py
    checks the two agree).
    """
    if source == target:
        return [source]
    pred: dict[Node, Node | None] = {source: None}
    succ: dict[Node, Node | None] = {target: None}
    ahead, behind = [source], [target]
    meet: Node | None = None
    while meet is None and ahead and behind:
        grow_forward = len(ahead) <= len(behind)
        level, seen, other, edges = ((ahead, pred, succ, forward) if grow_forward
                                     else (behind, succ, pred, backward))
        frontier: list[Node] = []
        for v in level:
            for w in edges[v]:
                if w not in seen:
                    seen[w] = v
                    frontier.append(w)
                if w in other:
                    meet = w
                    break
            if meet is not None:
                break
        if grow_forward:
            ahead = frontier
        else:
            behind = frontier
    assert meet is not None, "the target is reachable"
    path: list[Node] = []
    node: Node | None = meet
    while node is not None:
        path.append(node)
        node = pred[node]
    path.reverse()
    node = succ[meet]
    while node is not None:
        path.append(node)
        node = succ[node]
    return path
