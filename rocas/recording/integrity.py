"""A checksum for MCAP metadata records, which the format leaves without one.

Chunks and attachments carry a CRC; a metadata record does not, so a flipped bit in rocas's
``rocas.ego`` record (the ego's route, start and parameters) or ``rocas.run`` record (the
recorded outcome) would change the replayed scenario without a word. rocas's writer adds one
more key to every metadata record it writes, ``rocas.crc32``: the CRC-32 of the record's name
and its other key/value pairs; the reader verifies it and drops a record that fails it as
damage. A record without the key (other writers, older rocas) is read as it is, with nothing
claimed about it.
"""

from __future__ import annotations

import json
import zlib
from collections.abc import Mapping

#: the metadata key holding the checksum (8 lowercase hex digits)
CHECKSUM_KEY = "rocas.crc32"


def metadata_checksum(name: str, data: Mapping[str, str]) -> str:
    """CRC-32 of ``name`` and the pairs of ``data`` other than :data:`CHECKSUM_KEY` (sorted)."""
    pairs = sorted((k, v) for k, v in data.items() if k != CHECKSUM_KEY)
    text = json.dumps([name, pairs], ensure_ascii=False, separators=(",", ":"))
    return f"{zlib.crc32(text.encode('utf-8', 'surrogatepass')):08x}"


def with_checksum(name: str, data: Mapping[str, str]) -> dict[str, str]:
    """``data`` with its :data:`CHECKSUM_KEY` set (any old one replaced)."""
    out = {k: v for k, v in data.items() if k != CHECKSUM_KEY}
    out[CHECKSUM_KEY] = metadata_checksum(name, out)
    return out


def checksum_problem(name: str, data: Mapping[str, str]) -> str | None:
    """Why a metadata record read back cannot be trusted (its checksum fails), or None.

    None too for a record written without a checksum.
    """
    stored = data.get(CHECKSUM_KEY)
    if stored is None or stored == metadata_checksum(name, data):
        return None
    return f"metadata record {name!r} fails its checksum (its content was damaged)"
