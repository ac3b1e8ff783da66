"""Streaming, damage-tolerant reading of MCAP recordings.

The reader walks the file's data section record by record (constant memory: one chunk at
a time) using the record parsers of the ``mcap`` library. What it cannot read it reports
instead of failing, so that a log cut off by a power loss, or one with a corrupted chunk,
still yields everything before and around the damage:

- a file that ends early is read up to its last complete record (``truncated``);
- a chunk whose CRC or inner lengths are wrong is skipped (``skipped_chunks``);
- messages whose channel or schema never appeared, that have an encoding rocas cannot
  decode, or whose bytes do not parse, are counted per channel (``ChannelStats``).

Decoding needs no generated code: protobuf classes are built from the schema records,
with one ``mcap_protobuf`` decoder factory per opened file (a shared factory caches
classes by schema id and would decode a second file with the first file's classes).
JSON channels are decoded with :func:`json.loads`, ROS 2 (cdr) channels with ``rosbags``
(:mod:`rocas.recording.decoding`).
"""

from __future__ import annotations

import io
import os
import re
import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    Channel,
    Chunk,
    ChunkIndex,
    Metadata,
    Schema,
    Statistics,
)

from rocas.errors import InputError, RecordingError
from rocas.recording.decoding import DecoderCache
from rocas.recording.integrity import CHECKSUM_KEY, checksum_problem

MAGIC = b"\x89MCAP0\r\n"
_RECORD_HEADER = struct.Struct("<BQ")
_CHUNK_HEAD = struct.Struct("<QQQII")  # start, end, uncompressed_size, crc, compression length
#: Record body (a chunk as stored, a message, ...) above which a length field needs more
#: evidence before rocas loads it [bytes]. Every length must fit in the file; a longer one is
#: loaded only if a plausible record starts where it ends (memory then stays within a few
#: times the file's size), otherwise it is taken for a corrupted length field. Attachments are
#: only read on request.
MAX_RECORD_BYTES = 512 << 20
#: Uncompressed chunk size rocas always inflates [bytes]; a chunk may inflate to more if that
#: is still no more than the file's size. A larger ``uncompressed_size`` is skipped as damage
#: (a corrupted size field or a decompression bomb).
MAX_CHUNK_BYTES = 512 << 20
#: Opcodes the MCAP specification defines (0x80 and above are user-defined and skipped).
_SPEC_OPCODES = frozenset(range(0x01, 0x10))
# a plausible record header: a spec opcode and a length below 4 GiB. A look-ahead, so that
# every offset is tried: a false candidate that overlaps a real header must not hide it.
_CANDIDATE = re.compile(rb"(?=[\x01-\x0f].{4}\x00\x00\x00\x00)", re.DOTALL)
#: Encodings rocas decodes; any other channel is skipped with a warning.
DECODABLE_ENCODINGS = ("protobuf", "json", "cdr", "ros1")


@dataclass(frozen=True)
class ChannelInfo:
    """A channel as declared in the recording.

    Attributes:
        id: channel id in this file.
        topic: channel topic.
        message_encoding: e.g. ``"protobuf"``, ``"json"``, ``"ros1"``.
        schema_name: the schema's name (protobuf: the message's full name); "" if none.
        schema_encoding: e.g. ``"protobuf"``, ``"jsonschema"``; "" if none.
        schema_data: the raw schema bytes (protobuf: a serialized FileDescriptorSet).
        metadata: channel metadata (string key/value pairs).
        schema_id: the schema record's id in this file (0 when none).
    """

    id: int
    topic: str
    message_encoding: str
    schema_name: str
    schema_encoding: str
    schema_data: bytes
    metadata: dict[str, str]
    schema_id: int = 0


@dataclass
class ChannelStats:
    """What happened to one channel's messages while reading."""

    messages: int = 0
    decoded: int = 0
    undecodable: int = 0
    skipped_encoding: int = 0
    first_error: str | None = None


@dataclass(frozen=True)
class RawMessage:
    """One message record with its channel; ``data`` is the encoded payload."""

    channel: ChannelInfo
    log_time_ns: int
    publish_time_ns: int
    sequence: int
    data: bytes


@dataclass(frozen=True)
class DecodedMessage:
    """A message decoded to a protobuf object (or JSON value, or ROS 2 message).

    ``payload`` is the encoded bytes it was decoded from: two messages of one schema with
    equal payloads are equal, which is cheaper to check on the bytes than on the objects.
    """

    channel: ChannelInfo
    log_time_ns: int
    publish_time_ns: int
    sequence: int
    message: Any
    payload: bytes = b""


