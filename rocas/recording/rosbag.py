"""ROS 1 ``.bag`` files and rosbag2 recordings (``.db3`` files, or directories holding a
``metadata.yaml`` with sqlite3 or mcap storage), read with ``rosbags``.

Each connection becomes a channel as the MCAP profiles declare it, so that a bag and its MCAP
copy (``rocas annotate``) carry the same schemas and compare as equal:

- ROS 1 (profile ``ros1``): message encoding ``ros1``, schema ``pkg/Name`` in encoding
  ``ros1msg`` holding the connection's full message definition; the connection header's
  ``callerid`` (the publishing node: the channel's writer under the topology contract) and
  ``latching`` become channel metadata.
- rosbag2 (profile ``ros2``): message encoding ``cdr``, schema ``pkg/msg/Name`` in encoding
  ``ros2msg`` or ``ros2idl`` as the bag stores it. A bag written before rosbag2 stored
  definitions (or a service-event topic, whose definition sqlite3 bags leave out) gets the
  definition of rosbags' type store for the newest ROS 2 release when that store knows the
  type; otherwise its messages are counted as undecodable, with the reason.

Log times are the bag's receive times [ns]; ROS 1 and rosbag2 keep no publish time or
sequence number, so those are the log time and 0. Messages come in log-time order.
"""

from __future__ import annotations

import mmap
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path
from typing import Any

from rocas.errors import RecordingError
from rocas.recording.decoding import DecoderCache
from rocas.recording.foreign import ForeignRecording, Walked
from rocas.recording.model import ChannelInfo, describe_error
from rocas.recording.topology import ROS1_CALLERID_KEY


def ros1_name(msgtype: str) -> str:
    """``pkg/msg/Name`` -> ``pkg/Name`` (the ROS 1 spelling the ``ros1`` profile uses)."""
    parts = msgtype.split("/")
    return f"{parts[0]}/{parts[-1]}" if len(parts) == 3 and parts[1] == "msg" else msgtype


class Ros1Recording(ForeignRecording):
    """A ROS 1 bag (format 2.0).

    Its connections are read from the bag's index; its messages chunk by chunk in file order
    (:mod:`rocas.recording.ros1_chunks`, over a memory map: one chunk at a time), which is
    what the MCAP reader does too and twice as fast as ``rosbags.rosbag1``'s reader, which
    merges the index entries of every connection in time order. Messages decode with
    ``rosbags``' ROS 1 deserializer (:mod:`rocas.recording.decoding`).

    A bag whose index is missing (its recorder was stopped before writing it) or unreadable
    (the file was cut short or damaged) is read all the same, up to the first damage, with
    warnings that say so; one with nothing readable is refused in one line.
    """

    format = "ros1"
    profile = "ros1"

    def __init__(self, path: str | os.PathLike[str], size: int,
                 decoders: DecoderCache | None = None) -> None:
        super().__init__(path, size, decoders)
        from rocas.recording.ros1_chunks import BagDamage, index_connections

        #: why the index could not be used (channels are then learnt from the chunks), or None
        self.index_problem: str | None = None
        try:
            with _mapped(self.path) as mm:
                for conn in index_connections(mm):
                    self._declare(_chunk_channel(conn))
        except BagDamage as exc:
            self.index_problem = exc.reason
            self.scan()  # fail now, with one line, if the chunks hold nothing either
            if not self.channels:
                raise RecordingError(
                    f"{self.path} is a ROS 1 bag that cannot be read ({self.index_problem}, and "
                    f"no complete chunk: {self.report.stop_reason or 'no chunk at all'})",
                    "if its recorder was stopped before it finished, index it with "
                    "'rosbag reindex' (ROS 1) and try again",
                ) from None

    def _walk(self) -> Iterator[Walked]:
        from rocas.recording.ros1_chunks import BagDamage, Connection, walk_chunks

        report = self.report
        if self.index_problem is not None:
            report.summary_problem = (
                f"the bag's index cannot be used ({self.index_problem}); its chunks were read "
                "in file order up to the damage")
        infos = {ch.id: ch for ch in self.channels.values()}

        def progress(offset: int) -> None:
            report.bytes_read = offset

        with _mapped(self.path) as mm:
            walk = walk_chunks(mm, progress)
            try:
                for item in walk:
                    if type(item) is tuple:
                        cid, t, data = item
                        ch = infos.get(cid)
                        if ch is None:
                            report.unknown_channel_messages += 1
                            continue
                        yield ch, t, t, 0, bytes(data)
                    elif isinstance(item, Connection):
                        infos[item.id] = self._declare(_chunk_channel(item))
            except BagDamage as exc:
                self._stop(exc.offset, exc.reason)
                return
            finally:
                walk.close()
                del walk
        report.bytes_read = self.size
        report.complete = True


