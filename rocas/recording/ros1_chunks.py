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


def walk_chunks(data: bytes | memoryview) -> Iterator[Connection | tuple[int, int, memoryview]]:
    """Connections and messages ``(connection id, log time [ns], payload)`` in file order.

    Args:
        data: the whole bag file (a memory map keeps memory flat: one chunk at a time).

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
        elif op == bytes([OP_CONNECTION]) and not cut:
            yield _connection(header, body, offset)


def _chunk(inner: bytes | memoryview, offset: int, cut: bool,
           ) -> Iterator[Connection | tuple[int, int, memoryview]]:
    try:
        for _, header, body, _ in _records(inner, 0, partial=cut):
            op = header.get("op", b"\xff")[:1]
            if op == bytes([OP_MSG_DATA]):
                (conn,) = _U32.unpack(header["conn"])
                sec, nsec = _TIME.unpack(header["time"])
                yield conn, sec * 1_000_000_000 + nsec, body
            elif op == bytes([OP_CONNECTION]):
                yield _connection(header, body, offset)
    except BagDamage as exc:
        if cut:  # the chunk ends where the file does: the outer walk says so
            return
        raise BagDamage(offset, f"chunk at byte {offset} is damaged inside ({exc.reason})"
                        ) from None
    except (KeyError, struct.error) as exc:
        raise BagDamage(offset, f"chunk at byte {offset} is damaged inside (a message "
                                f"record lacks {exc})") from None


def _connection(header: dict[str, bytes], body: memoryview, offset: int) -> Connection:
    try:
        (cid,) = _U32.unpack(header["conn"])
        fields = parse_header(body)
        topic = header.get("topic", fields.get("topic", b"")).decode()
    except (KeyError, ValueError, struct.error, UnicodeDecodeError) as exc:
        raise BagDamage(offset, f"unreadable connection record near byte {offset} "
                                f"({type(exc).__name__})") from None
    return Connection(cid, topic, fields)