@dataclass
class ReadReport:
    """Damage and skips found while reading one file (filled in as the file is read)."""

    bytes_total: int = 0
    bytes_read: int = 0
    complete: bool = False
    truncated: bool = False
    stop_reason: str | None = None
    skipped_chunks: list[tuple[int, str]] = field(default_factory=list)
    skipped_ranges: list[tuple[int, int, str]] = field(default_factory=list)
    unknown_channel_messages: int = 0
    channels_from_summary: bool = False
    channel_stats: dict[str, ChannelStats] = field(default_factory=dict)
    summary_problem: str | None = None
    summary_mismatches: list[str] = field(default_factory=list)

    @property
    def intact(self) -> bool:
        """Whether the pass read every record to the end, skipped nothing, decoded every message
        and agreed with the summary section (when the file has one)."""
        return not (
            self.truncated or not self.complete or self.skipped_chunks or self.skipped_ranges
            or self.unknown_channel_messages or self.channels_from_summary
            or self.summary_problem or self.summary_mismatches
            or any(st.undecodable for st in self.channel_stats.values())
        )

    def warnings(self, name: str, skipped_encodings: bool = True) -> list[str]:
        """Human-readable warning lines (without the ``rocas: warning:`` prefix).

        ``skipped_encodings=False`` leaves out channels skipped for their encoding (for a
        caller that explains encodings itself).
        """
        out: list[str] = []
        if self.truncated:
            pct = 100.0 * self.bytes_read / max(self.bytes_total, 1)
            out.append(
                f"{name}: recording is truncated ({self.stop_reason}); read "
                f"{self.bytes_read} of {self.bytes_total} bytes ({pct:.1f}%), "
                f"stopped at offset {self.bytes_read}"
            )
        for offset, reason in self.skipped_chunks:
            out.append(f"{name}: skipped a corrupted chunk at offset {offset} ({reason})")
        for offset, size, reason in self.skipped_ranges:
            out.append(
                f"{name}: skipped {size} bytes of damaged data at offset {offset} ({reason}); "
                f"reading resumed at offset {offset + size}"
            )
        if self.channels_from_summary:
            out.append(
                f"{name}: channel declarations were lost with damaged data; "
                "recovered them from the file's summary section"
            )
        if self.summary_problem:
            out.append(f"{name}: {self.summary_problem}")
        out.extend(f"{name}: {line}" for line in self.summary_mismatches)
        if self.unknown_channel_messages:
            out.append(
                f"{name}: {self.unknown_channel_messages} messages reference channels "
                "that were never declared (lost with a damaged chunk?)"
            )
        for topic, st in sorted(self.channel_stats.items()):
            if st.skipped_encoding and skipped_encodings:
                out.append(
                    f"{name}: skipped channel {topic}: {st.skipped_encoding} messages in an "
                    "encoding rocas cannot decode (only protobuf, json, ROS 2 cdr and ROS 1 are "
                    "compared)"
                )
            if st.undecodable:
                out.append(
                    f"{name}: {st.undecodable} of {st.messages} messages on {topic} could "
                    f"not be decoded ({st.first_error})"
                )
        return out


def _check_file(path: Path) -> int:
    if not path.exists():
        raise InputError(f"no such file: {path}", "check the path")
    if path.is_dir():
        raise InputError(f"{path} is a directory, not an MCAP recording")
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            head = f.read(len(MAGIC))
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror}") from exc
    if size == 0:
        raise RecordingError(f"{path} is empty (0 bytes)", "give a non-empty MCAP recording")
    if head != MAGIC:
        raise RecordingError(
            f"{path} is not an MCAP file (it does not start with the MCAP magic bytes)",
            "rocas reads MCAP recordings; convert ROS bags with 'rosbags-convert --src BAG --dst OUT "
            "--dst-storage mcap' (installed with rocas; OUT is a folder holding the .mcap)",
        )
    return size


