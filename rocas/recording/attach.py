"""Attach rocas to a pipeline that already writes MCAP: declare who writes and reads a channel.

rocas needs one thing your recordings may lack: for each channel, the modules that write
and read it (channel metadata ``rocas.writers`` / ``rocas.readers``), and which channel is
the control channel (``rocas.role = control``). :func:`attach_channel` registers a protobuf
channel with that metadata on the writer you already use; you keep writing messages exactly
as before.

- ``mcap.writer.Writer``: ``channel_id = attach_channel(writer, "/planning", Trajectory,
  writers=["planning"], readers=["control"])``, then ``writer.add_message(channel_id, ...)``.
- ``mcap_protobuf.writer.Writer``: call ``attach_channel(writer, "/planning", Trajectory,
  ...)`` once before the first ``writer.write_message("/planning", msg, ...)``; the topic is
  then pre-registered with its metadata and ``write_message`` uses that channel.

Channels that are not protobuf (JSON, or encodings rocas does not decode): pass
``metadata=topology_metadata(writers=[...], readers=[...])`` to ``register_channel``.
"""

from __future__ import annotations

import weakref
from collections.abc import Iterable, Mapping
from typing import Any

from mcap.writer import Writer as McapWriter
from mcap_protobuf.schema import register_schema
from mcap_protobuf.writer import Writer as ProtobufWriter

from rocas.errors import UsageError
from rocas.recording.topology import merge_topology_metadata
from rocas.recording.writer import RecordingWriter, register_protobuf_channel

# one schema cache per mcap writer, so a message type shared by channels is stored once
_SCHEMA_IDS: weakref.WeakKeyDictionary[McapWriter, dict[str, int]] = weakref.WeakKeyDictionary()


def attach_channel(
    writer: McapWriter | ProtobufWriter | RecordingWriter,
    topic: str,
    message_type: type[Any],
    *,
    writers: Iterable[str] = (),
    readers: Iterable[str] = (),
    role: str | None = None,
    metadata: Mapping[str, str] | None = None,
) -> int:
    """Register a protobuf channel with its topology on the MCAP writer you already use.

    Args:
        writer: a started ``mcap.writer.Writer``, an ``mcap_protobuf.writer.Writer`` or a
            :class:`~rocas.recording.RecordingWriter`.
        topic: the channel's topic, e.g. ``"/planning"``.
        message_type: the generated protobuf class carried on the channel (any protobuf
            message class, generated or built at run time).
        writers: modules that publish on the channel.
        readers: modules that subscribe to it.
        role: ``"control"`` on the one channel Algorithm 1 starts from (the stack's output).
        metadata: further channel metadata to store with it.

    Returns:
        The channel id (for ``mcap.writer.Writer.add_message(channel_id=...)``).

    Raises:
        UsageError: the topic is already registered on an ``mcap_protobuf`` writer (call
            this before the first ``write_message`` on it), or ``writer`` is of another kind.
    """
    if isinstance(writer, RecordingWriter):
        return writer.add_channel(
            topic, message_type, writers=writers, readers=readers, role=role,
            metadata=metadata,
        )
    if isinstance(writer, ProtobufWriter):
        return _attach_protobuf_writer(writer, topic, message_type, writers, readers, role,
                                       metadata)
    if isinstance(writer, McapWriter):
        return register_protobuf_channel(
            writer, topic, message_type, writers=writers, readers=readers, role=role,
            metadata=metadata, schema_ids=_SCHEMA_IDS.setdefault(writer, {}),
        )
    raise UsageError(
        f"attach_channel needs an MCAP writer, not {type(writer).__name__}",
        "pass an mcap.writer.Writer, an mcap_protobuf.writer.Writer or a rocas RecordingWriter",
    )


def _attach_protobuf_writer(
    writer: ProtobufWriter,
    topic: str,
    message_type: type[Any],
    writers: Iterable[str],
    readers: Iterable[str],
    role: str | None,
    metadata: Mapping[str, str] | None,
) -> int:
    # mcap_protobuf's Writer registers a channel lazily in write_message, keyed by topic in
    # ``_channels`` (topic -> channel id) and ``_schemas`` (topic -> (schema id, type name)),
    # on the mcap Writer ``_writer``. Filling both first makes write_message use our channel.
    inner = getattr(writer, "_writer", None)
    channels = getattr(writer, "_channels", None)
    schemas = getattr(writer, "_schemas", None)
    if not (isinstance(inner, McapWriter) and isinstance(channels, dict)
            and isinstance(schemas, dict)):
        raise UsageError(
            "this version of mcap-protobuf-support keeps its channels differently; rocas "
            "cannot pre-register a topic on its Writer",
            "write with mcap.writer.Writer and attach_channel, or add the topology afterwards "
            "with 'rocas annotate'",
        )
    if topic in channels:
        raise UsageError(
            f"topic {topic!r} is already registered on this writer",
            "call attach_channel before the first write_message on the topic",
        )
    full_name = message_type.DESCRIPTOR.full_name
    schema_id = next((sid for sid, name in schemas.values() if name == full_name), None)
    if schema_id is None:
        schema_id = register_schema(inner, message_type)
    channel_id = inner.register_channel(
        topic=topic,
        message_encoding="protobuf",
        schema_id=schema_id,
        metadata=merge_topology_metadata(metadata or {}, writers, readers, role),
    )
    schemas[topic] = (schema_id, full_name)
    channels[topic] = channel_id
    return channel_id
