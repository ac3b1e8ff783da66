"""Apollo Cyber RT ``.record`` files, read directly.

The format (Cyber RT's ``cyber/proto/record.proto`` and ``cyber/record/``): a file is a
sequence of sections, each a 16-byte head (``int32`` type, 4 bytes of padding, ``int64`` body
size [bytes], little endian) and a body that is one serialized protobuf message:

- type 0, ``Header`` (major/minor version, compression, chunk and channel counts, begin and
  end time [ns], message count, total size [bytes], ``is_complete``, ``index_position``), always
  the first section; its body is padded to :data:`HEADER_BYTES` whatever its size field says;
- type 4, ``Channel`` (name, message type, ``proto_desc``): one per channel, before its
  messages;
- type 1, ``ChunkHeader`` (begin and end time [ns], message count, raw size [bytes]), then
  type 2, ``ChunkBody``: repeated ``SingleMessage`` (channel name, time [ns], content bytes);
- type 3, ``Index``: where the sections are, at ``index_position``, written last.

A channel's schema is a ``ProtoDesc``: the message's ``FileDescriptorProto`` (field 1, bytes)
and the ``ProtoDesc`` of every file it imports (field 2, repeated), recursively.
:func:`descriptor_set` flattens it into a ``FileDescriptorSet`` (each file once, imports before
the files that use them), which is what MCAP's ``protobuf`` schemas are: a Cyber channel is
declared as an MCAP protobuf channel would be and decodes (and compares) the same way.

The walk reads sections in file order (the index is not needed) and tolerates damage: a file
cut short is read up to its last complete section (``truncated``); a chunk body that does not
parse is skipped (``skipped_chunks``); a section head whose type or size cannot be right stops
the pass with a warning. The header's ``is_complete`` flag and message count are checked against
what was read.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Iterator
from functools import lru_cache
from typing import Any

from rocas.errors import RecordingError
from rocas.recording.decoding import DecoderCache
from rocas.recording.foreign import ForeignRecording, Walked
from rocas.recording.model import ChannelInfo, describe_error

#: A section's head: type, padding, body size [bytes].
SECTION_HEAD = struct.Struct("<iiq")
#: The header section's body, padded to this size [bytes].
HEADER_BYTES = 2048
SECTION_HEADER, SECTION_CHUNK_HEADER, SECTION_CHUNK_BODY, SECTION_INDEX, SECTION_CHANNEL = range(5)
_COMPRESSION = {0: "", 1: "bz2", 2: "lz4"}


def looks_like_cyber(head: bytes) -> bool:
    """Whether a file's first bytes are a Cyber RT record's header section (type 0, a body of
    at most :data:`HEADER_BYTES`, starting with field 1 of ``Header``, its major version)."""
    if len(head) < SECTION_HEAD.size + 1:
        return False
    kind, pad, size = SECTION_HEAD.unpack_from(head)
    return kind == SECTION_HEADER and pad == 0 and 0 < size <= HEADER_BYTES and head[16] == 0x08


@lru_cache(maxsize=1)
def _record_classes() -> dict[str, Any]:
    """Protobuf classes of the record format's messages, built from a descriptor written
    here (field numbers as in ``cyber/proto/record.proto`` and ``proto_desc.proto``)."""
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    f = descriptor_pb2.FieldDescriptorProto
    fd = descriptor_pb2.FileDescriptorProto(name="rocas_cyber_record.proto",
                                            package="rocas.cyber", syntax="proto2")

    def message(name: str, *fields: tuple[str, int, int, str]) -> None:
        m = fd.message_type.add(name=name)
        for fname, number, ftype, type_name in fields:
            label = f.LABEL_REPEATED if fname.endswith("[]") else f.LABEL_OPTIONAL
            field = m.field.add(name=fname.rstrip("[]"), number=number, type=ftype, label=label)
            if type_name:
                field.type_name = f".rocas.cyber.{type_name}"

    u64, u32, i32, bts, string, boolean, msg = (
        f.TYPE_UINT64, f.TYPE_UINT32, f.TYPE_INT32, f.TYPE_BYTES, f.TYPE_STRING, f.TYPE_BOOL,
        f.TYPE_MESSAGE)
    message("Header", ("major_version", 1, u32, ""), ("minor_version", 2, u32, ""),
            ("compress", 3, i32, ""), ("chunk_interval", 4, u64, ""),
            ("segment_interval", 5, u64, ""), ("index_position", 6, u64, ""),
            ("chunk_number", 7, u64, ""), ("channel_number", 8, u64, ""),
            ("begin_time", 9, u64, ""), ("end_time", 10, u64, ""),
            ("message_number", 11, u64, ""), ("size", 12, u64, ""),
            ("is_complete", 13, boolean, ""), ("chunk_raw_size", 14, u64, ""),
            ("segment_raw_size", 15, u64, ""))
    message("Channel", ("name", 1, string, ""), ("message_type", 2, string, ""),
            ("proto_desc", 3, bts, ""))
    message("ChunkHeader", ("begin_time", 1, u64, ""), ("end_time", 2, u64, ""),
            ("message_number", 3, u64, ""), ("raw_size", 4, u64, ""))
    message("SingleMessage", ("channel_name", 1, string, ""), ("time", 2, u64, ""),
            ("content", 3, bts, ""))
    message("ChunkBody", ("messages[]", 1, msg, "SingleMessage"))
    message("ProtoDesc", ("desc", 1, bts, ""), ("dependencies[]", 2, msg, "ProtoDesc"))
    pool = descriptor_pool.DescriptorPool()
    pool.Add(fd)
    return {m.name: message_factory.GetMessageClass(pool.FindMessageTypeByName(
        f"rocas.cyber.{m.name}")) for m in fd.message_type}


def descriptor_set(proto_desc: bytes) -> bytes:
    """A Cyber ``ProtoDesc`` flattened into a serialized ``FileDescriptorSet``.

    Each file appears once (by name; the first description wins), every file after the files
    it imports. Raises ``ValueError`` when the bytes are not a ``ProtoDesc`` or hold no file.
    """
    from google.protobuf import descriptor_pb2

    cls = _record_classes()["ProtoDesc"]
    root = cls.FromString(proto_desc)
    out = descriptor_pb2.FileDescriptorSet()
    seen: set[str] = set()
    # iterative post-order walk: a deep or cyclic description cannot overflow the stack
    stack: list[tuple[Any, bool]] = [(root, False)]
    while stack:
        node, expanded = stack.pop()
        if not node.desc:
            continue
        fdp = descriptor_pb2.FileDescriptorProto.FromString(node.desc)
        if fdp.name in seen:
            continue
        if expanded:
            seen.add(fdp.name)
            out.file.append(fdp)
            continue
        stack.append((node, True))
        stack.extend((dep, False) for dep in reversed(node.dependencies))
    if not out.file:
        raise ValueError("the channel's ProtoDesc holds no file description")
    return out.SerializeToString()


class CyberRecording(ForeignRecording):
    """An Apollo Cyber RT record file (one file of a split recording: ``x.record.00000``)."""

    format = "cyber"
    profile = ""

    def __init__(self, path: str | os.PathLike[str], size: int,
                 decoders: DecoderCache | None = None) -> None:
        super().__init__(path, size, decoders)
        self.header = self._read_header()
        self._by_name: dict[str, ChannelInfo] = {}

    def _read_header(self) -> Any:
        with open(self.path, "rb") as f:
            head = f.read(SECTION_HEAD.size + HEADER_BYTES)
        kind, _, size = SECTION_HEAD.unpack_from(head)
        body = head[SECTION_HEAD.size : SECTION_HEAD.size + size]
        if len(head) < SECTION_HEAD.size + size:
            raise RecordingError(f"{self.path} is a Cyber RT record cut off inside its header "
                                 f"({self.size} bytes)", "give the complete record file")
        try:
            header = _record_classes()["Header"].FromString(body)
        except Exception as exc:
            raise RecordingError(
                f"{self.path} is a Cyber RT record whose header is damaged ({describe_error(exc)})",
                "give an undamaged record file",
            ) from None
        if header.compress not in (0, 1, 2):
            raise RecordingError(
                f"{self.path} is a Cyber RT record with an unknown compression "
                f"({header.compress})", "rewrite it uncompressed with 'cyber_recorder split'")
        return header

    def _channel(self, section: bytes) -> ChannelInfo:
        ch = _record_classes()["Channel"].FromString(section)
        try:
            fds = descriptor_set(ch.proto_desc)
        except Exception:  # its messages then count as undecodable, with the reason
            fds = b""
        known = self._by_name.get(ch.name)
        info = ChannelInfo(
            id=known.id if known is not None else len(self._by_name) + 1,
            topic=ch.name, message_encoding="protobuf",
            schema_name=ch.message_type if fds else "", schema_encoding="protobuf",
            schema_data=fds, metadata={}, schema_id=0,
        )
        info = self._declare(info)
        self._by_name[ch.name] = info
        return info

    def _walk(self) -> Iterator[Walked]:
        classes = _record_classes()
        body_cls = classes["ChunkBody"]
        decompress = _decompressor(_COMPRESSION[self.header.compress])
        report = self.report
        size = self.size
        read = 0
        with open(self.path, "rb", buffering=1 << 20) as f:
            pos = SECTION_HEAD.size + HEADER_BYTES
            while pos < size:
                f.seek(pos)
                head = f.read(SECTION_HEAD.size)
                if len(head) < SECTION_HEAD.size:
                    self._stop(pos, f"the file ends inside a section head at byte {pos}")
                    return
                kind, _, length = SECTION_HEAD.unpack(head)
                body_at = pos + SECTION_HEAD.size
                if not SECTION_HEADER < kind <= SECTION_CHANNEL or length < 0:
                    self._stop(pos, f"no valid section starts at byte {pos} (type {kind})")
                    return
                if body_at + length > size:
                    self._stop(pos, f"the {_KINDS[kind]} section at byte {pos} claims "
                                    f"{length} bytes, {size - body_at} remain")
                    return
                pos = body_at + length
                if kind == SECTION_CHANNEL:
                    try:
                        self._channel(f.read(length))
                    except Exception as exc:
                        report.skipped_ranges.append(
                            (body_at - SECTION_HEAD.size, length + SECTION_HEAD.size,
                             f"unreadable channel section: {describe_error(exc)}"))
                elif kind == SECTION_CHUNK_BODY:
                    try:
                        body = body_cls.FromString(decompress(f.read(length)))
                    except Exception as exc:
                        report.skipped_chunks.append((body_at - SECTION_HEAD.size,
                                                      describe_error(exc)))
                        continue
                    by_name = self._by_name
                    for m in body.messages:
                        ch = by_name.get(m.channel_name)
                        if ch is None:
                            report.unknown_channel_messages += 1
                            continue
                        read += 1
                        t = m.time
                        yield ch, t, t, 0, m.content
                report.bytes_read = pos
        report.bytes_read = size
        report.complete = True
        expected = self.header.message_number
        if not self.header.is_complete:
            report.summary_mismatches.append(
                "the record's header says it was not closed properly (is_complete false): "
                "its recorder was stopped before it finished")
        elif expected and expected != read + report.unknown_channel_messages:
            report.summary_mismatches.append(
                f"read {read} messages, the record's header lists {expected}")


_KINDS = {1: "chunk header", 2: "chunk body", 3: "index", 4: "channel"}


def _decompressor(kind: str) -> Any:
    """A function from a chunk body as stored to its protobuf bytes."""
    if kind == "bz2":
        import bz2

        return bz2.decompress
    if kind == "lz4":
        import lz4.frame

        return lz4.frame.decompress
    return _same


def _same(data: bytes) -> bytes:
    return data