class Recording:
    """An MCAP file opened for streaming.

    Iterate :meth:`messages` (raw) or :meth:`decoded` once per pass; each pass re-reads the
    file. Channels, attachments and metadata are collected during a pass; :meth:`scan`
    runs a pass that collects them without decoding messages.
    """

    #: the recording's format (readers of other formats set theirs: ``ros1``, ``rosbag2``,
    #: ``cyber``); ``profile`` is the MCAP header's profile for those
    format = "mcap"

    def __init__(
        self, path: str | os.PathLike[str], decoders: DecoderCache | None = None
    ) -> None:
        self.path = Path(path)
        self.size = _check_file(self.path)
        self.channels: dict[int, ChannelInfo] = {}
        self.report = ReadReport(bytes_total=self.size)
        self._schemas: dict[int, Schema] = {}
        self._pending_channels: dict[int, Channel] = {}
        self._metadata: list[tuple[str, dict[str, str]]] = []
        self._attachment_names: list[tuple[str, str, int]] = []
        self._decoders: dict[int, Callable[[bytes], Any] | None] = {}
        self._decoder_cache = decoders if decoders is not None else DecoderCache()
        self._scanned = False
        self._summary_channels_tried = False
        self._summary_read: tuple[Any, str | None] | None = None
        self._pass_chunks: list[int] = []
        self.attachment_warnings: list[str] = []

    # -- records -----------------------------------------------------------------------
    def _channel_info(self, ch: Channel) -> ChannelInfo:
        schema = self._schemas.get(ch.schema_id)
        return ChannelInfo(
            id=ch.id,
            topic=ch.topic,
            message_encoding=ch.message_encoding,
            schema_name=schema.name if schema else "",
            schema_encoding=schema.encoding if schema else "",
            schema_data=bytes(schema.data) if schema else b"",
            metadata=dict(ch.metadata),
            schema_id=ch.schema_id,
        )

    def _register_channel(self, ch: Channel) -> None:
        if ch.id in self.channels and self.channels[ch.id].topic == ch.topic:
            return
        if ch.schema_id != 0 and ch.schema_id not in self._schemas:
            self._pending_channels[ch.id] = ch  # schema may follow (out of spec, but seen)
        self.channels[ch.id] = self._channel_info(ch)
        self.report.channel_stats.setdefault(ch.topic, ChannelStats())

    def _register_schema(self, schema: Schema) -> None:
        self._schemas[schema.id] = schema
        for cid, ch in list(self._pending_channels.items()):
            if ch.schema_id == schema.id:
                self.channels[cid] = self._channel_info(ch)
                del self._pending_channels[cid]

    def _records(
        self, want_attachments: bool = False
    ) -> Iterator[_MessageRecord | Attachment]:
        """Yield message records (and attachments if asked) in file order, tolerating damage.

        A message pass resets :attr:`report`; an attachment pass reports into a scratch one.
        """
        if want_attachments:
            kept, self.report = self.report, ReadReport(bytes_total=self.size)
            try:
                yield from self._walk(want_attachments)
            finally:
                scratch, self.report = self.report, kept
                self.attachment_warnings = [
                    line for line in scratch.warnings(str(self.path))
                    if line not in self.report.warnings(str(self.path))
                ]
            return
        yield from self._walk(want_attachments)

    def _walk(self, want_attachments: bool) -> Iterator[_MessageRecord | Attachment]:
        with open(self.path, "rb", buffering=1 << 20) as f:
            pos = len(MAGIC)
            while True:
                f.seek(pos)
                head = f.read(_RECORD_HEADER.size)
                if len(head) < _RECORD_HEADER.size:
                    self._stop(pos, "the file ends without a footer", truncated=True)
                    return
                opcode, length = _RECORD_HEADER.unpack(head)
                body_start = pos + _RECORD_HEADER.size
                end = body_start + length
                problem = self._header_problem(f, pos, opcode, length)
                if problem is not None:
                    # the length (or opcode) cannot be trusted: find the next record instead
                    nxt = self._resync(f, pos + 1)
                    if nxt is None:
                        self._stop(pos, problem, truncated=True)
                        return
                    self.report.skipped_ranges.append((pos, nxt - pos, problem))
                    pos = nxt
                    continue
                if opcode in (Opcode.DATA_END, Opcode.FOOTER):
                    self.report.bytes_read = self.size
                    self.report.complete = True
                    self._scanned = not want_attachments
                    return
                if (
                    opcode in _SKIPPED_OPCODES
                    or opcode not in _SPEC_OPCODES
                    or (opcode == Opcode.ATTACHMENT and not want_attachments)
                ):
                    pos = end
                    self.report.bytes_read = pos
                    continue
                if opcode == Opcode.CHUNK:
                    self._pass_chunks.append(pos)
                f.seek(body_start)
                try:  # no reference kept here: a chunk's stored bytes are freed once inflated
                    yield from self._handle_record(opcode, f.read(length), pos)
                except _BadRecord as exc:
                    if opcode == Opcode.CHUNK:
                        self.report.skipped_chunks.append((pos, exc.reason))
                    if not self._plausible(f, end, depth=1):
                        nxt = self._resync(f, pos + 1)
                        if nxt is None:
                            self._stop(pos, exc.reason, truncated=True)
                            return
                        end = nxt
                    if opcode != Opcode.CHUNK:
                        self.report.skipped_ranges.append((pos, end - pos, exc.reason))
                pos = end
                self.report.bytes_read = pos

    def _header_problem(self, f: io.BufferedReader, pos: int, opcode: int, length: int) -> str | None:
        """Why the record header at ``pos`` cannot be trusted, or None."""
        remain = self.size - pos - _RECORD_HEADER.size
        if length > remain:
            return f"record at offset {pos} claims {length} bytes but only {remain} remain"
        if opcode == 0 or 0x10 <= opcode < 0x80:
            return f"invalid record opcode {opcode:#04x} at offset {pos}"
        if (
            opcode in _LOADED_OPCODES
            and length > MAX_RECORD_BYTES
            and not self._plausible(f, pos + _RECORD_HEADER.size + length, depth=1)
        ):
            # a long record is real only if the file goes on with records where it ends
            return (
                f"record at offset {pos} claims {length} bytes (over {_amount(MAX_RECORD_BYTES)}) "
                "but no record starts where it would end"
            )
        if opcode == Opcode.CHUNK and not _chunk_header_ok(_peek(f, pos, 64), length):
            return f"chunk at offset {pos} has inconsistent length fields"
        return None

    def _plausible(self, f: io.BufferedReader, pos: int, depth: int = 2) -> bool:
        """Whether a record (and the ``depth`` records after it) could start at ``pos``."""
        for _ in range(depth + 1):
            if pos == self.size or (pos == self.size - len(MAGIC) and _peek(f, pos, 8) == MAGIC):
                return True
            head = _peek(f, pos, 64)
            if len(head) < _RECORD_HEADER.size:
                return False
            opcode, length = _RECORD_HEADER.unpack_from(head)
            if opcode not in _SPEC_OPCODES or length > self.size - pos - _RECORD_HEADER.size:
                return False
            if opcode == Opcode.CHUNK:
                return _chunk_header_ok(head, length)
            if opcode == Opcode.FOOTER and pos + _RECORD_HEADER.size + length != self.size - 8:
                return False
            pos += _RECORD_HEADER.size + length
        return True

    def _resync(self, f: io.BufferedReader, start: int) -> int | None:
        """Offset of the next plausible record at or after ``start``, or None."""
        block = 4 << 20
        base = start
        while base < self.size:
            data = _peek(f, base, block + 16)
            for m in _CANDIDATE.finditer(data):
                if m.start() >= block:
                    break
                if self._plausible(f, base + m.start()):
                    return base + m.start()
            base += block
        return None

    def _stop(self, offset: int, reason: str, truncated: bool) -> None:
        self.report.bytes_read = offset
        self.report.truncated = truncated
        self.report.stop_reason = reason
        self._scanned = True

    def _handle_record(self, opcode: int, body: bytes, offset: int) -> Iterator[Any]:
        stream = ReadDataStream(io.BytesIO(body))
        if opcode == Opcode.CHUNK:
            try:
                chunk = Chunk.read(stream)
                del body, stream  # the chunk holds a copy of its data
                data = _inflate(chunk, max(MAX_CHUNK_BYTES, self.size))
                del chunk
                records = _chunk_records(data)
                del data
            except Exception as exc:  # any parse failure inside one chunk: skip the chunk
                raise _BadRecord(offset, describe_error(exc)) from exc
            for rec in records:
                if type(rec) is tuple:
                    yield rec
                elif isinstance(rec, Schema):
                    self._register_schema(rec)
                elif isinstance(rec, Channel):
                    self._register_channel(rec)
            return
        try:
            if opcode == Opcode.MESSAGE:
                rec: Any = _message_record(body, 0, len(body))
            elif opcode == Opcode.SCHEMA:
                self._register_schema(Schema.read(stream))
                return
            elif opcode == Opcode.CHANNEL:
                self._register_channel(Channel.read(stream))
                return
            elif opcode == Opcode.METADATA:
                md = Metadata.read(stream)
                problem = checksum_problem(md.name, md.metadata)
                if problem is not None:
                    raise _BadRecord(offset, f"{problem}; not used")
                self._metadata.append(
                    (md.name, {k: v for k, v in md.metadata.items() if k != CHECKSUM_KEY}))
                return
            elif opcode == Opcode.ATTACHMENT:
                rec = Attachment.read(stream)
                (crc,) = struct.unpack_from("<I", body, len(body) - 4)
                if crc != 0 and zlib.crc32(body[: len(body) - 4]) != crc:
                    raise _BadRecord(offset, f"attachment {rec.name!r} at offset {offset} fails "
                                             "its CRC check")
            else:
                return  # other opcodes (header, indexes, unknown) carry nothing we need
        except (McapError, struct.error, ValueError, UnicodeDecodeError, EOFError) as exc:
            reason = f"unreadable record at offset {offset}: {describe_error(exc)}"
            raise _BadRecord(offset, reason) from exc
        yield rec

    # -- public passes ------------------------------------------------------------------
    def messages(self) -> Iterator[RawMessage]:
        """Every readable message, in file order (each call is a new pass).

        A pass that reaches the end of the file compares what it read with the summary
        section's statistics and chunk indexes (:meth:`_check_summary`).
        """
        for ch, log_time, publish_time, sequence, data in self._attributed():
            yield RawMessage(ch, log_time, publish_time, sequence, data)

    def _attributed(self) -> Iterator[tuple[ChannelInfo, int, int, int, bytes]]:
        """:meth:`messages` as tuples (channel, log time, publish time, sequence, payload)."""
        self.report = ReadReport(bytes_total=self.size)
        self._pass_chunks = []
        stats = self.report.channel_stats
        by_id: dict[int, int] = {}
        first, last = None, None
        channels = self.channels
        # channel id -> (its ChannelInfo, its stats) while the declaration stands
        known: dict[int, tuple[ChannelInfo, ChannelStats]] = {}
        for rec in self._records():
            channel_id, t, publish_time, sequence, data = rec  # type: ignore[misc]
            by_id[channel_id] = by_id.get(channel_id, 0) + 1
            if first is None:
                first = last = t
            elif t < first:
                first = t
            elif t > last:  # type: ignore[operator]
                last = t
            ch = channels.get(channel_id)
            if ch is None and not self._summary_channels_tried:
                self._channels_from_summary()
                ch = channels.get(channel_id)
            if ch is None:
                self.report.unknown_channel_messages += 1
                continue
            entry = known.get(channel_id)
            if entry is None or entry[0] is not ch:
                st = stats.get(ch.topic)
                if st is None:
                    st = stats[ch.topic] = ChannelStats()
                entry = known[channel_id] = (ch, st)
            entry[1].messages += 1
            yield ch, t, publish_time, sequence, data
        if self.report.complete:
            self._check_summary(by_id, first, last)

    def decoded(self, topics: set[str] | None = None) -> Iterator[DecodedMessage]:
        """Every message that decodes, in file order; failures are counted, not raised."""
        stats = None
        for ch, log_time, publish_time, sequence, data in self._attributed():
            if topics is not None and ch.topic not in topics:
                continue
            if stats is not self.report.channel_stats:
                stats = self.report.channel_stats
            st = stats[ch.topic]
            decode = self._decoders[ch.id] if ch.id in self._decoders else self._decoder(ch)
            if decode is None:
                st.skipped_encoding += 1
                continue
            try:
                obj = decode(data)
            except Exception as exc:  # a foreign file can hold anything
                st.undecodable += 1
                if st.first_error is None:
                    st.first_error = describe_error(exc)
                continue
            st.decoded += 1
            yield DecodedMessage(ch, log_time, publish_time, sequence, obj, data)

    def undecoded(self) -> Iterator[tuple[ChannelInfo, int, bytes, Callable[[bytes], Any]]]:
        """Every message rocas has a decoder for, in file order, *not* decoded:
        (channel, log time [ns], payload, decoder), for a caller that decodes only what it
        needs (two equal payloads of one schema are one message, decoded once).

        The pass's report counts each of these messages as decoded (and the others as skipped
        for their encoding, as :meth:`decoded` does). A caller that then finds a payload its
        decoder refuses holds a report that counted it wrongly, and must read again with
        :meth:`decoded`, which counts it as undecodable and leaves it out.
        """
        stats = None
        decoders = self._decoders
        for ch, log_time, _publish_time, _sequence, data in self._attributed():
            if stats is not self.report.channel_stats:
                stats = self.report.channel_stats
            decode = decoders[ch.id] if ch.id in decoders else self._decoder(ch)
            if decode is None:
                stats[ch.topic].skipped_encoding += 1
                continue
            stats[ch.topic].decoded += 1
            yield ch, log_time, data, decode

    def scan(self) -> Recording:
        """Read the file once to learn its channels, metadata and damage; returns self."""
        if not self._scanned:
            for _ in self.messages():
                pass
        return self

    def _channels_from_summary(self) -> None:
        """Declare the channels (and schemas) the summary section repeats.

        Called when a message names a channel not seen yet, typically because the chunk that
        declared it was damaged: a complete file repeats every declaration in its summary.
        """
        self._summary_channels_tried = True
        summary, _ = self.summary()
        if summary is None:  # no or damaged summary: the messages stay unattributed
            return
        for schema in summary.schemas.values():
            if schema.id not in self._schemas:
                self._register_schema(schema)
        for ch in summary.channels.values():
            if ch.id not in self.channels:
                self._register_channel(ch)
        self.report.channels_from_summary = True

    def summary_start_time_ns(self) -> int | None:
        """Earliest message log time from the file's summary statistics, if it has them.

        A truncated file has no summary, and a damaged one is not trusted; callers then fall
        back to the first message read.
        """
        summary, _ = self.summary()
        stats = summary.statistics if summary is not None else None
        if stats is None or stats.message_count == 0:
            return None
        return int(stats.message_start_time)

    def summary(self) -> tuple[SummarySection | None, str | None]:
        """(the summary section, why it cannot be used): read once, checked against its CRC.

        ``(None, None)`` when the file has no summary (it ends early, or was written without
        one); ``(None, reason)`` when the summary is damaged, in which case nothing in it is
        used (its start time would misalign the recording, its channels misattribute messages).
        """
        if self._summary_read is None:
            self._summary_read = _read_summary(self.path, self.size)
        return self._summary_read

    def _check_summary(self, by_id: dict[int, int], first: int | None, last: int | None) -> None:
        """Compare a complete pass with the summary: message counts per channel, chunks, span.

        Args:
            by_id: channel id -> message records read; first, last: their earliest and latest
                log time [ns] (None when no message was read).
        """
        summary, problem = self.summary()
        if problem is not None:
            self.report.summary_problem = problem
        if summary is None:
            return
        out = self.report.summary_mismatches
        if summary.shift:
            out.append(
                f"the data section is {abs(summary.shift)} bytes "
                f"{'longer' if summary.shift > 0 else 'shorter'} than when the summary section "
                "was written"
            )
        stats = summary.statistics
        if stats is not None:
            listed = {int(k): int(v) for k, v in stats.channel_message_counts.items()}
            read = sum(by_id.values())
            differ = sorted(cid for cid in set(listed) | set(by_id)
                            if listed.get(cid, 0) != by_id.get(cid, 0))
            if differ or (stats.message_count and stats.message_count != read):
                names = {c.id: c.topic for c in summary.channels.values()}
                names.update({cid: c.topic for cid, c in self.channels.items()})
                detail = ", ".join(
                    f"{names.get(cid, f'channel {cid}')} {by_id.get(cid, 0)} of {listed.get(cid, 0)}"
                    for cid in differ[:4]
                ) + (f", and {len(differ) - 4} more channels" if len(differ) > 4 else "")
                out.append(
                    f"read {read} messages, the summary section lists {stats.message_count} "
                    f"({detail or 'per channel as listed'}): messages were lost, repeated or "
                    "added after the summary was written"
                )
            elif read and first is not None and last is not None and (
                first != stats.message_start_time or last != stats.message_end_time
            ):
                out.append(
                    f"messages span log times {first}-{last} ns, the summary section says "
                    f"{stats.message_start_time}-{stats.message_end_time} ns"
                )
        indexed = sorted(ci.chunk_start_offset for ci in summary.chunk_indexes)
        if indexed and indexed != sorted(self._pass_chunks):
            moved = len(set(indexed) ^ set(self._pass_chunks))
            out.append(
                f"the data section holds {len(self._pass_chunks)} chunks, the summary's chunk "
                f"index lists {len(indexed)} ({moved} offsets differ): chunks were removed, "
                "repeated or moved"
            )

    def warnings(self, name: str) -> list[str]:
        """The last message pass's warnings plus those of the last attachment pass."""
        return self.report.warnings(name) + [
            w.replace(str(self.path), name, 1) for w in self.attachment_warnings
        ]

    def attachments(self) -> Iterator[Attachment]:
        """Every readable attachment record (a separate pass over the file)."""
        for rec in self._records(want_attachments=True):
            if isinstance(rec, Attachment):
                yield rec

    def attachment(self, name: str) -> bytes | None:
        """The data of the first attachment called ``name``, or None."""
        for att in self.attachments():
            if att.name == name:
                return bytes(att.data)
        return None

    @property
    def metadata(self) -> list[tuple[str, dict[str, str]]]:
        """Metadata records seen so far (complete after a full pass)."""
        return list(self._metadata)

    def topics(self) -> dict[str, ChannelInfo]:
        """Channels by topic (after a pass; the last declaration of a topic wins)."""
        return {ch.topic: ch for ch in self.channels.values()}

    # -- decoding -----------------------------------------------------------------------
    def _decoder(self, ch: ChannelInfo) -> Callable[[bytes], Any] | None:
        if ch.id in self._decoders:
            return self._decoders[ch.id]
        decoder = self._decoder_cache.decoder(
            ch.message_encoding, ch.schema_name, ch.schema_encoding, ch.schema_data
        )
        self._decoders[ch.id] = decoder
        return decoder



