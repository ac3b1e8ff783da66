"""What every recording reader yields and reports, whatever the file's format.

The MCAP reader (:mod:`rocas.recording.reader`) and the readers of other formats
(:mod:`rocas.recording.foreign` and the format modules under it) all declare channels as
:class:`ChannelInfo`, yield :class:`RawMessage` / :class:`DecodedMessage`, and count what they
could not read in a :class:`ReadReport` (one :class:`ChannelStats` per topic). This module is
the bottom of the reading layers: it imports no other module of :mod:`rocas.recording`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

#: Encodings rocas decodes; any other channel is skipped with a warning.
DECODABLE_ENCODINGS = ("protobuf", "json", "cdr", "ros1")


@dataclass(frozen=True)
class ChannelInfo:
    """A channel as declared in the recording.

    Attributes:
        id: channel id in this file.
        topic: channel topic.
        message_encoding: e.g. ``"protobuf"``, ``"json"``, ``"ros1"``.
        schema_name: the schema's name (protobuf: the message's full name); "" if none.
        schema_encoding: e.g. ``"protobuf"``, ``"jsonschema"``; "" if none.
        schema_data: the raw schema bytes (protobuf: a serialized FileDescriptorSet).
        metadata: channel metadata (string key/value pairs).
        schema_id: the schema record's id in this file (0 when none).
    """

    id: int
    topic: str
    message_encoding: str
    schema_name: str
    schema_encoding: str
    schema_data: bytes
    metadata: dict[str, str]
    schema_id: int = 0


@dataclass
class ChannelStats:
    """What happened to one channel's messages while reading."""

    messages: int = 0
    decoded: int = 0
    undecodable: int = 0
    skipped_encoding: int = 0
    first_error: str | None = None


@dataclass(frozen=True)
class RawMessage:
    """One message record with its channel; ``data`` is the encoded payload."""

    channel: ChannelInfo
    log_time_ns: int
    publish_time_ns: int
    sequence: int
    data: bytes


@dataclass(frozen=True)
class DecodedMessage:
    """A message decoded to a protobuf object (or JSON value, or ROS 2 message).

    ``payload`` is the encoded bytes it was decoded from: two messages of one schema with
    equal payloads are equal, which is cheaper to check on the bytes than on the objects.
    """

    channel: ChannelInfo
    log_time_ns: int
    publish_time_ns: int
    sequence: int
    message: Any
    payload: bytes = b""


@dataclass
class ReadReport:
    """Damage and skips found while reading one file (filled in as the file is read)."""

    bytes_total: int = 0
    bytes_read: int = 0
    complete: bool = False
    truncated: bool = False
    stop_reason: str | None = None
    skipped_chunks: list[tuple[int, str]] = field(default_factory=list)
    skipped_ranges: list[tuple[int, int, str]] = field(default_factory=list)
    unknown_channel_messages: int = 0
    channels_from_summary: bool = False
    channel_stats: dict[str, ChannelStats] = field(default_factory=dict)
    summary_problem: str | None = None
    summary_mismatches: list[str] = field(default_factory=list)

    @property
    def intact(self) -> bool:
        """Whether the pass read every record to the end, skipped nothing, decoded every message
        and agreed with the summary section (when the file has one)."""
        return not (
            self.truncated or not self.complete or self.skipped_chunks or self.skipped_ranges
            or self.unknown_channel_messages or self.channels_from_summary
            or self.summary_problem or self.summary_mismatches
            or any(st.undecodable for st in self.channel_stats.values())
        )

    def warnings(self, name: str, skipped_encodings: bool = True) -> list[str]:
        """Human-readable warning lines (without the ``rocas: warning:`` prefix).

        ``skipped_encodings=False`` leaves out channels skipped for their encoding (for a
        caller that explains encodings itself).
        """
        out: list[str] = []
        if self.truncated:
            pct = 100.0 * self.bytes_read / max(self.bytes_total, 1)
            out.append(
                f"{name}: recording is truncated ({self.stop_reason}); read "
                f"{self.bytes_read} of {self.bytes_total} bytes ({pct:.1f}%), "
                f"stopped at offset {self.bytes_read}"
            )
        for offset, reason in self.skipped_chunks:
            out.append(f"{name}: skipped a corrupted chunk at offset {offset} ({reason})")
        for offset, size, reason in self.skipped_ranges:
            out.append(
                f"{name}: skipped {size} bytes of damaged data at offset {offset} ({reason}); "
                f"reading resumed at offset {offset + size}"
            )
        if self.channels_from_summary:
            out.append(
                f"{name}: channel declarations were lost with damaged data; "
                "recovered them from the file's summary section"
            )
        if self.summary_problem:
            out.append(f"{name}: {self.summary_problem}")
        out.extend(f"{name}: {line}" for line in self.summary_mismatches)
        if self.unknown_channel_messages:
            out.append(
                f"{name}: {self.unknown_channel_messages} messages reference channels "
                "that were never declared (lost with a damaged chunk?)"
            )
        for topic, st in sorted(self.channel_stats.items()):
            if st.skipped_encoding and skipped_encodings:
                out.append(
                    f"{name}: skipped channel {topic}: {st.skipped_encoding} messages in an "
                    "encoding rocas cannot decode (only protobuf, json, ROS 2 cdr and ROS 1 are "
                    "compared)"
                )
            if st.undecodable:
                out.append(
                    f"{name}: {st.undecodable} of {st.messages} messages on {topic} could "
                    f"not be decoded ({st.first_error})"
                )
        return out


def describe_error(exc: BaseException) -> str:
    """An exception in one line: its type, and the first line of its text if it has one."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__
