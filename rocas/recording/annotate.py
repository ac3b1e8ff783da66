"""Add the topology contract to an existing recording, copying everything else as it is.

A recording in another format (ROS 1 bag, rosbag2, Cyber RT record) is written out as MCAP
with the same channels and messages (:mod:`rocas.recording.convert`).

``annotate_recording`` streams an MCAP file record by record (constant memory: one chunk at
a time) into a new file in which the channels you name carry ``rocas.writers`` /
``rocas.readers`` (and one channel ``rocas.role = control``). Everything else is copied:
the header's profile and library, every schema (name, encoding, bytes), every channel
(topic, message encoding, other metadata), every message in file order with its log time,
publish time, sequence number and bytes, every attachment and metadata record, and the
chunk compression (zstd, lz4 or none; unchunked files stay unchunked). Schema and channel
ids are renumbered by the writer (they are file-local); which message belongs to which
channel is kept. The summary section (indexes, statistics) is rebuilt.

The output appears under its name only when the copy is complete.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mcap.exceptions import EndOfFile, McapError
from mcap.reader import make_reader
from mcap.records import (
    Attachment,
    Channel,
    Chunk,
    DataEnd,
    Footer,
    Header,
    Message,
    Metadata,
    Schema,
)
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter

from rocas._fs import atomic_path, refuse_overwriting
from rocas.errors import RecordingError, TopologyError
from rocas.recording.annotation import AnnotateReport, ChannelAnnotation, annotated_metadata
from rocas.recording.convert import write_mcap
from rocas.recording.formats import open_recording
from rocas.recording.mcap_records import MAGIC
from rocas.recording.model import ChannelInfo, describe_error

_COMPRESSION = {"": CompressionType.NONE, "zstd": CompressionType.ZSTD,
                "lz4": CompressionType.LZ4}
_DEFAULT_CHUNK_SIZE = 1 << 20  # [bytes] mcap's default

#: The ``mcap`` CLI repairs damaged files; pip does not install it. What is installed with
#: rocas (``rerun mcap check``) shows where a file is damaged.
MCAP_CLI = ("the mcap CLI, a separate download from the foxglove/mcap releases; "
            "'rerun mcap check FILE', installed with rocas, shows where the damage is")
REPAIR_HINT = f"repair it with 'mcap recover' first ({MCAP_CLI})"


def read_channels(
    path: str | os.PathLike[str], warnings: list[str] | None = None
) -> tuple[list[ChannelInfo], dict[str, int]]:
    """The channels of a recording and message counts per topic, as fast as possible.

    Uses the summary section when the file has one (no pass over the messages); otherwise
    (a truncated or summary-less file) reads the file once with the damage-tolerant reader.

    Args:
        path: the recording.
        warnings: when given, the reader's warnings (truncation, skipped damage, one line
            each, without the ``rocas: warning:`` prefix) are appended to it; a file read
            from its summary adds none.

    Raises:
        InputError: the file is missing or not an MCAP file.
    """
    rec = open_recording(path)
    if rec.format != "mcap":  # other formats: one pass (they have no MCAP summary)
        rec.scan()
        if warnings is not None:
            warnings.extend(rec.report.warnings(str(path)))
        counts = {t: st.messages for t, st in rec.report.channel_stats.items()}
        return list(rec.channels.values()), counts
    try:
        with open(rec.path, "rb") as f:
            summary = make_reader(f).get_summary()
    except Exception:  # no or damaged summary: fall back to a streaming pass
        summary = None
    if summary is not None and summary.channels:
        infos = []
        for ch in summary.channels.values():
            schema = summary.schemas.get(ch.schema_id)
            infos.append(
                ChannelInfo(
                    id=ch.id, topic=ch.topic, message_encoding=ch.message_encoding,
                    schema_name=schema.name if schema else "",
                    schema_encoding=schema.encoding if schema else "",
                    schema_data=bytes(schema.data) if schema else b"",
                    metadata=dict(ch.metadata), schema_id=ch.schema_id,
                )
            )
        counts: dict[str, int] = {}
        if summary.statistics is not None:
            by_id = summary.statistics.channel_message_counts
            for ch in infos:
                counts[ch.topic] = counts.get(ch.topic, 0) + int(by_id.get(ch.id, 0))
        return infos, counts
    rec.scan()
    if warnings is not None:
        warnings.extend(rec.report.warnings(str(path)))
    counts = {t: st.messages for t, st in rec.report.channel_stats.items()}
    return list(rec.channels.values()), counts


class _Copier:
    """Writes the records of one input file into a new MCAP writer, renumbering ids."""

    def __init__(
        self,
        out: Any,
        annotations: Mapping[str, ChannelAnnotation],
        control_channel: str | None,
        chunk_size: int,
    ) -> None:
        self._out = out
        self._annotations = annotations
        self._control = control_channel
        self._chunk_size = chunk_size
        self.writer: McapWriter | None = None
        self.compression: str | None = None
        self._header: Header | None = None
        self._pending: list[Any] = []
        self._schema_ids: dict[int, int] = {0: 0}
        self._channel_ids: dict[int, int] = {}
        self.topics: set[str] = set()
        self.annotated: set[str] = set()
        self.counts = {"schemas": 0, "channels": 0, "messages": 0, "attachments": 0,
                       "metadata": 0}

    def _start(self, chunked: bool, compression: str) -> McapWriter:
        if compression not in _COMPRESSION:
            raise RecordingError(
                f"the recording uses chunk compression {compression!r}, which rocas cannot write",
                "recompress it with 'mcap compress' (zstd or lz4) first",
            )
        self.compression = compression if chunked else None
        writer = McapWriter(
            self._out,
            chunk_size=self._chunk_size,
            compression=_COMPRESSION[compression],
            use_chunking=chunked,
        )
        header = self._header or Header(profile="", library="")
        writer.start(profile=header.profile, library=header.library)
        self.writer = writer
        for rec in self._pending:
            self._write(rec)
        self._pending.clear()
        return writer

    def feed(self, record: Any) -> bool:
        """Copy one top-level record; returns False at the end of the data section."""
        if isinstance(record, Header):
            self._header = record
        elif isinstance(record, Chunk):
            if self.writer is None:
                self._start(True, record.compression)
            for inner in breakup_chunk(record, validate_crc=True):
                self._write(inner)
        elif isinstance(record, DataEnd | Footer):
            if self.writer is None:
                self._start(False, "")
            return False
        elif isinstance(record, Message) and self.writer is None:
            self._start(False, "")
            self._write(record)
        elif isinstance(record, Schema | Channel | Message | Attachment | Metadata):
            if self.writer is None:
                self._pending.append(record)
            else:
                self._write(record)
        # indexes, statistics and summary offsets are rebuilt by the writer
        return True

    def _write(self, rec: Any) -> None:
        w = self.writer
        assert w is not None
        if isinstance(rec, Message):
            try:
                channel_id = self._channel_ids[rec.channel_id]
            except KeyError:
                raise RecordingError(
                    f"a message refers to channel id {rec.channel_id}, which is not declared "
                    "before it",
                    "the file is damaged; " + REPAIR_HINT,
                ) from None
            w.add_message(channel_id=channel_id, log_time=rec.log_time, data=rec.data,
                          publish_time=rec.publish_time, sequence=rec.sequence)
            self.counts["messages"] += 1
        elif isinstance(rec, Schema):
            if rec.id not in self._schema_ids:
                self._schema_ids[rec.id] = w.register_schema(rec.name, rec.encoding, rec.data)
                self.counts["schemas"] += 1
        elif isinstance(rec, Channel):
            if rec.id in self._channel_ids:
                return
            try:
                schema_id = self._schema_ids[rec.schema_id]
            except KeyError:
                raise RecordingError(
                    f"channel {rec.topic} refers to schema id {rec.schema_id}, which is not "
                    "declared before it",
                    "the file is damaged; " + REPAIR_HINT,
                ) from None
            meta = annotated_metadata(
                rec.metadata, rec.topic, self._annotations.get(rec.topic), self._control
            )
            if meta != dict(rec.metadata):
                self.annotated.add(rec.topic)
            self.topics.add(rec.topic)
            self._channel_ids[rec.id] = w.register_channel(
                topic=rec.topic, message_encoding=rec.message_encoding,
                schema_id=schema_id, metadata=meta,
            )
            self.counts["channels"] += 1
        elif isinstance(rec, Attachment):
            w.add_attachment(create_time=rec.create_time, log_time=rec.log_time,
                             name=rec.name, media_type=rec.media_type, data=rec.data)
            self.counts["attachments"] += 1
        elif isinstance(rec, Metadata):
            w.add_metadata(rec.name, dict(rec.metadata))
            self.counts["metadata"] += 1


def _chunk_size(path: Path) -> int:
    """The largest uncompressed chunk of the input (from its summary), so chunks stay alike."""
    try:
        with open(path, "rb") as f:
            summary = make_reader(f).get_summary()
    except Exception:
        return _DEFAULT_CHUNK_SIZE
    if summary is None or not summary.chunk_indexes:
        return _DEFAULT_CHUNK_SIZE
    return max(ci.uncompressed_size for ci in summary.chunk_indexes)


def _damage(exc: BaseException, done: int, size: int, copying: bool, at_end: bool) -> str:
    """What is wrong with the input, in words, after ``exc`` stopped the copy.

    Args:
        exc: the exception the mcap library raised.
        done: where the last complete record ends [byte offset].
        size: the file's size [bytes].
        copying: whether the record was being copied (a chunk's inner records) rather than
            read from the file.
        at_end: whether reading had reached the end of the file.
    """
    if at_end and not copying:  # the mcap library reads short at the end, then fails anywhere
        if done >= size:
            return (f"is truncated: it ends at byte {size}, after a complete record but "
                    "before the end of its data section")
        return (f"is truncated: it ends at byte {size}, in the middle of the record that "
                f"starts at byte {done}")
    if copying and isinstance(exc, EndOfFile):
        return f"is damaged: a record inside the chunk at byte {done} ends early"
    return f"is damaged or truncated ({describe_error(exc)})"


def annotate_recording(
    source: str | os.PathLike[str],
    output: str | os.PathLike[str],
    annotations: Mapping[str, ChannelAnnotation],
    *,
    control_channel: str | None = None,
) -> AnnotateReport:
    """Copy ``source`` to ``output`` with topology metadata on the channels you name.

    Args:
        source: the recording to annotate (it is never modified).
        output: where to write the annotated copy; must not be ``source``.
        annotations: topic -> writers/readers; channels not named keep their metadata.
        control_channel: the channel to mark ``rocas.role = control`` (any other channel
            loses a control role); None keeps the recorded roles.

    Returns:
        What was copied and changed; ``missing`` lists named topics the file lacks.

    Raises:
        UsageError: ``output`` is ``source``.
        InputError: ``source`` is missing or not an MCAP file.
        RecordingError: ``source`` is damaged (the output is then not written).
        TopologyError: ``control_channel`` is not a channel of the recording.
    """
    src, dst = Path(source), Path(output)
    rec = open_recording(src)  # the uniform checks: exists, is a file, is a recording
    if rec.format != "mcap":  # a ROS bag or Cyber record: written out as MCAP
        return write_mcap(rec, dst, annotations, control_channel)  # type: ignore[arg-type]
    refuse_overwriting(src, dst)
    chunk_size = _chunk_size(src)
    with atomic_path(dst) as tmp, open(tmp, "wb") as out, open(rec.path, "rb") as f:
        copier = _Copier(out, annotations, control_channel, chunk_size)
        reader = StreamReader(f, emit_chunks=True, validate_crcs=True)
        ended = False
        done = len(MAGIC)  # where the last complete record ends [byte offset]
        copying = False  # False while a record is being read, True while it is copied
        try:
            for record in reader.records:
                copying = True
                if not copier.feed(record):
                    ended = True
                    break
                copying = False
                done = f.tell()
        except RecordingError:
            raise
        except (McapError, ValueError, EOFError, OSError, struct.error) as exc:
            raise RecordingError(
                f"{src} {_damage(exc, done, rec.size, copying, f.tell() >= rec.size)}; "
                "annotate copies complete recordings only",
                f"repair it first with 'mcap recover {src} -o FIXED.mcap' ({MCAP_CLI})",
            ) from None
        if not ended:
            raise RecordingError(
                f"{src} ends before its data section is complete",
                f"repair it first with 'mcap recover {src} -o FIXED.mcap' ({MCAP_CLI})",
            )
        if control_channel is not None and control_channel not in copier.topics:
            raise TopologyError(
                f"control channel {control_channel!r} is not in {src}",
                "choose one of: " + ", ".join(sorted(copier.topics)),
            )
        assert copier.writer is not None
        copier.writer.finish()
    header = copier._header
    return AnnotateReport(
        source=str(src),
        output=str(dst),
        profile=header.profile if header else "",
        compression=copier.compression,
        annotated=tuple(sorted(copier.annotated)),
        control_channel=control_channel,
        missing=tuple(sorted(set(annotations) - copier.topics)),
        **copier.counts,
    )

