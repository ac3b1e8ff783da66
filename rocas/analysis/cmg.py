"""The Channel Module Graph (CMG, Definition 5.1): who writes and who reads each channel.

A CMG is a directed bipartite graph with an edge module -> channel for every writer and
channel -> module for every reader. rocas learns it from the recording itself, in this order
of precedence per channel:

1. a ``--cmg`` JSON file, for the channels it names as written (writers) or read
   (readers) by some module (``source = "cmg"``);
2. the channel metadata ``rocas.writers`` / ``rocas.readers`` (``source = "metadata"``);
3. the ROS 1 profile's ``callerid`` metadata, which names the publishing node, as the writer
   when ``rocas.writers`` is absent (``source = "callerid"``).

A topic recorded on several channels (a ROS 1 topic with two publishers has one channel per
``callerid``) gets the union of their writers and readers.

The CMG JSON format::

    {"modules": {"planning": {"reads": ["/prediction"], "writes": ["/planning"]}},
     "control_channel": "/control"}            # optional

``rocas cmg REC --format json`` prints this format plus the informational keys
``"channels"`` (per-channel sources), ``"recording"``, ``"control_source"``, ``"notes"``,
``"hints"``, ``"warnings"`` and ``"complete"``; they are accepted and ignored when the file
is read back as ``--cmg``, so the output feeds straight back in.
Any other key is refused (it is most likely a typo).
"""

from __future__ import annotations

import functools
import json
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rocas.errors import InputError, TopologyError
from rocas.recording.model import ChannelInfo
from rocas.recording.topology import (
    CONTROL_ROLE,
    READERS_KEY,
    ROLE_KEY,
    ROS1_CALLERID_KEY,
    WRITERS_KEY,
    split_modules,
)

if TYPE_CHECKING:
    import networkx as nx

    from rocas.recording.annotation import ChannelAnnotation

CHANNEL, MODULE = "channel", "module"
Node = tuple[str, str]  # (kind, name)


@dataclass(frozen=True)
class ChannelTopology:
    """Topology of one channel.

    Attributes:
        topic: the channel.
        writers: modules publishing on it.
        readers: modules subscribed to it.
        is_control: whether the channel is marked ``rocas.role = control``.
        writers_source: where the writers came from: "cmg", "metadata", "callerid" or "missing".
        readers_source: where the readers came from: "cmg", "metadata" or "missing".
        in_recording: False for a channel only the CMG file names.
    """

    topic: str
    writers: tuple[str, ...]
    readers: tuple[str, ...]
    is_control: bool = False
    writers_source: str = "missing"
    readers_source: str = "missing"
    in_recording: bool = True


@dataclass(frozen=True)
class CmgSpec:
    """A topology supplied from a CMG JSON file.

    Attributes:
        writes: module -> channels it writes.
        reads: module -> channels it reads.
        control_channel: the control channel, if the file names one.
        path: the file it came from (for messages).
    """

    writes: Mapping[str, tuple[str, ...]]
    reads: Mapping[str, tuple[str, ...]]
    control_channel: str | None = None
    path: str = "<cmg>"

    def channels(self) -> set[str]:
        """Every channel the file mentions."""
        out: set[str] = set()
        for chans in (*self.writes.values(), *self.reads.values()):
            out.update(chans)
        return out

    def annotations(self) -> dict[str, ChannelAnnotation]:
        """Per channel the file names: its writers and readers (for ``rocas annotate``)."""
        from rocas.recording.annotation import ChannelAnnotation

        return {
            topic: ChannelAnnotation(
                writers=tuple(m for m, cs in self.writes.items() if topic in cs),
                readers=tuple(m for m, cs in self.reads.items() if topic in cs),
            )
            for topic in sorted(self.channels())
        }

    def restricted_to(self, topics: Iterable[str]) -> CmgSpec:
        """The same file with every channel outside ``topics`` dropped from the modules'
        reads and writes (a module left with none drops out of the graph built from it).
        The control channel is kept as named, so a check against the recording still sees it.
        """
        keep = set(topics)

        def only(side: Mapping[str, tuple[str, ...]]) -> dict[str, tuple[str, ...]]:
            return {m: tuple(c for c in chans if c in keep) for m, chans in side.items()}

        return CmgSpec(only(self.writes), only(self.reads), self.control_channel, self.path)

    def missing_channels(self, topics: Iterable[str]) -> list[str]:
        """Channels the file names (control channel included) that are not in ``topics``."""
        present = set(topics)
        named = self.channels() | ({self.control_channel} if self.control_channel else set())
        return sorted(named - present)

    def missing_channel_warnings(self, topics: Iterable[str], where: str) -> list[str]:
        """One warning line per channel of :meth:`missing_channels`; ``where`` names the
        recording(s) (the channels are ignored, which is what the line says)."""
        return [
            f"{self.path} names {'control channel' if t == self.control_channel else 'channel'} "
            f"{t}, which is not in {where}; ignored"
            for t in self.missing_channels(topics)
        ]


