"""Message decoders built from the schemas stored in recordings.

:class:`DecoderCache` keys decoders by the schema's *content* (encoding, name and bytes), not
by its id. Two files that carry the same schema therefore decode into the same protobuf
class (which lets comparisons run in C), while a schema id reused by two files for two
different schemas can never be confused (the pitfall of sharing one ``mcap_protobuf``
``DecoderFactory``, whose cache is keyed by schema id).

ROS 2 channels (``message_encoding = "cdr"``, schema encoding ``ros2msg`` or ``ros2idl``, the
MCAP ``ros2`` profile) are decoded with ``rosbags`` into its message dataclasses (primitive
arrays as numpy arrays). Each schema content gets a type store of its own, so two files that
define one type name differently never share a class. ``rosbags`` was chosen over
mcap-ros2-support (2.7x slower on the same payloads, no ``ros2idl``) and its faster fork
(GPL-3.0): tests/benchmarks/bench_ros2_decode.py measures all three.

ROS 1 channels (``message_encoding = "ros1"``, schema encoding ``ros1msg``: the connection's
full message definition, the MCAP ``ros1`` profile, and what :mod:`rocas.recording.rosbag`
reads from ``.bag`` files) decode the same way into the same kind of dataclasses, with
rosbags' ROS 1 deserializer.

ROS 2 service-event channels (type ``pkg/srv/Name_Event``) are stored by rosbag2 with the
``.srv`` text (request, ``---``, response) as their schema, which is not a message
definition; :func:`service_event_types` builds the Event type from it (an
``service_msgs/msg/ServiceEventInfo info``, at most one request and at most one response) so
that those channels decode too.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from typing import Any

from mcap.records import Schema
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory

from rocas.errors import RecordingError

Decoder = Callable[[bytes], Any]


class DecoderCache:
    """Decoders keyed by schema content; safe to share between recordings."""

    def __init__(self) -> None:
        self._decoders: dict[tuple[str, str, str, bytes], Decoder | None] = {}

    def decoder(
        self, message_encoding: str, schema_name: str, schema_encoding: str, schema_data: bytes
    ) -> Decoder | None:
        """A decoder for messages of this encoding and schema, or None if rocas has none.

        A protobuf or CDR channel whose schema is missing or broken gets a decoder that raises
        :class:`RecordingError`, so its messages are counted as undecodable.
        """
        key = (message_encoding, schema_name, schema_encoding, schema_data)
        if key in self._decoders:
            return self._decoders[key]
        decoder: Decoder | None
        if message_encoding == "protobuf":
            decoder = _protobuf_decoder(schema_name, schema_encoding, schema_data)
        elif message_encoding == "json":
            decoder = json.loads
        elif message_encoding == "cdr":
            decoder = _cdr_decoder(schema_name, schema_encoding, schema_data)
        elif message_encoding == "ros1":
            decoder = _ros1_decoder(schema_name, schema_encoding, schema_data)
        else:
            decoder = None
        self._decoders[key] = decoder
        return decoder


def _protobuf_decoder(name: str, encoding: str, data: bytes) -> Decoder:
    if not name:
        return _failing("the channel has no protobuf schema")
    if encoding != "protobuf":
        return _failing(f"schema {name} has encoding {encoding!r}, not protobuf")
    schema = Schema(id=1, name=name, encoding=encoding, data=data)
    try:
        # a fresh factory per schema content: its id-keyed cache then holds exactly one type
        decoder = ProtobufDecoderFactory().decoder_for("protobuf", schema)
    except Exception as exc:  # a malformed FileDescriptorSet can raise nearly anything
        return _failing(f"schema {name} cannot be loaded: {type(exc).__name__}: {exc}")
    if decoder is None:
        return _failing(f"schema {name} cannot be loaded")
    return decoder


#: Schema encodings of the ``ros2`` profile that rocas decodes CDR messages with.
ROS2_SCHEMA_ENCODINGS = ("ros2msg", "ros2idl")


def _cdr_decoder(name: str, encoding: str, data: bytes) -> Decoder:
    if not name:
        return _failing("the channel has no ROS 2 schema")
    if encoding not in ROS2_SCHEMA_ENCODINGS:
        return _failing(f"schema {name} has encoding {encoding!r}, not ros2msg or ros2idl")
    if not data.strip():
        return _failing(f"the recording stores no definition of {name} (nor does rosbags' type "
                        "store have one)")
    loaded = _typestore(name, encoding, data)
    if isinstance(loaded, str):
        return _failing(loaded)
    deserialize, typename = loaded[0].deserialize_cdr, loaded[1]

    def decode(payload: bytes) -> Any:
        return deserialize(payload, typename)

    return decode


def _ros1_decoder(name: str, encoding: str, data: bytes) -> Decoder:
    if not name:
        return _failing("the channel has no ROS 1 message definition")
    if encoding != "ros1msg":
        return _failing(f"schema {name} has encoding {encoding!r}, not ros1msg")
    loaded = _typestore(name, "ros1msg", data)
    if isinstance(loaded, str):
        return _failing(loaded)
    deserialize, typename = loaded[0].deserialize_ros1, loaded[1]

    def decode(payload: bytes) -> Any:
        return deserialize(payload, typename)

    return decode


def _typestore(name: str, encoding: str, data: bytes) -> tuple[Any, str] | str:
    """(a type store holding the schema's types, the channel's type name in it), or why not.

    ``encoding``: ``ros2msg``, ``ros2idl`` or ``ros1msg`` (a ``.msg`` text with its
    dependencies after ``====`` / ``MSG: pkg/Name`` lines, the same syntax in both ROS).
    """
    from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
    from rosbags.typesys.msg import normalize_msgtype

    typename = name if is_service_event(name) else normalize_msgtype(name)
    try:
        text = data.decode()
        if encoding == "ros2idl":
            types = get_types_from_idl(text)
        elif is_service_event(typename) and _has_service_separator(text):
            types = service_event_types(text, typename)
        else:
            types = get_types_from_msg(text, typename)
        store = get_typestore(Stores.EMPTY)
        store.register(types)
    except Exception as exc:  # a malformed definition can raise nearly anything
        return f"schema {name} cannot be loaded: {type(exc).__name__}: {exc}"
    if typename not in store.fielddefs:
        return f"schema {name} does not define {name}"
    missing = _undefined(store, typename)
    if missing:
        return f"schema {name} uses {missing}, which it does not define"
    return store, typename


def _undefined(store: Any, typename: str) -> str | None:
    """The first type ``typename`` uses (directly or through its fields) that ``store`` lacks."""
    seen: set[str] = set()
    todo = [typename]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        if name not in store.fielddefs:
            return name
        todo.extend(_names(store.fielddefs[name][1]))
    return None


def _names(tree: Any) -> list[str]:
    """Type names a rosbags field list refers to (nested message types)."""
    from rosbags.typesys.base import Nodetype

    out: list[str] = []
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, tuple) and len(node) == 2 and node[0] == Nodetype.NAME:
            out.append(node[1])
        elif isinstance(node, (tuple, list)):
            stack.extend(node)
    return out


#: The dependencies' separator in a concatenated message definition (ROS 1 and ROS 2 alike).
_DEPENDENCY_LINE = re.compile(r"^={10,}\s*$", re.MULTILINE)
_SERVICE_SEPARATOR = re.compile(r"^---\s*$", re.MULTILINE)
#: ``service_msgs/msg/ServiceEventInfo`` (ROS 2 Iron and later); ``client_gid`` is 16 bytes
#: (``char[16]`` since Jazzy, ``uint8[16]`` in Iron: one CDR layout).
SERVICE_EVENT_INFO = """uint8 REQUEST_SENT = 0
uint8 REQUEST_RECEIVED = 1
uint8 RESPONSE_SENT = 2
uint8 RESPONSE_RECEIVED = 3
uint8 event_type
builtin_interfaces/Time stamp
char[16] client_gid
int64 sequence_number
"""
_TIME = "int32 sec\nuint32 nanosec\n"


def is_service_event(typename: str) -> bool:
    """Whether a ROS 2 type name is a service's event message (``pkg/srv/Name_Event``)."""
    parts = typename.split("/")
    return len(parts) == 3 and parts[1] == "srv" and parts[2].endswith("_Event")


