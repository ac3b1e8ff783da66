"""Whether two recordings' channels carry the same message type, and how to say they do not.

Two loggers may write one schema as different bytes (a protobuf FileDescriptorSet lists its
files in any order; a JSON schema may be formatted differently), so schemas are compared by
what they define rather than byte for byte.
"""

from __future__ import annotations

import json

from google.protobuf import descriptor_pb2
from google.protobuf.message import DecodeError

from rocas.recording.reader import ChannelInfo


def _schema_label(info: ChannelInfo) -> str:
    return f"{info.message_encoding}:{info.schema_name or '<no schema>'}"


def schema_difference(a: ChannelInfo, b: ChannelInfo) -> str:
    """How the schemas of one topic in the two recordings differ, for an error message."""
    la, lb = _schema_label(a), _schema_label(b)
    if la == lb:
        return f"{la} in both, defined differently"
    return f"{la} vs {lb}"


def same_schema(a: ChannelInfo, b: ChannelInfo) -> bool:
    """Whether two channels carry the same message type, as defined by their schemas.

    Equal bytes are the same schema. Otherwise a protobuf schema is compared as the
    definitions of the message's file and the files it imports, whatever their order in the
    FileDescriptorSet (loggers order dependencies differently), and a JSON schema as JSON.
    """
    if (a.message_encoding, a.schema_encoding, a.schema_name) != (
        b.message_encoding, b.schema_encoding, b.schema_name
    ):
        return False
    if a.schema_data == b.schema_data:
        return True
    ca, cb = _canonical_schema(a), _canonical_schema(b)
    return ca is not None and ca == cb


def _canonical_schema(info: ChannelInfo) -> object | None:
    """An order-free form of the schema, or None when it cannot be read."""
    try:
        if info.schema_encoding == "protobuf":
            fds = descriptor_pb2.FileDescriptorSet.FromString(info.schema_data)
            files = {f.name: f for f in fds.file}
            root = next(
                f.name for f in fds.file for m in f.message_type
                if info.schema_name == ".".join(filter(None, (f.package, m.name)))
                or info.schema_name.startswith(".".join(filter(None, (f.package, m.name))) + ".")
            )
            needed, todo = set(), [root]
            while todo:
                name = todo.pop()
                if name not in needed:
                    needed.add(name)
                    todo.extend(files[name].dependency)
            return tuple(
                (name, files[name].SerializeToString(deterministic=True)) for name in sorted(needed)
            )
        if info.schema_encoding == "jsonschema":
            return json.dumps(json.loads(info.schema_data), sort_keys=True)
    except (StopIteration, KeyError, ValueError, DecodeError):
        return None
    return None
