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
"""

from __future__ import annotations

import json
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
    from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
    from rosbags.typesys.msg import normalize_msgtype

    try:
        text = data.decode()
        types = get_types_from_msg(text, name) if encoding == "ros2msg" else get_types_from_idl(text)
        store = get_typestore(Stores.EMPTY)
        store.register(types)
    except Exception as exc:  # a malformed definition can raise nearly anything
        return _failing(f"schema {name} cannot be loaded: {type(exc).__name__}: {exc}")
    typename = name if name in store.fielddefs else normalize_msgtype(name)
    if typename not in store.fielddefs:
        return _failing(f"schema {name} does not define {name}")
    deserialize = store.deserialize_cdr

    def decode(payload: bytes) -> Any:
        return deserialize(payload, typename)

    return decode


def _failing(reason: str) -> Decoder:
    def decode(_: bytes) -> Any:
        raise RecordingError(reason)

    return decode
