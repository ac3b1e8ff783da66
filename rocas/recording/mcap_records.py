"""The bytes of an MCAP file, below the reader: record headers, chunks, the summary section.

What :class:`rocas.recording.reader.Recording` needs to take a record apart without trusting
its length fields: the header layout, the memory limits a length must respect, where a record
can plausibly start (to resume reading after damage), chunk inflation that never sizes a buffer
from a field it has not checked, the parse of a chunk's inner records (messages as plain
tuples, the hot path of every pass), and the summary section, found and CRC-checked even when
the data section before it changed length, then compared with a complete pass. Every function
here is stateless; damage is raised as :class:`ValueError` (or :class:`BadRecord` with the
offset) for the reader to count and skip.
"""

from __future__ import annotations

import io
import re
import struct
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, ChunkIndex, Schema, Statistics

from rocas.errors import InputError, RecordingError
from rocas.recording.model import ChannelInfo, describe_error

MAGIC = b"\x89MCAP0\r\n"
RECORD_HEADER = struct.Struct("<BQ")
CHUNK_HEAD = struct.Struct("<QQQII")  # start, end, uncompressed_size, crc, compression length
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
SPEC_OPCODES = frozenset(range(0x01, 0x10))
# a plausible record header: a spec opcode and a length below 4 GiB. A look-ahead, so that
# every offset is tried: a false candidate that overlaps a real header must not hide it.
_CANDIDATE = re.compile(rb"(?=[\x01-\x0f].{4}\x00\x00\x00\x00)", re.DOTALL)

_FOOTER = struct.Struct("<BQQQI")  # opcode, length, summary start, summary offset start, crc
_DATA_END_HEAD = RECORD_HEADER.pack(Opcode.DATA_END, 4)
#: How far before the footer a summary section that moved is looked for [bytes].
_SUMMARY_SEARCH_BYTES = 64 << 20


def check_mcap_file(path: Path) -> int:
    """The size [bytes] of the MCAP file at ``path``; raises for a path that is none."""
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


def read_summary(path: Path, size: int) -> tuple[SummarySection | None, str | None]:
    """(summary, problem) of :meth:`rocas.recording.reader.Recording.summary`.

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
                    if crc_ok(lo + at + RECORD_HEADER.size + 4):
                        found = lo + at + RECORD_HEADER.size + 4
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
        opcode, length = RECORD_HEADER.unpack_from(data, pos)
        start = pos + RECORD_HEADER.size
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


def summary_mismatches(
    summary: SummarySection,
    by_id: Mapping[int, int],
    first: int | None,
    last: int | None,
    chunks_read: Sequence[int],
    channels: Mapping[int, ChannelInfo],
) -> list[str]:
    """Where a complete pass disagrees with the summary section: its offset, the message counts
    per channel, the span of log times and the chunks (one line each; empty when they agree).

    Args:
        summary: the CRC-checked summary section.
        by_id: channel id -> message records the pass read.
        first, last: the earliest and latest log time read [ns] (None when no message was).
        chunks_read: offsets of the chunk records the pass met [bytes].
        channels: the channels declared in the data section (names for the lines).
    """
    out: list[str] = []
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
            names.update({cid: c.topic for cid, c in channels.items()})
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
    if indexed and indexed != sorted(chunks_read):
        moved = len(set(indexed) ^ set(chunks_read))
        out.append(
            f"the data section holds {len(chunks_read)} chunks, the summary's chunk "
            f"index lists {len(indexed)} ({moved} offsets differ): chunks were removed, "
            "repeated or moved"
        )
    return out


def peek(f: io.BufferedReader, offset: int, n: int) -> bytes:
    f.seek(offset)
    return f.read(n)


def chunk_header_ok(head: bytes, length: int) -> bool:
    """Whether a chunk's record length agrees with the lengths inside its header."""
    body = head[RECORD_HEADER.size :]
    if len(body) < CHUNK_HEAD.size:
        return False
    start, end, _, _, clen = CHUNK_HEAD.unpack_from(body)
    if clen > 16 or start > end or len(body) < CHUNK_HEAD.size + clen + 8:
        return False
    (records_length,) = struct.unpack_from("<Q", body, CHUNK_HEAD.size + clen)
    return records_length == length - (CHUNK_HEAD.size + clen + 8)