_SKIPPED_OPCODES = frozenset(
    {
        Opcode.HEADER,
        Opcode.MESSAGE_INDEX,
        Opcode.CHUNK_INDEX,
        Opcode.ATTACHMENT_INDEX,
        Opcode.METADATA_INDEX,
        Opcode.STATISTICS,
        Opcode.SUMMARY_OFFSET,
    }
)


_LOADED_OPCODES = frozenset(
    {Opcode.CHUNK, Opcode.MESSAGE, Opcode.SCHEMA, Opcode.CHANNEL, Opcode.METADATA}
)


_FOOTER = struct.Struct("<BQQQI")  # opcode, length, summary start, summary offset start, crc
_DATA_END_HEAD = _RECORD_HEADER.pack(Opcode.DATA_END, 4)
#: How far before the footer a summary section that moved is looked for [bytes].
_SUMMARY_SEARCH_BYTES = 64 << 20


@dataclass(frozen=True)
class SummarySection:
    """The parts of an MCAP summary section rocas checks a pass against.

    Attributes:
        schemas, channels: declarations by id.
        statistics: the Statistics record, or None.
        chunk_indexes: every ChunkIndex record.
        shift: where the summary was found minus where the footer says it starts [bytes];
            not 0 when the data section grew or shrank after the file was written.
    """

    schemas: dict[int, Schema]
    channels: dict[int, Channel]
    statistics: Statistics | None
    chunk_indexes: list[ChunkIndex]
    shift: int = 0


