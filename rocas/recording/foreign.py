"""What every non-MCAP recording reader shares: the :class:`~rocas.recording.reader.Recording`
interface over a stream of messages a format module provides.

A format module (:mod:`rocas.recording.rosbag`, :mod:`rocas.recording.cyber`) subclasses
:class:`ForeignRecording` and implements :meth:`ForeignRecording._walk`, which yields
``(channel, log time [ns], publish time [ns], sequence, payload)`` for every message in file
order, declares channels as it meets them (:meth:`ForeignRecording._declare`) and reports
damage into :attr:`ForeignRecording.report` (the same :class:`ReadReport` as MCAP's). Payloads
stay encoded until asked for, and are decoded with the same :class:`DecoderCache` as MCAP
channels: ROS messages into rosbags dataclasses, Cyber RT messages into protobuf messages. So
``rocas diff`` pairs and compares them exactly as it does MCAP channels, and a pair may mix
formats.

These formats have no MCAP summary section: :meth:`summary` is ``(None, None)`` and the start
time is the earliest message read.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from rocas.recording.decoding import DecoderCache
from rocas.recording.model import (
    ChannelInfo,
    ChannelStats,
    DecodedMessage,
    RawMessage,
    ReadReport,
    describe_error,
)

#: A message as a format's walk yields it: (channel, log time [ns], publish time [ns],
#: sequence, payload).
Walked = tuple[ChannelInfo, int, int, int, bytes]


class ForeignRecording:
    """A recording in a format other than MCAP, read with the MCAP reader's interface.

    Attributes:
        path: the file (or rosbag2 directory).
        size: its size [bytes] (a directory: the sum of its storage files).
        format: ``"ros1"``, ``"rosbag2"`` or ``"cyber"``.
        profile: the MCAP profile its channels follow (``"ros1"``, ``"ros2"``, ``""``), which
            ``rocas annotate`` writes into the MCAP copy's header.
        channels: channel id -> :class:`ChannelInfo`, complete after a pass.
        report: the last pass's :class:`ReadReport`.
    """

    format = ""
    profile = ""
    #: what a pass that stops early suggests, appended to its stop reason by callers
    repair_hint = ""

    def __init__(self, path: str | os.PathLike[str], size: int,
                 decoders: DecoderCache | None = None) -> None:
        self.path = Path(path)
        self.size = size
        self.channels: dict[int, ChannelInfo] = {}
        self.report = ReadReport(bytes_total=size)
        self.attachment_warnings: list[str] = []
        self._decoder_cache = decoders if decoders is not None else DecoderCache()
        self._decoders: dict[int, Callable[[bytes], Any] | None] = {}
        self._scanned = False

    # -- what a format implements --------------------------------------------------------
    def _walk(self) -> Iterator[Walked]:
        """Every message in file order; sets ``report.complete`` (and ``bytes_read``) when the
        whole file was read, or ``truncated``/``stop_reason`` (and skips) when it was not."""
        raise NotImplementedError

    # -- helpers for formats -------------------------------------------------------------
    def _declare(self, info: ChannelInfo) -> ChannelInfo:
        """Register a channel (by id) and its stats entry; returns the registered info."""
        known = self.channels.get(info.id)
        if known is not None and known == info:
            return known
        self.channels[info.id] = info
        self._decoders.pop(info.id, None)
        self.report.channel_stats.setdefault(info.topic, ChannelStats())
        return info

    def _stop(self, offset: int, reason: str) -> None:
        """End the pass early: the file is cut or damaged at ``offset`` [bytes]."""
        self.report.bytes_read = offset
        self.report.truncated = True
        self.report.stop_reason = reason

    # -- the Recording interface ---------------------------------------------------------
    def _attributed(self) -> Iterator[Walked]:
        self.report = ReadReport(bytes_total=self.size)
        stats = self.report.channel_stats
        for ch in self.channels.values():
            stats.setdefault(ch.topic, ChannelStats())
        for rec in self._walk():
            st = stats.get(rec[0].topic)
            if st is None:
                st = stats[rec[0].topic] = ChannelStats()
            st.messages += 1
            yield rec
        self._scanned = True

    def messages(self) -> Iterator[RawMessage]:
        """Every readable message, in file order (each call is a new pass)."""
        for ch, log_time, publish_time, sequence, data in self._attributed():
            yield RawMessage(ch, log_time, publish_time, sequence, data)

    def decoded(self, topics: set[str] | None = None) -> Iterator[DecodedMessage]:
        """Every message that decodes, in file order; failures are counted, not raised."""
        for ch, log_time, publish_time, sequence, data in self._attributed():
            if topics is not None and ch.topic not in topics:
                continue
            st = self.report.channel_stats[ch.topic]
            decode = self._decoders[ch.id] if ch.id in self._decoders else self._decoder(ch)
            if decode is None:
                st.skipped_encoding += 1
                continue
            try:
                obj = decode(data)
            except Exception as exc:  # a foreign file can hold anything
                st.undecodable += 1
                if st.first_error is None:
                    st.first_error = describe_error(exc)
                continue
            st.decoded += 1
            yield DecodedMessage(ch, log_time, publish_time, sequence, obj, data)

    def undecoded(self) -> Iterator[tuple[ChannelInfo, int, bytes, Callable[[bytes], Any]]]:
        """As :meth:`rocas.recording.reader.Recording.undecoded`: (channel, log time [ns],
        payload, decoder) of every message rocas has a decoder for, not decoded."""
        self.report = ReadReport(bytes_total=self.size)
        stats = self.report.channel_stats
        for info in self.channels.values():
            stats.setdefault(info.topic, ChannelStats())
        # channel id -> (its ChannelInfo, its stats, its decoder) while the declaration stands
        known: dict[int, tuple[ChannelInfo, ChannelStats, Any]] = {}
        for ch, log_time, _publish, _sequence, data in self._walk():
            entry = known.get(ch.id)
            if entry is None or entry[0] is not ch:
                st = stats.get(ch.topic)
                if st is None:
                    st = stats[ch.topic] = ChannelStats()
                decode = self._decoders[ch.id] if ch.id in self._decoders else self._decoder(ch)
                entry = known[ch.id] = (ch, st, decode)
            st = entry[1]
            st.messages += 1
            if entry[2] is None:
                st.skipped_encoding += 1
                continue
            st.decoded += 1
            yield ch, log_time, data, entry[2]
        self._scanned = True

    def scan(self) -> ForeignRecording:
        """Read the file once to learn its channels and damage; returns self."""
        if not self._scanned:
            for _ in self._attributed():
                pass
        return self

    def summary_start_time_ns(self) -> int | None:
        """None: these formats have no summary rocas checks; the first messages align."""
        return None

    def summary(self) -> tuple[None, None]:
        """``(None, None)``: no MCAP summary section."""
        return None, None

    def warnings(self, name: str) -> list[str]:
        """The last pass's warnings (one line each, no ``rocas: warning:`` prefix)."""
        return self.report.warnings(name)

    def attachments(self) -> Iterator[Any]:
        """None: these formats carry no MCAP attachments."""
        return iter(())

    def attachment(self, name: str) -> bytes | None:
        """None: these formats carry no MCAP attachments."""
        return None

    @property
    def metadata(self) -> list[tuple[str, dict[str, str]]]:
        """Recording-level metadata records (name, key/values) the format carries."""
        return []

    def topics(self) -> dict[str, ChannelInfo]:
        """Channels by topic (after a pass; the last declaration of a topic wins)."""
        return {ch.topic: ch for ch in self.channels.values()}

    def _decoder(self, ch: ChannelInfo) -> Callable[[bytes], Any] | None:
        decoder = self._decoder_cache.decoder(
            ch.message_encoding, ch.schema_name, ch.schema_encoding, ch.schema_data
        )
        self._decoders[ch.id] = decoder
        return decoder