def plausible(f: io.BufferedReader, pos: int, size: int, depth: int = 2) -> bool:
    """Whether a record (and the ``depth`` records after it) could start at ``pos`` of the
    file ``f`` of ``size`` bytes."""
    for _ in range(depth + 1):
        if pos == size or (pos == size - len(MAGIC) and peek(f, pos, 8) == MAGIC):
            return True
        head = peek(f, pos, 64)
        if len(head) < RECORD_HEADER.size:
            return False
        opcode, length = RECORD_HEADER.unpack_from(head)
        if opcode not in SPEC_OPCODES or length > size - pos - RECORD_HEADER.size:
            return False
        if opcode == Opcode.CHUNK:
            return chunk_header_ok(head, length)
        if opcode == Opcode.FOOTER and pos + RECORD_HEADER.size + length != size - 8:
            return False
        pos += RECORD_HEADER.size + length
    return True


def resync(f: io.BufferedReader, start: int, size: int) -> int | None:
    """Offset of the next plausible record at or after ``start``, or None."""
    block = 4 << 20
    base = start
    while base < size:
        data = peek(f, base, block + 16)
        for m in _CANDIDATE.finditer(data):
            if m.start() >= block:
                break
            if plausible(f, base + m.start(), size):
                return base + m.start()
        base += block
    return None


def inflate(chunk: Chunk, limit: int) -> bytes:
    """The chunk's records, decompressed without trusting its size fields for allocation.

    ``limit`` is the largest uncompressed size accepted [bytes].
    """
    size = chunk.uncompressed_size
    if size > limit:
        raise ValueError(
            f"chunk claims {size} bytes uncompressed, more than rocas inflates "
            f"({amount(limit)}: {amount(MAX_CHUNK_BYTES)} or the file's size if larger)"
        )
    if chunk.compression == "":
        data = bytes(chunk.data)
    elif chunk.compression == "zstd":
        data = inflate_one_frame(chunk.data, size)
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


def inflate_one_frame(compressed: bytes, size: int) -> bytes | None:
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
MessageRecord = tuple[int, int, int, int, bytes]
_MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time


def message_record(data: bytes, start: int, length: int) -> MessageRecord:
    """The message record whose body is ``data[start : start + length]``."""
    if length < _MESSAGE_HEAD.size:
        raise ValueError(f"a message record of {length} bytes is shorter than its header")
    channel_id, sequence, log_time, publish_time = _MESSAGE_HEAD.unpack_from(data, start)
    return (channel_id, log_time, publish_time, sequence,
            data[start + _MESSAGE_HEAD.size : start + length])


def chunk_records(data: bytes) -> list[Schema | Channel | MessageRecord]:
    """Schema, channel and message records in a chunk's inflated data; raises on any damage."""
    view = memoryview(data)
    out: list[Schema | Channel | MessageRecord] = []
    append = out.append
    unpack_head = RECORD_HEADER.unpack_from
    unpack_message = _MESSAGE_HEAD.unpack_from
    head_size, message_head = RECORD_HEADER.size, _MESSAGE_HEAD.size
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


class BadRecord(Exception):
    """A record that cannot be read, at ``offset`` [bytes], and why."""

    def __init__(self, offset: int, reason: str) -> None:
        super().__init__(reason)
        self.offset = offset
        self.reason = reason


def amount(n: int) -> str:
    """A byte count for messages: whole MiB when it is one, else bytes."""
    return f"{n >> 20} MiB" if n >= 1 << 20 and n % (1 << 20) == 0 else f"{n} bytes"