def _read_summary(path: Path, size: int) -> tuple[SummarySection | None, str | None]:
    """(summary, problem) of :meth:`Recording.summary`.

    The summary is where the footer says, or, when the data section before it changed length
    (a chunk removed or repeated), right after the Data End record found by searching back from
    the footer; either way its CRC must match before anything in it is used.
    """
    tail = len(MAGIC) + _FOOTER.size
    if size < len(MAGIC) + tail:
        return None, None
    try:
        with open(path, "rb") as f:
            f.seek(size - tail)
            footer = f.read(tail)
            opcode, length, start, _, crc = _FOOTER.unpack_from(footer)
            if opcode != Opcode.FOOTER or length != 20 or footer[-len(MAGIC):] != MAGIC:
                return None, None  # no footer: the walk reports where the file ends
            if start == 0:
                return None, None  # written without a summary
            footer_pos = size - tail
            covered_end = footer_pos + _FOOTER.size - 4  # the CRC covers up to its own field

            def crc_ok(at: int) -> bool:
                if not len(MAGIC) <= at <= footer_pos:
                    return False
                f.seek(at)
                return zlib.crc32(f.read(covered_end - at)) == crc

            found: int | None = start if len(MAGIC) <= start <= footer_pos else None
            if crc != 0 and (found is None or not crc_ok(found)):
                found = None
                lo = max(len(MAGIC), footer_pos - _SUMMARY_SEARCH_BYTES)
                f.seek(lo)
                block = f.read(footer_pos - lo)
                at = block.rfind(_DATA_END_HEAD)
                while at >= 0:
                    if crc_ok(lo + at + _RECORD_HEADER.size + 4):
                        found = lo + at + _RECORD_HEADER.size + 4
                        break
                    at = block.rfind(_DATA_END_HEAD, 0, at)
            if found is None:
                return None, ("the summary section is damaged (it fails its CRC check); the "
                              "counts it lists could not be checked and nothing in it is used")
            f.seek(found)
            body = f.read(footer_pos - found)
        return _parse_summary(body, found - start), None
    except Exception as exc:  # a damaged summary is reported, never raised
        return None, (f"the summary section is unreadable ({describe_error(exc)}); the counts "
                      "it lists could not be checked")


