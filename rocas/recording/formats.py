"""Which recording format a path holds, from its first bytes (not its name), and the reader
that opens it (:func:`open_recording`, the one entry point of every reader).

========================  =======================================  ==============================
format                    recognised by                            read by
========================  =======================================  ==============================
``mcap``                  the MCAP magic ``\\x89MCAP0\\r\\n``         :mod:`rocas.recording.reader`
``ros1``                  ``#ROSBAG V2.0``                         :mod:`rocas.recording.rosbag`
``rosbag2``               ``SQLite format 3\\0`` (a ``.db3``), or a  :mod:`rocas.recording.rosbag`
                          directory holding ``metadata.yaml``
``cyber``                 a Cyber RT header section                :mod:`rocas.recording.cyber`
========================  =======================================  ==============================

Anything else is refused in one line that names what the file looks like and what to do.

This module sits above the readers: it imports them, none of them imports it.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from rocas.errors import InputError, RecordingError
from rocas.recording.reader import Recording

if TYPE_CHECKING:
    from rocas.recording.decoding import DecoderCache

MCAP_MAGIC = b"\x89MCAP0\r\n"
ROS1_MAGIC = b"#ROSBAG V2.0\n"
SQLITE_MAGIC = b"SQLite format 3\x00"
#: The formats :func:`sniff` names, with a description for messages.
FORMATS = {
    "mcap": "MCAP recording",
    "ros1": "ROS 1 bag",
    "rosbag2": "rosbag2 recording",
    "cyber": "Apollo Cyber RT record",
}
READABLE = "MCAP, ROS 1 .bag, rosbag2 (.db3 or a directory with metadata.yaml) and Cyber RT .record"
#: First bytes of files people give by mistake: (magic, what it is, what to do).
_KNOWN = (
    (b"#ROSBAG V", "a ROS 1 bag of an old format version (before 2.0)",
     "migrate it with 'rosbag fix' (ROS 1) first"),
    (b"\x1f\x8b", "a gzip-compressed file", "decompress it first"),
    (b"\x28\xb5\x2f\xfd", "a zstd-compressed file", "decompress it first"),
    (b"BZh", "a bzip2-compressed file", "decompress it first"),
    (b"PK\x03\x04", "a zip archive", "extract the recording from it first"),
    (b"RRF", "a Rerun .rrd file", "open it with 'rerun' directly; rocas reads recordings"),
)


def sniff(path: Path) -> tuple[str, int]:
    """(format, size [bytes]) of the recording at ``path``; raises for anything else.

    Raises:
        InputError: the path does not exist, is a directory that is no rosbag2 recording, or
            cannot be read.
        RecordingError: the file is empty or in no format rocas reads.
    """
    if not path.exists():
        raise InputError(f"no such file: {path}", "check the path")
    if path.is_dir():
        if (path / "metadata.yaml").is_file():
            from rocas.recording.rosbag import rosbag2_size

            return "rosbag2", rosbag2_size(path)
        raise InputError(
            f"{path} is a directory, not an MCAP recording (nor a rosbag2 directory: it holds "
            "no metadata.yaml)",
            "give a recording file, or a rosbag2 directory",
        )
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            head = f.read(64)
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror}") from exc
    if size == 0:
        raise RecordingError(f"{path} is empty (0 bytes)", "give a non-empty MCAP recording")
    if head.startswith(MCAP_MAGIC):
        return "mcap", size
    if head.startswith(ROS1_MAGIC):
        return "ros1", size
    if head.startswith(SQLITE_MAGIC):
        return "rosbag2", size
    from rocas.recording.cyber import looks_like_cyber

    if looks_like_cyber(head):
        return "cyber", size
    for magic, what, todo in _KNOWN:
        if head.startswith(magic):
            raise RecordingError(f"{path} is {what}, not an MCAP file or another recording "
                                 "format rocas reads", f"{todo}; rocas reads {READABLE}")
    raise RecordingError(
        f"{path} is not an MCAP file, nor a ROS 1 bag, rosbag2 .db3 or Cyber RT record (its "
        "first bytes match none of them)",
        f"rocas reads {READABLE}; convert other formats to MCAP (e.g. 'rosbags-convert' for ROS "
        "bags, installed with rocas)",
    )


def open_recording(
    path: str | os.PathLike[str], decoders: DecoderCache | None = None
) -> Recording:
    """Open a recording for streaming, whatever its format; raises :class:`InputError` if it
    is none rocas reads.

    The format is recognised from the file's first bytes (:func:`sniff`): MCAP is read by
    :class:`~rocas.recording.reader.Recording`; ROS 1 bags and rosbag2 recordings by
    :mod:`rocas.recording.rosbag`, Cyber RT records by :mod:`rocas.recording.cyber`, each
    with :class:`~rocas.recording.reader.Recording`'s interface (``format`` tells them apart).
    Pass one :class:`~rocas.recording.decoding.DecoderCache` to several recordings to decode
    identical schemas into identical classes.
    """
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