def load_cmg(path: str | os.PathLike[str]) -> CmgSpec:
    """Read and validate a CMG JSON file."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"no such CMG file: {p}", "check the --cmg path") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read CMG file {p}: {exc}") from exc
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(
            f"{p}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})",
            'expected {"modules": {"NAME": {"reads": [...], "writes": [...]}}}',
        ) from None
    return parse_cmg(data, str(p))


# keys ``rocas cmg --format json`` adds to the --cmg format; read back, they are ignored
INFORMATIVE_KEYS = frozenset({"channels", "recording", "control_source", "notes", "hints",
                              "warnings", "complete"})


def parse_cmg(data: Any, origin: str = "<cmg>") -> CmgSpec:
    """Validate a decoded CMG JSON document (the keys in ``INFORMATIVE_KEYS`` are ignored)."""
    hint = 'expected {"modules": {"NAME": {"reads": [...], "writes": [...]}}}'
    if not isinstance(data, dict) or not isinstance(data.get("modules"), dict):
        raise InputError(f"{origin}: key 'modules' must be an object of modules", hint)
    unknown = set(data) - {"modules", "control_channel"} - INFORMATIVE_KEYS
    if unknown:
        raise InputError(f"{origin}: unknown key {sorted(unknown)[0]!r}", hint)
    writes: dict[str, tuple[str, ...]] = {}
    reads: dict[str, tuple[str, ...]] = {}
    for name, spec in data["modules"].items():
        if not isinstance(spec, dict):
            raise InputError(f"{origin}: modules.{name} must be an object", hint)
        bad = set(spec) - {"reads", "writes"}
        if bad:
            raise InputError(f"{origin}: modules.{name}: unknown key {sorted(bad)[0]!r}", hint)
        for key, target in (("reads", reads), ("writes", writes)):
            chans = spec.get(key, [])
            if not isinstance(chans, list) or not all(isinstance(c, str) and c for c in chans):
                raise InputError(
                    f"{origin}: modules.{name}.{key} must be a list of channel names", hint
                )
            target[name] = tuple(dict.fromkeys(chans))
    control = data.get("control_channel")
    if control is not None and not isinstance(control, str):
        raise InputError(f"{origin}: control_channel must be a string")
    return CmgSpec(writes, reads, control, origin)


def resolve_topology(
    channels: Iterable[ChannelInfo], cmg: CmgSpec | None = None
) -> dict[str, ChannelTopology]:
    """Per-topic topology from channel metadata, ``callerid`` and an optional CMG file.

    For a channel the CMG file names, its writers (readers) replace the recorded ones when
    the file names any; a side the file leaves empty keeps what the recording says. When
    the file names a control channel, that channel (and no other) is the control channel.
    """
    writers_of: dict[str, dict[str, None]] = {}
    readers_of: dict[str, dict[str, None]] = {}
    callerids: dict[str, dict[str, None]] = {}
    control: set[str] = set()
    for ch in channels:
        meta = ch.metadata
        writers_of.setdefault(ch.topic, {}).update(
            dict.fromkeys(split_modules(meta.get(WRITERS_KEY)))
        )
        readers_of.setdefault(ch.topic, {}).update(
            dict.fromkeys(split_modules(meta.get(READERS_KEY)))
        )
        caller = meta.get(ROS1_CALLERID_KEY, "").strip()
        if caller:
            callerids.setdefault(ch.topic, {})[caller] = None
        if meta.get(ROLE_KEY, "").strip().lower() == CONTROL_ROLE:
            control.add(ch.topic)
    recorded = set(writers_of)
    cmg_channels = cmg.channels() if cmg else set()
    if cmg is not None and cmg.control_channel:
        control = {cmg.control_channel}
    out: dict[str, ChannelTopology] = {}
    for topic in sorted(recorded | cmg_channels):
        writers = tuple(writers_of.get(topic, ()))
        w_src = "metadata" if writers else "missing"
        if not writers and callerids.get(topic):
            writers = tuple(callerids[topic])
            w_src = "callerid"
        readers = tuple(readers_of.get(topic, ()))
        r_src = "metadata" if readers else "missing"
        if cmg is not None and topic in cmg_channels:
            if cmg_writers := tuple(m for m, cs in cmg.writes.items() if topic in cs):
                writers, w_src = cmg_writers, "cmg"
            if cmg_readers := tuple(m for m, cs in cmg.reads.items() if topic in cs):
                readers, r_src = cmg_readers, "cmg"
        out[topic] = ChannelTopology(
            topic, writers, readers, topic in control, w_src, r_src,
            in_recording=topic in recorded,
        )
    return out


@dataclass(frozen=True)
class ChannelModuleGraph:
    """A CMG: channels, modules, and the read/write edges between them.

    Attributes:
        topology: topic -> ChannelTopology.
        successors: node -> the nodes its edges lead to, over nodes ``("channel", topic)``
            and ``("module", name)``; nodes and each node's successors in the order they
            were added (the order a networkx DiGraph built the same way keeps).
    """

    topology: dict[str, ChannelTopology]
    successors: dict[Node, dict[Node, None]] = field(compare=False, repr=False)

    @classmethod
    def from_topology(cls, topology: Mapping[str, ChannelTopology]) -> ChannelModuleGraph:
        succ: dict[Node, dict[Node, None]] = {}

        def add_edge(u: Node, v: Node) -> None:
            succ.setdefault(u, {})
            succ.setdefault(v, {})
            succ[u][v] = None

        for topic, t in topology.items():
            succ.setdefault((CHANNEL, topic), {})
            for m in t.writers:
                add_edge((MODULE, m), (CHANNEL, topic))
            for m in t.readers:
                add_edge((CHANNEL, topic), (MODULE, m))
        return cls(dict(topology), succ)

    @functools.cached_property
    def graph(self) -> nx.DiGraph:
        """The CMG as a networkx DiGraph (imported on first use: the diff itself needs none)."""
        import networkx as nx

        g = nx.DiGraph()
        g.add_nodes_from(self.successors)
        g.add_edges_from((u, v) for u, vs in self.successors.items() for v in vs)
        return g

    @property
    def nodes(self) -> list[Node]:
        return list(self.successors)

    @property
    def edges(self) -> list[tuple[Node, Node]]:
        return [(u, v) for u, vs in self.successors.items() for v in vs]

    @property
    def modules(self) -> list[str]:
        return sorted(n for k, n in self.successors if k == MODULE)

    @property
    def channels(self) -> list[str]:
        return sorted(self.topology)

    def has_edges(self) -> bool:
        return any(self.successors.values())

    def writers_of(self, topic: str) -> tuple[str, ...]:
        t = self.topology.get(topic)
        return t.writers if t else ()

    def channels_written_by(self, module: str) -> list[str]:
        return sorted(n for k, n in self.successors.get((MODULE, module), {}) if k == CHANNEL)

    def channels_read_by(self, module: str) -> list[str]:
        node = (MODULE, module)
        return sorted(n for (k, n), vs in self.successors.items() if k == CHANNEL and node in vs)

    def to_json(self) -> dict[str, Any]:
        """The graph in the ``--cmg`` file format, plus per-channel sources."""
        modules: dict[str, dict[str, list[str]]] = {}
        for m in self.modules:
            modules[m] = {
                "reads": self.channels_read_by(m),
                "writes": self.channels_written_by(m),
            }
        control = [t for t, c in self.topology.items() if c.is_control]
        return {
            "modules": modules,
            "control_channel": control[0] if len(control) == 1 else None,
            "channels": [
                {
                    "topic": t.topic,
                    "writers": list(t.writers),
                    "readers": list(t.readers),
                    "writers_source": t.writers_source,
                    "readers_source": t.readers_source,
                    "control": t.is_control,
                }
                for t in self.topology.values()
            ],
        }

    def to_dot(self) -> str:
        """Graphviz DOT text: modules as ellipses, channels as boxes.

        Names are written as DOT quoted strings with backslash, double quote and line breaks
        escaped, so any topic or module name gives valid DOT and is shown as it is.
        """
        lines = ["digraph cmg {", "  rankdir=LR;"]
        for kind, name in sorted(self.successors):
            shape = "box" if kind == CHANNEL else "ellipse"
            extra = ", style=bold" if kind == CHANNEL and self.topology[name].is_control else ""
            lines.append(
                f"  {_dot_quote(f'{kind}:{name}')} [label={_dot_quote(name)}, "
                f"shape={shape}{extra}];"
            )
        for (k1, n1), (k2, n2) in sorted(self.edges):
            lines.append(f"  {_dot_quote(f'{k1}:{n1}')} -> {_dot_quote(f'{k2}:{n2}')};")
        lines.append("}")
        return "\n".join(lines) + "\n"


def _dot_quote(text: str) -> str:
    r"""``text`` as a DOT quoted string: ``\\`` for a backslash, ``\"`` for a double quote,
    ``\n`` / ``\r`` for line breaks (one statement stays on one line)."""
    for raw, escaped in (("\\", "\\\\"), ('"', '\\"'), ("\n", "\\n"), ("\r", "\\r")):
        text = text.replace(raw, escaped)
    return f'"{text}"'


def no_topology_hint(start: str = "") -> str:
    """What to do about a recording without topology; ``start`` says where a graph could
    come from."""
    graph = f"the module graph ({start})" if start else "the module graph"
    return (f"pass --cmg FILE with {graph}, or add the metadata with "
            "'rocas annotate IN.mcap --cmg FILE -o OUT.mcap'")


def declares_topology(channels: Iterable[ChannelInfo]) -> bool:
    """Whether any of ``channels`` names a writer or reader (metadata or ``callerid``)."""
    return any(t.writers or t.readers for t in resolve_topology(channels).values())


def build_cmg(
    channels: Iterable[ChannelInfo], cmg: CmgSpec | None = None, *, where: str = "the recording"
) -> ChannelModuleGraph:
    """Build the CMG of a recording; refuses a recording that has no topology at all.

    Channels only the CMG file names are part of the graph (so a graph can come from a
    file alone, with ``channels`` empty); to analyse recordings, drop them first with
    :meth:`CmgSpec.restricted_to` and report them with :meth:`CmgSpec.missing_channels`.
    ``where`` names the recording(s) in the refusal.
    """
    topo = resolve_topology(channels, cmg)
    graph = ChannelModuleGraph.from_topology(topo)
    if not graph.has_edges():
        raise TopologyError(
            f"no channel topology in {where} (no channel has rocas.writers, "
            "rocas.readers or callerid metadata)",
            no_topology_hint(),
        )
    return graph


def control_channel(
    graph: ChannelModuleGraph,
    override: str | None = None,
    cmg: CmgSpec | None = None,
    where: str = "the recording",
) -> str:
    """The channel Algorithm 1 starts from: ``override``, else the CMG file's, else the one
    channel marked ``rocas.role = control``. A chosen channel that is not in the graph is
    refused; ``where`` names the recording(s) in that message."""
    for chosen, origin in (
        (override, "--control-channel"),
        (cmg and cmg.control_channel, cmg and cmg.path),
    ):
        if chosen:
            if chosen not in graph.topology:
                raise TopologyError(
                    f"control channel {chosen!r} (from {origin}) is not in {where}",
                    f"choose one of: {', '.join(graph.channels)}",
                )
            return chosen
    marked = sorted(t for t, c in graph.topology.items() if c.is_control)
    if len(marked) == 1:
        return marked[0]
    if len(marked) > 1:
        raise TopologyError(
            f"several channels are marked rocas.role=control: {', '.join(marked)}",
            "pick one with --control-channel TOPIC",
        )
    written = [t for t, c in graph.topology.items() if c.writers]
    candidates = sorted(written, key=lambda t: ("control" not in t.lower(), t))
    raise TopologyError(
        "no channel is marked as the control channel (channel metadata rocas.role=control)",
        "pick one with --control-channel TOPIC; candidates: "
        + (", ".join(candidates) if candidates else "none (no channel has a writer)"),
    )