def _parse_summary(data: bytes, shift: int) -> SummarySection:
    """The records of a summary section (``data``: its bytes up to the footer)."""
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    stats: Statistics | None = None
    indexes: list[ChunkIndex] = []
    pos = 0
    while pos < len(data):
        opcode, length = _RECORD_HEADER.unpack_from(data, pos)
        start = pos + _RECORD_HEADER.size
        if length > len(data) - start:
            raise ValueError(f"a summary record at byte {pos} claims {length} bytes")
        stream = ReadDataStream(io.BytesIO(data[start : start + length]))
        if opcode == Opcode.SCHEMA:
            sch = Schema.read(stream)
            schemas[sch.id] = sch
        elif opcode == Opcode.CHANNEL:
            ch = Channel.read(stream)
            channels[ch.id] = ch
        elif opcode == Opcode.STATISTICS:
            stats = Statistics.read(stream)
        elif opcode == Opcode.CHUNK_INDEX:
            indexes.append(ChunkIndex.read(stream))
        pos = start + length
    return SummarySection(schemas, channels, stats, indexes, shift)


def _peek(f: io.BufferedReader, offset: int, n: int) -> bytes:
    f.seek(offset)
    return f.read(n)


def _chunk_header_ok(head: bytes, length: int) -> bool:
    """Whether a chunk's record length agrees with the lengths inside its header."""
    body = head[_RECORD_HEADER.size :]
    if len(body) < _CHUNK_HEAD.size:
        return False
    start, end, _, _, clen = _CHUNK_HEAD.unpack_from(body)
    if clen > 16 or start > end or len(body) < _CHUNK_HEAD.size + clen + 8:
        return False
    (records_length,) = struct.unpack_from("<Q", body, _CHUNK_HEAD.size + clen)
    return records_length == length - (_CHUNK_HEAD.size + clen + 8)


