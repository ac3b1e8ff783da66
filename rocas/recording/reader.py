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
import struct
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Attachment, Channel, Chunk, Metadata, Schema

from rocas.recording import mcap_records
from rocas.recording.decoding import DecoderCache
from rocas.recording.integrity import CHECKSUM_KEY, checksum_problem
from rocas.recording.mcap_records import (
    MAGIC,
    RECORD_HEADER,
    SPEC_OPCODES,
    BadRecord,
    MessageRecord,
    SummarySection,
    amount,
    check_mcap_file,
    chunk_header_ok,
    chunk_records,
    inflate,
    message_record,
    peek,
    plausible,
    read_summary,
    resync,
    summary_mismatches,
)
from rocas.recording.model import (
    ChannelInfo,
    ChannelStats,
    DecodedMessage,
    RawMessage,
    ReadReport,
    describe_error,
)

#: Records a pass steps over without reading (indexes, statistics: the summary is checked apart).
_SKIPPED_OPCODES = frozenset({
    Opcode.HEADER, Opcode.MESSAGE_INDEX, Opcode.CHUNK_INDEX, Opcode.ATTACHMENT_INDEX,
    Opcode.METADATA_INDEX, Opcode.STATISTICS, Opcode.SUMMARY_OFFSET,
})
#: Records a pass loads into memory, whose length must respect the memory limit.
_LOADED_OPCODES = frozenset(
    {Opcode.CHUNK, Opcode.MESSAGE, Opcode.SCHEMA, Opcode.CHANNEL, Opcode.METADATA}
)


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
        self.size = check_mcap_file(self.path)
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
    ) -> Iterator[MessageRecord | Attachment]:
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

    def _walk(self, want_attachments: bool) -> Iterator[MessageRecord | Attachment]:
        with open(self.path, "rb", buffering=1 << 20) as f:
            pos = len(MAGIC)
            while True:
                f.seek(pos)
                head = f.read(RECORD_HEADER.size)
                if len(head) < RECORD_HEADER.size:
                    self._stop(pos, "the file ends without a footer", truncated=True)
                    return
                opcode, length = RECORD_HEADER.unpack(head)
                body_start = pos + RECORD_HEADER.size
                end = body_start + length
                problem = self._header_problem(f, pos, opcode, length)
                if problem is not None:
                    # the length (or opcode) cannot be trusted: find the next record instead
                    nxt = resync(f, pos + 1, self.size)
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
                    or opcode not in SPEC_OPCODES
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
                except BadRecord as exc:
                    if opcode == Opcode.CHUNK:
                        self.report.skipped_chunks.append((pos, exc.reason))
                    if not plausible(f, end, self.size, depth=1):
                        nxt = resync(f, pos + 1, self.size)
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
        remain = self.size - pos - RECORD_HEADER.size
        if length > remain:
            return f"record at offset {pos} claims {length} bytes but only {remain} remain"
        if opcode == 0 or 0x10 <= opcode < 0x80:
            return f"invalid record opcode {opcode:#04x} at offset {pos}"
        if (
            opcode in _LOADED_OPCODES
            and length > mcap_records.MAX_RECORD_BYTES
            and not plausible(f, pos + RECORD_HEADER.size + length, self.size, depth=1)
        ):
            # a long record is real only if the file goes on with records where it ends
            return (
                f"record at offset {pos} claims {length} bytes "
                f"(over {amount(mcap_records.MAX_RECORD_BYTES)}) but no record starts where it "
                "would end"
            )
        if opcode == Opcode.CHUNK and not chunk_header_ok(peek(f, pos, 64), length):
            return f"chunk at offset {pos} has inconsistent length fields"
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
                data = inflate(chunk, max(mcap_records.MAX_CHUNK_BYTES, self.size))
                del chunk
                records = chunk_records(data)
                del data
            except Exception as exc:  # any parse failure inside one chunk: skip the chunk
                raise BadRecord(offset, describe_error(exc)) from exc
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
                rec: Any = message_record(body, 0, len(body))
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
                    raise BadRecord(offset, f"{problem}; not used")
                self._metadata.append(
                    (md.name, {k: v for k, v in md.metadata.items() if k != CHECKSUM_KEY}))
                return
            elif opcode == Opcode.ATTACHMENT:
                rec = Attachment.read(stream)
                (crc,) = struct.unpack_from("<I", body, len(body) - 4)
                if crc != 0 and zlib.crc32(body[: len(body) - 4]) != crc:
                    raise BadRecord(offset, f"attachment {rec.name!r} at offset {offset} fails "
                                             "its CRC check")
            else:
                return  # other opcodes (header, indexes, unknown) carry nothing we need
        except (McapError, struct.error, ValueError, UnicodeDecodeError, EOFError) as exc:
            reason = f"unreadable record at offset {offset}: {describe_error(exc)}"
            raise BadRecord(offset, reason) from exc
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
            self._summary_read = read_summary(self.path, self.size)
        return self._summary_read

    def _check_summary(self, by_id: dict[int, int], first: int | None, last: int | None) -> None:
        """Compare a complete pass with the summary (:func:`summary_mismatches`) into the report.

        Args:
            by_id: channel id -> message records read; first, last: their earliest and latest
                log time [ns] (None when no message was read).
        """
        summary, problem = self.summary()
        if problem is not None:
            self.report.summary_problem = problem
        if summary is None:
            return
        self.report.summary_mismatches.extend(
            summary_mismatches(summary, by_id, first, last, self._pass_chunks, self.channels))

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