def _has_service_separator(text: str) -> bool:
    head = _DEPENDENCY_LINE.split(text, maxsplit=1)[0]
    return _SERVICE_SEPARATOR.search(head) is not None


def service_event_types(text: str, typename: str) -> dict[str, Any]:
    """The types of a service-event channel whose schema is the service's ``.srv`` text.

    Args:
        text: the ``.srv`` text (request fields, a ``---`` line, response fields), optionally
            followed by the definitions of the types it uses (``====`` and ``MSG: pkg/Name``
            lines, as in a message schema).
        typename: the channel's type, ``pkg/srv/Name_Event``.

    Returns:
        rosbags type definitions of ``pkg/srv/Name_Event``, ``pkg/srv/Name_Request``,
        ``pkg/srv/Name_Response``, ``service_msgs/msg/ServiceEventInfo`` and
        ``builtin_interfaces/msg/Time`` (the last two unless the text defines them), and of
        every type the text defines.
    """
    from rosbags.typesys import get_types_from_msg

    pkg, _, event = typename.split("/")
    name = event[: -len("_Event")]
    # rosbags' parser files every type under pkg/msg/: the service's three are built there
    # and then moved to pkg/srv/ (their names, and every reference to them)
    moved = {f"{pkg}/msg/{name}{part}": f"{pkg}/srv/{name}{part}"
             for part in ("_Event", "_Request", "_Response")}
    srv, *deps = _DEPENDENCY_LINE.split(text)
    request, response = _SERVICE_SEPARATOR.split(srv, maxsplit=1)
    types: dict[str, Any] = {}
    for dep in deps:
        lines = dep.strip().splitlines()
        if not lines or not lines[0].startswith("MSG:"):
            raise ValueError("a dependency of the service definition has no 'MSG: pkg/Name' line")
        types.update(get_types_from_msg("\n".join(lines[1:]), _msg_name(lines[0][4:].strip())))
    if "builtin_interfaces/msg/Time" not in types:
        types.update(get_types_from_msg(_TIME, "builtin_interfaces/msg/Time"))
    if "service_msgs/msg/ServiceEventInfo" not in types:
        types.update(get_types_from_msg(SERVICE_EVENT_INFO, "service_msgs/msg/ServiceEventInfo"))
    types.update(get_types_from_msg(request, f"{pkg}/msg/{name}_Request"))
    types.update(get_types_from_msg(response, f"{pkg}/msg/{name}_Response"))
    types.update(get_types_from_msg(
        "service_msgs/ServiceEventInfo info\n"
        f"{pkg}/msg/{name}_Request[<=1] request\n{pkg}/msg/{name}_Response[<=1] response\n",
        f"{pkg}/msg/{name}_Event",
    ))
    return {moved.get(k, k): _renamed(v, moved) for k, v in types.items()}


def _renamed(tree: Any, names: dict[str, str]) -> Any:
    """A rosbags parse tree with the type names in ``names`` replaced."""
    if isinstance(tree, str):
        return names.get(tree, tree)
    if isinstance(tree, tuple):
        return tuple(_renamed(x, names) for x in tree)
    if isinstance(tree, list):
        return [_renamed(x, names) for x in tree]
    return tree


def _msg_name(name: str) -> str:
    """``pkg/Name`` or ``pkg/msg/Name`` -> ``pkg/msg/Name``."""
    parts = name.split("/")
    return f"{parts[0]}/msg/{parts[-1]}" if len(parts) == 2 else name


def _failing(reason: str) -> Decoder:
    def decode(_: bytes) -> Any:
        raise RecordingError(reason)

    return decode