def _inflate(chunk: Chunk, limit: int) -> bytes:
    """The chunk's records, decompressed without trusting its size fields for allocation.

    ``limit`` is the largest uncompressed size accepted [bytes].
    """
    size = chunk.uncompressed_size
    if size > limit:
        raise ValueError(
            f"chunk claims {size} bytes uncompressed, more than rocas inflates "
            f"({_amount(limit)}: {_amount(MAX_CHUNK_BYTES)} or the file's size if larger)"
        )
    if chunk.compression == "":
        data = bytes(chunk.data)
    elif chunk.compression == "zstd":
        data = _inflate_one_frame(chunk.data, size)
        if data is None:
            import zstandard

            reader = zstandard.ZstdDecompressor().stream_reader(
                io.BytesIO(chunk.data), read_across_frames=True
            )
            out = bytearray()
            while len(out) <= size:  # read in pieces: a lying frame header must not size a buffer
                piece = reader.read(min(4 << 20, size + 1 - len(out)))
                if not piece:
                    break
                out += piece
            data = bytes(out)
    elif chunk.compression == "lz4":
        import lz4.frame

        data = lz4.frame.LZ4FrameDecompressor().decompress(chunk.data, max_length=size + 1)
    else:
        raise ValueError(f"unsupported chunk compression {chunk.compression!r}")
    if len(data) != size:
        raise ValueError(f"chunk inflates to {len(data)} bytes, its header says {size}")
    if chunk.uncompressed_crc != 0 and zlib.crc32(data) != chunk.uncompressed_crc:
        raise ValueError(
            f"CRC mismatch (expected {chunk.uncompressed_crc:#010x}, "
            f"computed {zlib.crc32(data):#010x})"
        )
    return data


