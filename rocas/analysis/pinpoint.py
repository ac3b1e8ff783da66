"""Algorithm 1 of the paper: pinpoint the initial deviating module on the CMG.

1. t*(channel) is the channel's first change point (None when it never deviated);
   t*(module) is the earliest t* among the channels the module writes.
2. Every edge (u, v) is removed unless t*(u) lies in [t*(v) - delta, t*(v)]; an edge
   with an undefined t* on either end is removed.
3. From the control channel, walk the reversed graph; the deviating module is the
   reachable module with the earliest t*. Ties (modules whose change points fall into the
   same bin, as when a whole pipeline reacts within one tick) go to the module farthest
   upstream along the walk, since deviations travel downstream; then by name.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import networkx as nx

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
    """

    deviating_module: str | None
    control_channel: str
    t_star: dict[Node, float | None]
    reachable: frozenset[str]
    removed_edges: tuple[RemovedEdge, ...]
    path: tuple[str, ...]
    exclusions: dict[str, str]


def _fmt(t: float | None) -> str:
    return "none" if t is None else f"{t:g} s"


def _why_not(
    module: str,
    t_module: float,
    deviating: str | None,
    t_star: Mapping[Node, float | None],
    depth: Mapping[Node, int],
    control_channel: str,
) -> str:
    """Why a reachable module with a change point is not the answer (see the tie rule)."""
    if deviating is None:
        return "reachable"
    t_dev = t_star[(MODULE, deviating)]
    if t_dev is None or t_module > t_dev:
        return (f"reachable, but its change point ({_fmt(t_module)}) is later than "
                f"{deviating}'s ({_fmt(t_dev)})")
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
) -> PinpointResult:
    """Run Algorithm 1.

    Args:
        cmg: the channel-module graph.
        channel_t_star: topic -> first change point [s] or None.
        control_channel: the channel to start from.
        delta_s: reaction window delta [s].
    """
    g = cmg.graph
    t_star: dict[Node, float | None] = {}
    for node in g.nodes:
        kind, name = node
        if kind == CHANNEL:
            t_star[node] = channel_t_star.get(name)
    for node in g.nodes:
        kind, name = node
        if kind == MODULE:
            ts = [t_star[v] for _, v in g.out_edges(node) if t_star.get(v) is not None]
            t_star[node] = min(ts) if ts else None  # type: ignore[type-var]

    pruned = g.copy()
    removed: list[RemovedEdge] = []
    for u, v in sorted(g.edges):
        tu, tv = t_star[u], t_star[v]
        if tu is None or tv is None:
            which = u if tu is None else v
            reason = f"t*({which[1]}) is undefined (no change point)"
        elif tv - delta_s <= tu <= tv:
            continue
        else:
            reason = f"t*({u[1]}) = {tu:g} s is outside [{tv - delta_s:g}, {tv:g}] s"
        pruned.remove_edge(u, v)
        removed.append(RemovedEdge(u, v, reason))

    start: Node = (CHANNEL, control_channel)
    reversed_g = pruned.reverse(copy=False)
    reach_nodes = nx.descendants(reversed_g, start) if start in reversed_g else set()
    reachable = frozenset(n for k, n in reach_nodes if k == MODULE)
    depth = nx.single_source_shortest_path_length(reversed_g, start) if start in reversed_g else {}
    candidates = [
        (t_star[(MODULE, m)], -depth.get((MODULE, m), 0), m)
        for m in reachable
        if t_star[(MODULE, m)] is not None
    ]
    deviating = min(candidates)[2] if candidates else None

    path: tuple[str, ...] = ()
    if deviating is not None:
        nodes = nx.shortest_path(reversed_g, start, (MODULE, deviating))
        path = tuple(n for _, n in nodes)

    exclusions: dict[str, str] = {}
    for m in cmg.modules:
        tm = t_star[(MODULE, m)]
        if m == deviating or tm is None:
            continue
        if m in reachable:
            exclusions[m] = _why_not(m, tm, deviating, t_star, depth, control_channel)
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

    return PinpointResult(
        deviating_module=deviating,
        control_channel=control_channel,
        t_star=t_star,
        reachable=reachable,
        removed_edges=tuple(removed),
        path=path,
        exclusions=exclusions,
    )
