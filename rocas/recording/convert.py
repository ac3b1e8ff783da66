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
from typing import TYPE_CHECKING, Any

from rocas._fs import atomic_path, refuse_overwriting
from rocas.errors import RecordingError, TopologyError
from rocas.recording.annotation import AnnotateReport, ChannelAnnotation, annotated_metadata
from rocas.recording.model import ChannelInfo, ReadReport

if TYPE_CHECKING:
    from rocas.recording.foreign import ForeignRecording

#: Chunk size of the copies [bytes] (the mcap library's default).
CHUNK_BYTES = 1 << 20


class _Channels:
    """The copy's schemas and channels, declared as messages first name them.

    Attributes:
        schemas: (name, encoding, bytes) -> schema id in the copy (0: no schema).
        ids: channel id in the source -> channel id in the copy.
        annotated: topics whose metadata the copy changes.
    """

    def __init__(self, writer: Any, annotations: Mapping[str, ChannelAnnotation],
                 control_channel: str | None) -> None:
        self.writer = writer
        self.annotations = annotations
        self.control_channel = control_channel
        self.schemas: dict[tuple[str, str, bytes], int] = {}
        self.ids: dict[int, int] = {}
        self.annotated: set[str] = set()

    def declare(self, ch: ChannelInfo) -> int:
        """Declare ``ch`` (and its schema, once) in the copy; returns its id there."""
        key = (ch.schema_name, ch.schema_encoding, ch.schema_data)
        sid = self.schemas.get(key)
        if sid is None:
            sid = self.schemas[key] = self.writer.register_schema(*key) if ch.schema_name else 0
        meta = annotated_metadata(ch.metadata, ch.topic, self.annotations.get(ch.topic),
                                  self.control_channel)
        if meta != ch.metadata:
            self.annotated.add(ch.topic)
        cid = self.ids[ch.id] = self.writer.register_channel(
            topic=ch.topic, message_encoding=ch.message_encoding, schema_id=sid,
            metadata=meta)
        return cid


def _refuse_incomplete(report: ReadReport, src: Path) -> None:
    """Raise :class:`RecordingError` when the pass that was copied did not read ``src`` whole."""
    if (report.truncated or not report.complete or report.skipped_chunks
            or report.skipped_ranges):
        problem = (report.warnings(str(src)) or [f"{src} could not be read whole"])[0]
        raise RecordingError(
            f"{problem}; annotate copies complete recordings only",
            "repair the recording with its own tools first",
        )


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
    messages = 0
    with atomic_path(dst) as tmp, open(tmp, "wb") as out:
        writer = McapWriter(out, chunk_size=CHUNK_BYTES, compression=CompressionType.ZSTD)
        writer.start(profile=rec.profile, library=f"rocas ({rec.format} reader)")
        channels = _Channels(writer, annotations, control_channel)
        for ch, log_time, publish_time, sequence, data in rec._attributed():
            cid = channels.ids.get(ch.id)
            if cid is None:
                cid = channels.declare(ch)
            writer.add_message(channel_id=cid, log_time=log_time, data=data,
                               publish_time=publish_time, sequence=sequence)
            messages += 1
        _refuse_incomplete(rec.report, src)
        for ch in rec.channels.values():  # channels without messages are kept too
            if ch.id not in channels.ids:
                channels.declare(ch)
        writer.finish()
    return AnnotateReport(
        source=str(src), output=str(dst), profile=rec.profile, compression="zstd",
        schemas=len([s for s in channels.schemas.values() if s]), channels=len(channels.ids),
        messages=messages, attachments=0, metadata=0,
        annotated=tuple(sorted(channels.annotated)), control_channel=control_channel,
        missing=tuple(sorted(set(annotations) - topics)),
    )