def _inflate_one_frame(compressed: bytes, size: int) -> bytes | None:
    """A chunk that is one zstd frame whose header gives ``size`` (what writers make),
    decompressed in one call into a buffer of that size; None for anything else (more frames,
    trailing bytes, another size, damage), which the streamed path reads as before."""
    import zstandard

    try:
        if zstandard.frame_content_size(compressed) != size:
            return None
        data = zstandard.ZstdDecompressor().decompress(compressed, allow_extra_data=False)
    except zstandard.ZstdError:
        return None
    return data if len(data) == size else None


#: A message record as the reader passes it on: (channel id, log time [ns], publish time [ns],
#: sequence, payload). A tuple, not an object: a pass creates one per message.
_MessageRecord = tuple[int, int, int, int, bytes]
_MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time


def _message_record(data: bytes, start: int, length: int) -> _MessageRecord:
    """The message record whose body is ``data[start : start + length]``."""
    if length < _MESSAGE_HEAD.size:
        raise ValueError(f"a message record of {length} bytes is shorter than its header")
    channel_id, sequence, log_time, publish_time = _MESSAGE_HEAD.unpack_from(data, start)
    return (channel_id, log_time, publish_time, sequence,
            data[start + _MESSAGE_HEAD.size : start + length])


def _chunk_records(data: bytes) -> list[Schema | Channel | _MessageRecord]:
    """Schema, channel and message records in a chunk's inflated data; raises on any damage."""
    view = memoryview(data)
    out: list[Schema | Channel | _MessageRecord] = []
    append = out.append
    unpack_head = _RECORD_HEADER.unpack_from
    unpack_message = _MESSAGE_HEAD.unpack_from
    head_size, message_head = _RECORD_HEADER.size, _MESSAGE_HEAD.size
    pos, n = 0, len(data)
    while pos < n:
        if n - pos < head_size:
            raise ValueError(f"a record header is cut off at byte {pos} of the chunk")
        opcode, length = unpack_head(data, pos)
        start = pos + head_size
        end = start + length
        if end > n:
            raise ValueError(f"inner record at byte {pos} claims {length} bytes, "
                             f"{n - start} remain in the chunk")
        if opcode == Opcode.MESSAGE:
            if length < message_head:
                raise ValueError(f"a message record of {length} bytes is shorter than its "
                                 "header")
            channel_id, sequence, log_time, publish_time = unpack_message(data, start)
            append((channel_id, log_time, publish_time, sequence, data[start + message_head:end]))
        elif opcode == Opcode.CHANNEL:
            append(Channel.read(ReadDataStream(io.BytesIO(view[start:end]))))
        elif opcode == Opcode.SCHEMA:
            append(Schema.read(ReadDataStream(io.BytesIO(view[start:end]))))
        pos = end
    return out


class _BadRecord(Exception):
    def __init__(self, offset: int, reason: str) -> None:
        super().__init__(reason)
        self.offset = offset
        self.reason = reason


def _amount(n: int) -> str:
    """A byte count for messages: whole MiB when it is one, else bytes."""
    return f"{n >> 20} MiB" if n >= 1 << 20 and n % (1 << 20) == 0 else f"{n} bytes"


def describe_error(exc: BaseException) -> str:
    """An exception in one line: its type, and the first line of its text if it has one."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__



def open_recording(
    path: str | os.PathLike[str], decoders: DecoderCache | None = None
) -> Recording:
    """Open a recording for streaming, whatever its format; raises :class:`InputError` if it
    is none rocas reads.

    The format is recognised from the file's first bytes (:func:`rocas.recording.formats.sniff`):
    MCAP is read by :class:`Recording`; ROS 1 bags and rosbag2 recordings by
    :mod:`rocas.recording.rosbag`, Cyber RT records by :mod:`rocas.recording.cyber`, each
    with :class:`Recording`'s interface (``format`` tells them apart). Pass one
    :class:`DecoderCache` to several recordings to decode identical schemas into identical
    classes.
    """
    from rocas.recording.formats import sniff

    p = Path(path)
    kind, size = sniff(p)
    if kind == "ros1":
        from rocas.recording.rosbag import Ros1Recording

        return Ros1Recording(p, size, decoders)  # type: ignore[return-value]
    if kind == "rosbag2":
        from rocas.recording.rosbag import Rosbag2Recording

        return Rosbag2Recording(p, size, decoders)  # type: ignore[return-value]
    if kind == "cyber":
        from rocas.recording.cyber import CyberRecording

        return CyberRecording(p, size, decoders)  # type: ignore[return-value]
    return Recording(path, decoders)
