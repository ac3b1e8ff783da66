"""Writing protobuf recordings that follow the rocas recording contract."""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from types import TracebackType
from typing import Any, BinaryIO

from mcap.well_known import MessageEncoding
from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter
from mcap_protobuf.schema import register_schema

from rocas._fs import atomic_path
from rocas.errors import UsageError
from rocas.recording.integrity import with_checksum
from rocas.recording.topology import merge_topology_metadata

#: MCAP profile string rocas writes into headers of its own recordings.
ROCAS_PROFILE = ""
LIBRARY = "rocas"


def register_protobuf_channel(
    writer: McapWriter,
    topic: str,
    message_type: type[Any],
    *,
    writers: Iterable[str] = (),
    readers: Iterable[str] = (),
    role: str | None = None,
    metadata: Mapping[str, str] | None = None,
    schema_ids: dict[str, int] | None = None,
) -> int:
    """Register a protobuf channel on an existing ``mcap.writer.Writer`` with topology metadata.

    This is the hook for pipelines that write MCAP themselves: call it instead of
    ``register_schema`` + ``register_channel`` and keep writing messages as before.

    Args:
        writer: a started ``mcap.writer.Writer``.
        topic: channel topic, e.g. ``"/planning"``.
        message_type: the generated protobuf class carried on the channel.
        writers: modules that publish on the channel.
        readers: modules that subscribe to it.
        role: ``"control"`` for the channel Algorithm 1 starts from.
        metadata: further channel metadata to keep.
        schema_ids: optional cache ``{full_name: schema_id}`` so a type shared by
            several channels is registered once.

    Returns:
        The channel id, for ``writer.add_message(channel_id=...)``.
    """
    full_name = message_type.DESCRIPTOR.full_name
    if schema_ids is not None and full_name in schema_ids:
        schema_id = schema_ids[full_name]
    else:
        schema_id = register_schema(writer, message_type)
        if schema_ids is not None:
            schema_ids[full_name] = schema_id
    return writer.register_channel(
        topic=topic,
        message_encoding=MessageEncoding.Protobuf,
        schema_id=schema_id,
        metadata=merge_topology_metadata(metadata or {}, writers, readers, role),
    )


class RecordingWriter:
    """Write a protobuf MCAP recording atomically, with the topology contract.

    The file appears under its final name only when the writer is closed without error.

    Example::

        with RecordingWriter("run.mcap") as rec:
            rec.add_channel("/planning", ADCTrajectory, writers=["planning"],
                            readers=["control"])
            rec.write("/planning", msg, log_time_ns=t)
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        compression: str = "zstd",
        chunk_size: int = 1 << 20,
    ) -> None:
        try:
            comp = CompressionType[compression.upper()]
        except KeyError:
            raise UsageError(
                f"unknown MCAP compression {compression!r}", "use zstd, lz4 or none"
            ) from None
        self.path = Path(path)
        self._atomic = atomic_path(self.path)
        self._tmp = self._atomic.__enter__()
        self._file: BinaryIO = open(self._tmp, "wb")  # noqa: SIM115
        self._writer = McapWriter(self._file, chunk_size=chunk_size, compression=comp)
        self._writer.start(profile=ROCAS_PROFILE, library=LIBRARY)
        self._channels: dict[str, tuple[int, str]] = {}
        self._sequences: dict[str, int] = {}
        self._schema_ids: dict[str, int] = {}
        self._closed = False

    def add_channel(
        self,
        topic: str,
        message_type: type[Any],
        *,
        writers: Iterable[str] = (),
        readers: Iterable[str] = (),
        role: str | None = None,
        metadata: Mapping[str, str] | None = None,
    ) -> int:
        """Declare a channel before writing to it; returns its channel id."""
        if topic in self._channels:
            raise UsageError(f"channel {topic!r} is already registered")
        channel_id = register_protobuf_channel(
            self._writer,
            topic,
            message_type,
            writers=writers,
            readers=readers,
            role=role,
            metadata=metadata,
            schema_ids=self._schema_ids,
        )
        self._channels[topic] = (channel_id, message_type.DESCRIPTOR.full_name)
        self._sequences[topic] = 0
        return channel_id

    def write(
        self,
        topic: str,
        message: Any,
        *,
        log_time_ns: int,
        publish_time_ns: int | None = None,
        sequence: int | None = None,
    ) -> None:
        """Append one message; ``sequence`` defaults to a per-channel counter."""
        try:
            channel_id, type_name = self._channels[topic]
        except KeyError:
            raise UsageError(f"channel {topic!r} was not registered with add_channel") from None
        if message.DESCRIPTOR.full_name != type_name:
            raise UsageError(
                f"channel {topic!r} carries {type_name}, not {message.DESCRIPTOR.full_name}"
            )
        seq = self._sequences[topic] if sequence is None else sequence
        self._sequences[topic] = seq + 1
        self._writer.add_message(
            channel_id=channel_id,
            log_time=int(log_time_ns),
            publish_time=int(log_time_ns if publish_time_ns is None else publish_time_ns),
            data=message.SerializeToString(),
            sequence=seq,
        )

    def add_attachment(
        self, name: str, data: bytes, *, media_type: str = "application/octet-stream",
        log_time_ns: int = 0,
    ) -> None:
        """Attach a file (e.g. the static world) to the recording."""
        self._writer.add_attachment(
            create_time=0, log_time=log_time_ns, name=name, media_type=media_type, data=data
        )

    def add_metadata(self, name: str, data: Mapping[str, str]) -> None:
        """Add a metadata record (string key/value pairs) with its checksum
        (:mod:`rocas.recording.integrity`), which the reader verifies."""
        self._writer.add_metadata(name, with_checksum(name, data))

    def close(self) -> None:
        """Finish the file and move it to its final name."""
        if self._closed:
            return
        self._closed = True
        self._writer.finish()
        self._file.close()
        self._atomic.__exit__(None, None, None)

    def abort(self, exc: BaseException | None = None) -> None:
        """Drop the partial file; the final path is left untouched."""
        if self._closed:
            return
        self._closed = True
        self._file.close()
        err = exc or RuntimeError("aborted")
        try:
            self._atomic.__exit__(type(err), err, err.__traceback__)
        except BaseException:  # the context manager re-raises; we only want the cleanup
            pass

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc is None:
            self.close()
        else:
            self.abort(exc)