def _chunk_channel(conn: Any) -> ChannelInfo:
    """The channel of a connection record read by :mod:`rocas.recording.ros1_chunks`."""
    fields = conn.fields
    meta: dict[str, str] = {}
    if fields.get("callerid"):
        meta[ROS1_CALLERID_KEY] = fields["callerid"].decode()
    if "latching" in fields:
        meta["latching"] = str(int(fields["latching"].decode() or "0"))
    return ChannelInfo(
        id=conn.id, topic=conn.topic, message_encoding="ros1",
        schema_name=ros1_name(fields.get("type", b"").decode()), schema_encoding="ros1msg",
        schema_data=fields.get("message_definition", b""), metadata=meta, schema_id=0,
    )


@contextmanager
def _mapped(path: Path) -> Iterator[mmap.mmap]:
    """The file as a read-only memory map (closed when no view of it is left)."""
    with open(path, "rb") as f:
        mm = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
    try:
        yield mm
    finally:
        try:
            mm.close()
        except BufferError:  # a view still held: the map closes when it is collected
            pass


class Rosbag2Recording(ForeignRecording):
    """A rosbag2 recording: a ``.db3`` file, or a directory with ``metadata.yaml``."""

    format = "rosbag2"
    profile = "ros2"

    def __init__(self, path: str | os.PathLike[str], size: int,
                 decoders: DecoderCache | None = None) -> None:
        super().__init__(path, size, decoders)
        self._ids: dict[tuple[str, str], int] = {}
        for reader in self._open():
            reader.close()

    def _open(self) -> list[Any]:
        """Open readers for the recording's storage files, in order.

        A directory with sqlite3 storage is read file by file (its ``.db3`` files as
        ``metadata.yaml`` lists them): rosbags' directory reader keys topics by the ids in
        ``metadata.yaml``, which need not be those of the files, and then yields nothing.
        Channels are declared by (topic, type) across the files.
        """
        from rosbags.rosbag2 import Reader

        what = "rosbag2 directory" if self.path.is_dir() else "rosbag2 .db3 file"
        readers: list[Any] = []
        try:
            for part in _storage_files(self.path):
                # a sqlite3 file whatever its name ends with (rosbags goes by the suffix)
                reader = Reader(part) if part.is_dir() else _Db3(part)
                readers.append(reader)
                reader.open()
        except Exception as exc:
            for reader in readers:
                if reader.is_open:
                    reader.close()
            raise RecordingError(
                f"{self.path} is a {what} that cannot be read ({describe_error(exc)})",
                "if its recorder was stopped before it finished, repair it with "
                "'ros2 bag reindex' (ROS 2) and try again",
            ) from None
        for reader in readers:
            for conn in reader.connections:
                self._declare(self._channel(conn))
        return readers

    def _channel(self, conn: Any) -> ChannelInfo:
        fmt = getattr(conn.msgdef.format, "name", "NONE")
        text = conn.msgdef.data
        encoding = {"MSG": "ros2msg", "IDL": "ros2idl"}.get(fmt, "")
        if not encoding or not text:  # no definition stored: rosbags' own, if it has one
            text, encoding = stock_definition(conn.msgtype), "ros2msg"
        key = (conn.topic, conn.msgtype)
        cid = self._ids.setdefault(key, len(self._ids) + 1)
        return ChannelInfo(
            id=cid, topic=conn.topic,
            message_encoding=getattr(conn.ext, "serialization_format", "") or "cdr",
            schema_name=conn.msgtype, schema_encoding=encoding,
            schema_data=text.encode() if text else b"", metadata={}, schema_id=0,
        )

    def _walk(self) -> Iterator[Walked]:
        readers = self._open()
        if len(readers) == 1:  # one generator less per message
            reader = readers[0]
            infos = {conn.id: self.channels[self._ids[(conn.topic, conn.msgtype)]]
                     for conn in reader.connections}
            return _timed(self, reader.messages(), infos, max(1, int(reader.message_count)),
                          close=reader.close)
        return self._walk_files(readers)

    def _walk_files(self, readers: list[Any]) -> Iterator[Walked]:
        try:
            total = max(1, sum(int(r.message_count) for r in readers))
            done = 0
            for i, reader in enumerate(readers):
                infos = {conn.id: self.channels[self._ids[(conn.topic, conn.msgtype)]]
                         for conn in reader.connections}
                last = i == len(readers) - 1
                n = yield from _timed(self, reader.messages(), infos, total, done, last)
                done += n
                if self.report.truncated:
                    return
        finally:
            for reader in readers:
                if reader.is_open:
                    reader.close()


