"""MCAP copies of recordings in other formats (ROS 1 bags, rosbag2, Cyber RT records).

:func:`write_mcap` streams a :class:`~rocas.recording.foreign.ForeignRecording` into an MCAP
file whose channels are declared as the reader declares them (the ``ros1`` profile for bags,
``ros2`` for rosbag2, protobuf schemas flattened from Cyber's ProtoDesc), every message with
its log time, publish time, sequence number and bytes unchanged, optionally with the topology
contract set on the channels (``rocas annotate``). rocas reads the copy into exactly the same
messages as the original, so the two compare as equal (MDR 0 on every channel).

The copy appears under its name only when it is complete; a recording that is damaged or cut
short is refused (nothing is written), as ``rocas annotate`` refuses a damaged MCAP file.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from rocas._fs import atomic_path, refuse_overwriting
from rocas.errors import RecordingError, TopologyError
from rocas.recording.reader import ChannelInfo

if TYPE_CHECKING:
    from rocas.recording.annotate import AnnotateReport, ChannelAnnotation
    from rocas.recording.foreign import ForeignRecording

#: Chunk size of the copies [bytes] (the mcap library's default).
CHUNK_BYTES = 1 << 20


def write_mcap(
    rec: ForeignRecording,
    output: str | os.PathLike[str],
    annotations: Mapping[str, ChannelAnnotation] | None = None,
    control_channel: str | None = None,
) -> AnnotateReport:
    """Write ``rec`` as a zstd-chunked MCAP file at ``output``.

    Args:
        rec: the recording to copy (it is never modified).
        output: the MCAP file to write; must not be the source.
        annotations: topic -> writers/readers to set (``rocas annotate``); others kept.
        control_channel: the channel to mark ``rocas.role = control``; None keeps roles.

    Raises:
        RecordingError: the recording is damaged or cut short (nothing is written).
        TopologyError: ``control_channel`` is not a channel of the recording.
    """
    from mcap.writer import CompressionType
    from mcap.writer import Writer as McapWriter

    from rocas.recording.annotate import AnnotateReport, annotated_metadata

    annotations = annotations or {}
    src, dst = Path(rec.path), Path(output)
    refuse_overwriting(src, dst)
    rec.scan()
    topics = {ch.topic for ch in rec.channels.values()}
    if control_channel is not None and control_channel not in topics:
        raise TopologyError(
            f"control channel {control_channel!r} is not in {src}",
            "choose one of: " + ", ".join(sorted(topics)),
        )
    schemas: dict[tuple[str, str, bytes], int] = {}
    channel_ids: dict[int, int] = {}
    annotated: set[str] = set()
    messages = 0
    with atomic_path(dst) as tmp, open(tmp, "wb") as out:
        writer = McapWriter(out, chunk_size=CHUNK_BYTES, compression=CompressionType.ZSTD)
        writer.start(profile=rec.profile, library=f"rocas ({rec.format} reader)")

        def declare(ch: ChannelInfo) -> int:
            key = (ch.schema_name, ch.schema_encoding, ch.schema_data)
            sid = schemas.get(key)
            if sid is None:
                sid = schemas[key] = writer.register_schema(*key) if ch.schema_name else 0
            meta = annotated_metadata(ch.metadata, ch.topic, annotations.get(ch.topic),
                                      control_channel)
            if meta != ch.metadata:
                annotated.add(ch.topic)
            cid = channel_ids[ch.id] = writer.register_channel(
                topic=ch.topic, message_encoding=ch.message_encoding, schema_id=sid,
                metadata=meta)
            return cid

        for ch, log_time, publish_time, sequence, data in rec._attributed():
            cid = channel_ids.get(ch.id)
            if cid is None:
                cid = declare(ch)
            writer.add_message(channel_id=cid, log_time=log_time, data=data,
                               publish_time=publish_time, sequence=sequence)
            messages += 1
        report = rec.report
        if (report.truncated or not report.complete or report.skipped_chunks
                or report.skipped_ranges):
            problem = (report.warnings(str(src)) or [f"{src} could not be read whole"])[0]
            raise RecordingError(
                f"{problem}; annotate copies complete recordings only",
                "repair the recording with its own tools first",
            )
        for ch in rec.channels.values():  # channels without messages are kept too
            if ch.id not in channel_ids:
                declare(ch)
        writer.finish()
    return AnnotateReport(
        source=str(src), output=str(dst), profile=rec.profile, compression="zstd",
        schemas=len([s for s in schemas.values() if s]), channels=len(channel_ids),
        messages=messages, attachments=0, metadata=0, annotated=tuple(sorted(annotated)),
        control_channel=control_channel,
        missing=tuple(sorted(set(annotations) - topics)),
    )
