"""``rocas cmg REC``: the channel-module graph, and where rocas learned each part of it.

For every channel: its writers and readers and their source (``metadata`` = the channel's
``rocas.writers`` / ``rocas.readers``, ``cmg`` = the ``--cmg`` file, ``callerid`` = the ROS 1
publishing node, ``missing``), which channel is the control channel, and what to add when
something is missing. Explaining is this command's job, so a recording without any topology
is not an error here (``rocas diff`` refuses it); the output says what to add.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Mapping

from rich.table import Table

from rocas._json import dumps as json_dumps
from rocas.analysis.cmg import (
    ChannelModuleGraph,
    ChannelTopology,
    CmgSpec,
    resolve_topology,
)
from rocas.cli.console import Env, prose, safe
from rocas.cli.inputs import load_cmg_file
from rocas.errors import RecordingError, TopologyError
from rocas.recording.formats import open_recording
from rocas.recording.model import DECODABLE_ENCODINGS, ChannelInfo

HELP = "show who writes and reads each channel of a recording, and what is missing"

_SOURCE_TEXT = {
    "metadata": "metadata",
    "cmg": "--cmg",
    "callerid": "callerid",
    "missing": "missing",
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("recording", metavar="REC", help="an MCAP recording")
    parser.add_argument("--cmg", metavar="FILE",
                        help="CMG JSON file that supplies or overrides the topology")
    parser.add_argument("--control-channel", metavar="TOPIC",
                        help="the channel Algorithm 1 starts from (overrides the recording)")
    parser.add_argument("--format", choices=("text", "json", "dot"), default="text",
                        help="text (default): a table; json: the --cmg format plus sources; "
                        "dot: Graphviz")


@dataclasses.dataclass(frozen=True)
class CmgView:
    """What ``rocas cmg`` shows: the graph plus how it was found.

    Attributes:
        recording: the recording's path.
        graph: the channel-module graph (``is_control`` set on the chosen control channel).
        channels: topic -> its channel declarations in the recording.
        messages: topic -> message count.
        control_channel: the chosen control channel, or None.
        control_source: "--control-channel", "cmg", "metadata" or a reason it is unknown.
        notes: remarks about sources and encodings, one line each.
        hints: what to add, one line each (empty when nothing is missing).
        warnings: what the reader found (damage, counts that disagree with the summary).
    """

    recording: str
    graph: ChannelModuleGraph
    channels: Mapping[str, list[ChannelInfo]]
    messages: Mapping[str, int]
    control_channel: str | None
    control_source: str
    notes: tuple[str, ...]
    hints: tuple[str, ...]
    warnings: tuple[str, ...] = ()


def build_view(
    recording: str, spec: CmgSpec | None, override: str | None, env: Env | None = None
) -> CmgView:
    """Read the recording's channels and explain its topology; warnings go to ``env``.

    Every message is read and decoded, as ``rocas diff`` reads them: the counts shown are the
    messages that decode, and a file that diff cannot read is refused here too.

    Raises:
        RecordingError: no message of the recording can be read.
    """
    rec = open_recording(recording)
    for _ in rec.decoded():
        pass
    damage = rec.report.warnings(recording, skipped_encodings=False)  # the notes explain them
    infos = list(rec.channels.values())
    counts = {t: st.messages for t, st in rec.report.channel_stats.items()}
    if not any(st.messages for st in rec.report.channel_stats.values()):
        raise RecordingError(
            f"{recording} holds no readable message" + (f": {damage[0]}" if damage else ""),
            "check the file with 'mcap info'",
        )
    if env is not None:
        for line in damage:  # a truncated file lists only what was read before the cut
            env.warn(line)
    by_topic: dict[str, list[ChannelInfo]] = {}
    for ch in infos:
        by_topic.setdefault(ch.topic, []).append(ch)
        counts.setdefault(ch.topic, 0)
    if spec is not None:
        if env is not None:
            for line in spec.missing_channel_warnings(by_topic, recording):
                env.warn(line)
        if spec.control_channel and spec.control_channel not in by_topic:
            spec = dataclasses.replace(spec, control_channel=None)
    if override is not None and override not in by_topic:
        raise TopologyError(
            f"control channel {override!r} (from --control-channel) is not in {recording}",
            "choose one of: " + ", ".join(sorted(by_topic)),
        )
    topology = {t: c for t, c in resolve_topology(infos, spec).items() if c.in_recording}

    marked = sorted(t for t, c in topology.items() if c.is_control)
    control: str | None = None
    if override is not None:
        control, source = override, "--control-channel"
    elif spec is not None and spec.control_channel:
        control, source = spec.control_channel, "cmg"
    elif len(marked) == 1:
        control, source = marked[0], "metadata"
    elif marked:
        source = "several channels are marked rocas.role=control: " + ", ".join(marked)
    else:
        source = "none marked"
    if control is not None:
        topology = {t: dataclasses.replace(c, is_control=t == control)
                    for t, c in topology.items()}
    graph = ChannelModuleGraph.from_topology(topology)
    return CmgView(
        recording=recording,
        graph=graph,
        channels=by_topic,
        messages=counts,
        control_channel=control,
        control_source=source,
        notes=tuple(_notes(topology, by_topic)),
        hints=tuple(_hints(recording, topology, control, marked)),
        warnings=tuple(damage),
    )


def _notes(topology: Mapping[str, ChannelTopology],
           channels: Mapping[str, list[ChannelInfo]]) -> list[str]:
    notes = []
    caller = [t for t, c in topology.items() if c.writers_source == "callerid"]
    if caller:
        notes.append(
            "writers of " + ", ".join(caller) + " come from the ROS 1 'callerid' channel "
            "metadata (the publishing node), because rocas.writers is absent"
        )
    for topic in topology:
        encodings = sorted({c.message_encoding for c in channels.get(topic, [])})
        odd = [e for e in encodings if e not in DECODABLE_ENCODINGS]
        if odd:
            notes.append(
                f"{topic} is {'/'.join(odd) or 'unencoded'}: rocas decodes only protobuf, "
                "json, ROS 2 cdr and ROS 1, so 'rocas diff' skips its messages; it stays in the graph"
            )
    return notes


def _hints(recording: str, topology: Mapping[str, ChannelTopology], control: str | None,
           marked: list[str]) -> list[str]:
    no_writers = [t for t, c in topology.items() if not c.writers]
    no_readers = [t for t, c in topology.items() if not c.readers and t != control]
    hints = []
    if not any(c.writers or c.readers for c in topology.values()):
        hints.append(
            "this recording declares no topology: 'rocas diff' needs it (see below)"
        )
    if no_writers:
        hints.append(f"{len(no_writers)} channel(s) without writers: {', '.join(no_writers)}")
    if no_readers:
        hints.append(
            f"{len(no_readers)} channel(s) without readers: {', '.join(no_readers)} "
            "(fine for a stack output nobody reads)"
        )
    if no_writers or no_readers:
        example = no_writers[0] if no_writers else no_readers[0]
        key = "writes" if no_writers else "reads"
        hints.append(
            "add channel metadata rocas.writers / rocas.readers (comma-separated module "
            "names) when recording (rocas.recording.attach_channel), or write a CMG file, "
            f'e.g. {{"modules": {{"MODULE": {{"{key}": ["{example}"]}}}}}}, and pass it with '
            f"--cmg FILE or store it with 'rocas annotate {recording} --cmg FILE -o OUT.mcap'"
        )
    if control is None:
        if len(marked) > 1:
            hints.append("several control channels: pick one with --control-channel TOPIC")
        else:
            hints.append(
                "no control channel: set channel metadata rocas.role=control on the stack's "
                'output channel, or "control_channel" in the CMG file, or pass '
                "--control-channel TOPIC"
            )
    return hints


def _source(c: ChannelTopology, which: str) -> str:
    return _SOURCE_TEXT[c.writers_source if which == "writers" else c.readers_source]


def to_json(view: CmgView) -> dict[str, object]:
    """The ``--format json`` document: the --cmg format plus per-channel sources and hints."""
    doc = view.graph.to_json()
    doc["control_channel"] = view.control_channel
    for entry in doc["channels"]:  # type: ignore[union-attr]
        chans = view.channels.get(entry["topic"], [])
        entry["message_encoding"] = ",".join(sorted({c.message_encoding for c in chans}))
        entry["schema"] = ",".join(sorted({c.schema_name for c in chans if c.schema_name}))
        entry["messages"] = view.messages.get(entry["topic"], 0)
    doc["recording"] = view.recording
    doc["control_source"] = view.control_source
    doc["notes"] = list(view.notes)
    doc["hints"] = list(view.hints)
    doc["warnings"] = list(view.warnings)
    doc["complete"] = not view.warnings
    return doc


def _print_text(view: CmgView, env: Env) -> None:
    out = env.out()
    if not out.is_terminal:  # a pipe or a file: never cut a topic or module name short
        out.width = max(out.width, 240)
    table = Table(title=f"Channel-module graph of {safe(view.recording)}", title_justify="left")
    for col in ("channel", "encoding", "messages", "writers", "from", "readers", "from"):
        table.add_column(col, justify="right" if col == "messages" else "left")
    for topic, c in view.graph.topology.items():
        chans = view.channels.get(topic, [])
        encoding = ",".join(sorted({ch.message_encoding for ch in chans}))
        name = f"{topic} (control)" if c.is_control else topic
        table.add_row(
            safe(name), safe(encoding), str(view.messages.get(topic, 0)),
            safe(", ".join(c.writers)) or "-", safe(_source(c, "writers")),
            safe(", ".join(c.readers)) or "-", safe(_source(c, "readers")),
        )
    out.print(table)
    modules = view.graph.to_json()["modules"]
    if modules:
        out.print("Modules:")
        for name, io in modules.items():
            prose(out, f"  {name}: reads {', '.join(io['reads']) or '-'}; "
                      f"writes {', '.join(io['writes']) or '-'}")
    else:
        out.print("Modules: none (no channel names a writer or reader)")
    if view.control_channel:
        prose(out, f"Control channel: {view.control_channel} (from {view.control_source})")
    else:
        prose(out, f"Control channel: unknown ({view.control_source})")
    for note in view.notes:
        prose(out, f"Note: {note}")
    if view.hints:
        out.print("What to add:")
        for hint in view.hints:
            prose(out, f"  - {hint}")
    else:
        out.print("Nothing missing: every channel has writers and readers.")


def run(args: argparse.Namespace, env: Env) -> int:
    spec = load_cmg_file(args.cmg) if args.cmg else None
    view = build_view(args.recording, spec, args.control_channel, env)
    if args.format == "json":
        env.stdout.write(json_dumps(to_json(view), indent=2) + "\n")
    elif args.format == "dot":
        env.stdout.write(view.graph.to_dot())
    else:
        _print_text(view, env)
    return 0