class _Db3:
    """rosbags' sqlite3 storage reader with the interface of its ``Reader``, for a ``.db3``
    file whatever its name."""

    def __init__(self, path: Path) -> None:
        from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

        self.storage = Sqlite3Reader(path)
        self.is_open = False

    def open(self) -> None:
        self.storage.open()
        self.is_open = True

    def close(self) -> None:
        self.is_open = False
        self.storage.close()

    @property
    def connections(self) -> list[Any]:
        return list(self.storage.connections)

    @property
    def message_count(self) -> int:
        return int(self.storage.metadata.message_count)

    def messages(self) -> Iterator[tuple[Any, int, bytes]]:
        return self.storage.messages(self.storage.connections)


def _storage_files(path: Path) -> list[Path]:
    """The files to read: a ``.db3`` itself; a directory's storage files in recording order
    (sqlite3 storage), or the directory itself (other storage: rosbags reads it whole)."""
    if not path.is_dir():
        return [path]
    from ruamel.yaml import YAML

    try:
        info = YAML(typ="safe").load((path / "metadata.yaml").read_text())
        info = info["rosbag2_bagfile_information"]
    except Exception:  # let rosbags' directory reader say what is wrong
        return [path]
    if info.get("storage_identifier") != "sqlite3":
        return [path]
    names = info.get("relative_file_paths") or [f["path"] for f in info.get("files", [])]
    return [path / Path(name).name for name in names]


def _timed(rec: ForeignRecording, messages: Iterator[tuple[Any, int, bytes]],
           infos: dict[int, ChannelInfo], total: int, done: int = 0,
           last: bool = True, close: Callable[[], None] | None = None) -> Iterator[Walked]:
    """The walk over rosbags' ``(connection, log time [ns], payload)``, with progress and a
    stop (and warning) where the storage turns out damaged.

    Args:
        total: messages expected in the whole recording; done: read before this file.
        last: whether this is the recording's last file (the pass is then complete).
        close: called when the walk ends (closes the reader).

    Returns (as the generator's value): the messages this file yielded.
    """
    report = rec.report
    n = done
    try:
        for conn, t, data in messages:
            yield infos[conn.id], t, t, 0, data
            n += 1
            if not n & 0xFF:  # now and then: progress for the caller
                report.bytes_read = rec.size * min(n, total) // total
    except Exception as exc:  # damage past the index: keep what was read, say so
        rec._stop(rec.size * min(n, total) // total,
                  f"{describe_error(exc)} after {n} of {total} messages")
        return n - done
    finally:
        if close is not None:
            close()
    if last:
        report.bytes_read = rec.size
        report.complete = True
    return n - done


@lru_cache(maxsize=256)
def stock_definition(msgtype: str) -> str:
    """The ``ros2msg`` definition (with dependencies) of a standard ROS 2 type from rosbags'
    type store for the newest release, or "" if it does not know the type."""
    store = _latest_store()
    if msgtype not in store.fielddefs:
        return ""
    try:
        return str(store.generate_msgdef(msgtype, ros_version=2)[0])
    except Exception:  # a type the store cannot write out: left undecodable
        return ""


@lru_cache(maxsize=1)
def _latest_store() -> Any:
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.LATEST)


def rosbag2_size(path: Path) -> int:
    """The size of a rosbag2 recording [bytes]: the file, or a directory's storage files."""
    if not path.is_dir():
        return path.stat().st_size
    return sum(p.stat().st_size for p in path.iterdir() if p.is_file())
