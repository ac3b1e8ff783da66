"""``rocas annotate IN.mcap --cmg CMG.json -o OUT.mcap``: store the topology in a recording.

Copies the recording losslessly (schemas, channels, messages with their times and sequence
numbers, attachments, metadata records, chunk compression) and sets ``rocas.writers`` /
``rocas.readers`` on the channels the CMG file names, and ``rocas.role = control`` on its
control channel (or ``--control-channel``). The input is never modified.
"""

from __future__ import annotations

import argparse

from rocas._fs import check_parent_exists
from rocas.cli.console import Env, safe
from rocas.cli.inputs import load_cmg_file
from rocas.errors import TopologyError, UsageError
from rocas.recording.annotate import annotate_recording, read_channels

HELP = "copy a recording with the channel topology (a --cmg file) stored in its metadata"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("recording", metavar="IN.mcap", help="the recording to annotate")
    parser.add_argument("--cmg", metavar="FILE",
                        help="CMG JSON file: the modules' reads and writes, control_channel")
    parser.add_argument("--control-channel", metavar="TOPIC",
                        help="mark this channel rocas.role=control (overrides the CMG file)")
    parser.add_argument("-o", "--output", metavar="OUT.mcap", required=True,
                        help="where to write the annotated copy (not the input)")


def run(args: argparse.Namespace, env: Env) -> int:
    if not args.cmg and not args.control_channel:
        raise UsageError(
            "nothing to annotate",
            "give --cmg FILE (and/or --control-channel TOPIC)",
        )
    check_parent_exists(args.output)
    spec = load_cmg_file(args.cmg) if args.cmg else None
    infos, _ = read_channels(args.recording)
    topics = {c.topic for c in infos}
    if args.control_channel and args.control_channel not in topics:
        raise TopologyError(
            f"control channel {args.control_channel!r} (from --control-channel) is not in "
            f"{args.recording}",
            "choose one of: " + ", ".join(sorted(topics)),
        )
    annotations = {}
    control = args.control_channel
    if spec is not None:
        for line in spec.missing_channel_warnings(topics, args.recording):
            env.warn(line)
        annotations = {t: a for t, a in spec.annotations().items() if t in topics}
        if control is None and spec.control_channel in topics:
            control = spec.control_channel
    report = annotate_recording(args.recording, args.output, annotations,
                                control_channel=control)
    out = env.out()
    compression = (
        "unchunked" if report.compression is None
        else f"{report.compression or 'uncompressed'} chunks"
    )
    out.print(f"wrote {safe(report.output)}")
    changed = ", ".join(report.annotated) if report.annotated else "none (already as given)"
    out.print(f"  topology set on {len(report.annotated)} channel(s): {safe(changed)}")
    if report.control_channel:
        out.print(f"  control channel: {safe(report.control_channel)}")
    out.print(
        f"  copied {report.schemas} schemas, {report.channels} channels, {report.messages} "
        f"messages, {report.attachments} attachments, {report.metadata} metadata records "
        f"({compression}, profile {safe(report.profile or 'none')})"
    )
    out.print(f"  check it with: rocas cmg {safe(report.output)}")
    return 0
