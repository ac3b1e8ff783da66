"""A ROS 1 bag read chunk by chunk in file order, without its index: for a bag whose recorder
was stopped before it wrote the index (``.bag.active``), or that was cut short or damaged.

The bag format 2.0 (ROS 1 wiki, "Bags/Format/2.0"): after the 13-byte magic, records of
``u32 header length, header, u32 data length, data``; a header is fields of ``u32 length,
name=value``, and its ``op`` field says what the record is: ``0x03`` bag header, ``0x05``
chunk (``compression`` none, bz2 or lz4; its data holds ``0x07`` connection and ``0x02``
message records), ``0x04`` index data, ``0x06`` chunk info, ``0x07`` connection (repeated in
the index section). A connection's data is a header too: ``topic``, ``type``, ``md5sum``,
``message_definition``, ``callerid``, ``latching``. A message's header holds ``conn`` (u32)
and ``time`` (u32 seconds, u32 nanoseconds).

:func:`walk_chunks` yields what it can and stops at the first record that is cut off or
cannot be read, saying where and why.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass

MAGIC = b"#ROSBAG V2.0\n"
OP_MSG_DATA, OP_BAG_HEADER, OP_INDEX_DATA, OP_CHUNK, OP_CHUNK_INFO, OP_CONNECTION = (
    0x02, 0x03, 0x04, 0x05, 0x06, 0x07)
_U32 = struct.Struct("<I")
_TIME = struct.Struct("<II")


class BagDamage(Exception):
    """A record that is cut off or cannot be read; ``offset`` is where it starts [bytes]."""

    def __init__(self, offset: int, reason: str) -> None:
        super().__init__(reason)
        self.offset = offset
        self.reason = reason


@dataclass(frozen=True)
class Connection:
    """A connection record: id, topic and the fields of its connection header."""

    id: int
    topic: str
    fields: dict[str, bytes]


def parse_header(data: bytes | memoryview) -> dict[str, bytes]:
    """The ``name=value`` fields of a record header; raises ``ValueError`` if malformed."""
    fields: dict[str, bytes] = {}
    pos, n = 0, len(data)
    while pos < n:
        if n - pos < 4:
            raise ValueError("a header field length is cut off")
        (length,) = _U32.unpack_from(data, pos)
        pos += 4
        if length > n - pos:
            raise ValueError(f"a header field claims {length} bytes, {n - pos} remain")
        field = bytes(data[pos : pos + length])
        pos += length
        name, sep, value = field.partition(b"=")
        if not sep:
            raise ValueError("a header field has no '='")
        fields[name.decode("ascii", "replace")] = value
    return fields


def _records(data: bytes | memoryview, base: int, partial: bool = False,
             ) -> Iterator[tuple[int, dict[str, bytes], memoryview, bool]]:
    """(offset, header, data, cut) of each record in ``data`` (``base``: its offset in the
    file). With ``partial``, a last record whose data is cut off is yielded with what remains
    of it and ``cut`` true (instead of raising)."""
    view = memoryview(data)
    pos, n = 0, len(view)
    while pos < n:
        if n - pos < 8:
            raise BagDamage(base + pos, f"a record is cut off at byte {base + pos}")
        (hlen,) = _U32.unpack_from(view, pos)
        if hlen > n - pos - 8:
            raise BagDamage(base + pos, f"the record at byte {base + pos} claims a {hlen}-byte "
                                        f"header, {max(0, n - pos - 8)} bytes remain")
        try:
            header = parse_header(view[pos + 4 : pos + 4 + hlen])
        except ValueError as exc:
            raise BagDamage(base + pos, f"unreadable record header at byte {base + pos}: "
                                        f"{exc}") from None
        (dlen,) = _U32.unpack_from(view, pos + 4 + hlen)
        start = pos + 8 + hlen
        if dlen > n - start:
            reason = (f"the record at byte {base + pos} claims {dlen} bytes of data, "
                      f"{n - start} remain")
            if not partial:
                raise BagDamage(base + pos, reason)
            yield base + pos, header, view[start:n], True
            raise BagDamage(base + n, f"the file ends inside the record that starts at byte "
                                      f"{base + pos}, which claims {dlen} bytes of data; "
                                      f"{n - start} remain")
        yield base + pos, header, view[start : start + dlen], False
        pos = start + dlen


def _decompressor(kind: bytes) -> Callable[[bytes], bytes] | None:
    if kind == b"none":
        return _same
    if kind == b"bz2":
        import bz2

        return bz2.decompress
    if kind == b"lz4":
        import lz4.frame

        return lz4.frame.decompress
    return None


def _same(data: bytes) -> bytes:
    return data


def walk_chunks(data: bytes | memoryview, on_chunk: Callable[[int], None] | None = None,
                ) -> Iterator[Connection | tuple[int, int, memoryview]]:
    """Connections and messages ``(connection id, log time [ns], payload)`` in file order.

    Args:
        data: the whole bag file (a memory map keeps memory flat: one chunk at a time).
        on_chunk: called with the offset where each chunk ends [bytes] (progress).

    Raises:
        BagDamage: at the first record that is cut off or cannot be read (everything before it
            has been yielded).
    """
    view = memoryview(data)
    if bytes(view[: len(MAGIC)]) != MAGIC:
        raise BagDamage(0, "the file does not start with '#ROSBAG V2.0'")
    for offset, header, body, cut in _records(view[len(MAGIC):], len(MAGIC), partial=True):
        op = header.get("op", b"\xff")[:1]
        if op == bytes([OP_CHUNK]):
            kind = header.get("compression", b"none")
            decompress = _decompressor(kind)
            if decompress is None:
                raise BagDamage(offset, f"chunk at byte {offset} has unknown compression "
                                        f"{kind.decode('ascii', 'replace')!r}")
            if cut and kind != b"none":
                continue  # a compressed chunk cut off cannot be read; _records raises next
            try:
                inner = decompress(body) if not cut else body
            except Exception as exc:
                raise BagDamage(offset, f"chunk at byte {offset} does not decompress "
                                        f"({type(exc).__name__})") from None
            # an uncompressed chunk cut off still holds the records before the cut
            yield from _chunk(inner, offset, cut)
            if on_chunk is not None:
                on_chunk(offset + len(body))
        elif op == bytes([OP_INDEX_DATA]) or op == bytes([OP_CHUNK_INFO]):
            continue
        elif op == bytes([OP_CONNECTION]) and not cut:
            yield _connection(header, body, offset)


def _chunk(inner: bytes | memoryview, offset: int, cut: bool,
           ) -> Iterator[Connection | tuple[int, int, memoryview]]:
    """The connections and messages of one chunk's records (the hot loop: one message record
    at a time, parsed with ``struct`` and no per-field objects)."""
    view = memoryview(inner)
    n = len(view)
    pos = 0
    u32 = _U32.unpack_from
    try:
        while pos < n:
            if n - pos < 8:
                raise BagDamage(pos, f"a record is cut off at byte {pos} of the chunk")
            (hlen,) = u32(view, pos)
            hend = pos + 4 + hlen
            if hend + 4 > n:
                raise BagDamage(pos, f"a record header at byte {pos} of the chunk claims "
                                     f"{hlen} bytes")
            conn = stamp = op = None
            at = pos + 4
            while at < hend:  # the header's fields: u32 length, name=value
                (flen,) = u32(view, at)
                f0 = at + 4
                at = f0 + flen
                if at > hend:
                    raise BagDamage(pos, f"a header field at byte {f0 - 4} of the chunk claims "
                                         f"{flen} bytes")
                if flen == 4 and view[f0 : f0 + 3] == b"op=":
                    op = view[f0 + 3]
                elif flen == 9 and view[f0 : f0 + 5] == b"conn=":
                    (conn,) = u32(view, f0 + 5)
                elif flen == 13 and view[f0 : f0 + 5] == b"time=":
                    sec, nsec = _TIME.unpack_from(view, f0 + 5)
                    stamp = sec * 1_000_000_000 + nsec
            (dlen,) = u32(view, hend)
            start = hend + 4
            end = start + dlen
            if end > n:
                raise BagDamage(pos, f"a record at byte {pos} of the chunk claims {dlen} bytes "
                                     f"of data, {n - start} remain")
            if op == OP_MSG_DATA:
                if conn is None or stamp is None:
                    raise BagDamage(pos, "a message record lacks its conn or time field")
                yield conn, stamp, view[start:end]
            elif op == OP_CONNECTION:
                yield _connection(parse_header(view[pos + 4 : hend]), view[start:end], offset)
            pos = end
    except BagDamage as exc:
        if cut:  # the chunk ends where the file does: the outer walk says so
            return
        raise BagDamage(offset, f"chunk at byte {offset} is damaged inside ({exc.reason})"
                        ) from None
    except (ValueError, struct.error) as exc:
        raise BagDamage(offset, f"chunk at byte {offset} is damaged inside ({exc})") from None


def index_connections(data: bytes | memoryview) -> list[Connection]:
    """The connection records of the bag's index section (where the bag header's
    ``index_pos`` says), read without reading the chunks.

    Raises:
        BagDamage: the bag is not indexed (``index_pos`` 0: its recorder was stopped before it
            wrote the index), or the index is cut off or unreadable.
    """
    view = memoryview(data)
    if bytes(view[: len(MAGIC)]) != MAGIC:
        raise BagDamage(0, "the file does not start with '#ROSBAG V2.0'")
    records = _records(view[len(MAGIC):], len(MAGIC), partial=True)
    offset, header, _, _ = next(records)
    if header.get("op", b"")[:1] != bytes([OP_BAG_HEADER]):
        raise BagDamage(offset, "the bag does not start with its bag header record")
    try:
        (index_pos,) = struct.unpack("<Q", header["index_pos"])
        (conn_count,) = _U32.unpack(header["conn_count"])
    except (KeyError, struct.error):
        raise BagDamage(offset, "the bag header lacks index_pos or conn_count") from None
    if index_pos == 0:
        raise BagDamage(offset, "the bag is not indexed (its recorder did not finish it)")
    if index_pos >= len(view):
        raise BagDamage(offset, f"the index should start at byte {index_pos}, past the end of "
                                f"the file ({len(view)} bytes): the file was cut short")
    out: list[Connection] = []
    for at, head, body, cut in _records(view[index_pos:], index_pos, partial=True):
        if cut:
            break
        if head.get("op", b"")[:1] == bytes([OP_CONNECTION]):
            out.append(_connection(head, body, at))
        if len(out) == conn_count:
            break
    if len(out) != conn_count:
        raise BagDamage(index_pos, f"the index lists {len(out)} of its {conn_count} "
                                   "connections: it is cut off or damaged")
    return out


def _connection(header: dict[str, bytes], body: memoryview, offset: int) -> Connection:
    try:
        (cid,) = _U32.unpack(header["conn"])
        fields = parse_header(body)
        topic = header.get("topic", fields.get("topic", b"")).decode()
    except (KeyError, ValueError, struct.error, UnicodeDecodeError) as exc:
        raise BagDamage(offset, f"unreadable connection record near byte {offset} "
                                f"({type(exc).__name__})") from None
    return Connection(cid, topic, fields)
