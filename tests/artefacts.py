"""Ordinary logging artefacts, applied to a copy of an MCAP recording (issue 36).

Real loggers do not write two runs of a stack that agree bit for bit until one deviates: one file
ends earlier, the logger started later, a latched message arrives before the rest, a message is
logged twice or lost, a channel is recorded at another rate, on another clock or at flush time,
log times jitter, and every sensor value carries noise. Each function here returns a transform
that does one of these to an in-memory copy of a recording; :func:`rewrite` reads a file, applies
transforms in order and writes the result, keeping the schemas, the channels with their metadata,
the attachments and the metadata records (mcap's own Reader and Writer, nothing of rocas).

Transforms keep the order in which messages are written (a logger writes what it receives, in
the order it receives it) unless the artefact itself is an order (a latched message is written
first); where log times change, file order is therefore no longer log-time order, as in a real
file.

Times given in seconds are relative to the recording's first message (its earliest log time),
except :func:`flush_stamps`, whose boundaries are those of the clock (multiples of the period).

Noise and steps decode each message with its own schema (protobuf: the FileDescriptorSet in the
schema record; ROS 2 CDR: the ``ros2msg``/``ros2idl`` text, with rosbags), change its float
fields and encode it again. Other encodings (json, ros1, ...) are left as they are.

Used by tests/benchmarks/bench_artefacts.py and bench_real.py, and tests/test_artefacts.py.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from mcap.reader import make_reader
from mcap.records import Attachment, Channel, Schema
from mcap.writer import Writer

NS = 1_000_000_000


@dataclass
class Message:
    """One message record: its channel id (in :attr:`McapContent.channels`), times and bytes."""

    channel_id: int
    log_time: int
    publish_time: int
    sequence: int
    data: bytes


@dataclass
class McapContent:
    """Everything in one MCAP file that a rewrite keeps, messages in file order."""

    profile: str
    library: str
    schemas: dict[int, Schema]
    channels: dict[int, Channel]
    messages: list[Message]
    attachments: list[Attachment] = field(default_factory=list)
    metadata: list[tuple[str, dict[str, str]]] = field(default_factory=list)

    def channel_id(self, topic: str) -> int:
        """The id of the channel on ``topic`` (KeyError naming the topics when there is none)."""
        for cid, ch in self.channels.items():
            if ch.topic == topic:
                return cid
        raise KeyError(f"no channel {topic!r}; channels: {sorted(c.topic for c in self.channels.values())}")

    def topic(self, message: Message) -> str:
        return self.channels[message.channel_id].topic

    @property
    def start(self) -> int:
        """Earliest log time [ns]."""
        return min(m.log_time for m in self.messages)

    @property
    def end(self) -> int:
        """Latest log time [ns]."""
        return max(m.log_time for m in self.messages)


Transform = Callable[[McapContent], None]


def read(path: str | os.PathLike[str]) -> McapContent:
    """Read a whole MCAP file (small files: everything is held in memory)."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        messages: list[Message] = []
        for schema, channel, msg in reader.iter_messages(log_time_order=False):
            if schema is not None:
                schemas.setdefault(schema.id, schema)
            channels.setdefault(channel.id, channel)
            messages.append(Message(msg.channel_id, msg.log_time, msg.publish_time, msg.sequence,
                                    bytes(msg.data)))
        summary = reader.get_summary()
        if summary is not None:  # channels without messages are kept too
            for sid, schema in summary.schemas.items():
                schemas.setdefault(sid, schema)
            for cid, channel in summary.channels.items():
                channels.setdefault(cid, channel)
        attachments = list(reader.iter_attachments())
        metadata = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
    return McapContent(header.profile, header.library, schemas, dict(sorted(channels.items())),
                       messages, attachments, metadata)


def write(content: McapContent, path: str | os.PathLike[str]) -> None:
    """Write ``content`` as an MCAP file, messages in list order."""
    with open(path, "wb") as f:
        writer = Writer(f)
        writer.start(profile=content.profile, library=content.library)
        schema_ids = {0: 0}
        for sid, s in sorted(content.schemas.items()):
            schema_ids[sid] = writer.register_schema(s.name, s.encoding, s.data)
        channel_ids = {}
        for cid, ch in content.channels.items():
            channel_ids[cid] = writer.register_channel(ch.topic, ch.message_encoding,
                                                       schema_ids[ch.schema_id], dict(ch.metadata))
        for m in content.messages:
            writer.add_message(channel_ids[m.channel_id], m.log_time, m.data, m.publish_time, m.sequence)
        for a in content.attachments:
            writer.add_attachment(a.create_time, a.log_time, a.name, a.media_type, a.data)
        for name, data in content.metadata:
            writer.add_metadata(name, data)
        writer.finish()


def rewrite(src: str | os.PathLike[str], dst: str | os.PathLike[str], *transforms: Transform) -> McapContent:
    """Copy ``src`` to ``dst`` with ``transforms`` applied in order; returns what was written."""
    content = read(src)
    for t in transforms:
        t(content)
    write(content, dst)
    return content


# ----------------------------------------------------------------------------------- spans


def truncate_end(seconds: float) -> Transform:
    """The file ends ``seconds`` earlier: messages logged after ``end - seconds`` are gone."""
    def apply(c: McapContent) -> None:
        cut = c.end - round(seconds * NS)
        c.messages = [m for m in c.messages if m.log_time <= cut]
    return apply


def late_start(seconds: float) -> Transform:
    """The logger started ``seconds`` later: messages logged before ``start + seconds`` are gone."""
    def apply(c: McapContent) -> None:
        cut = c.start + round(seconds * NS)
        c.messages = [m for m in c.messages if m.log_time >= cut]
    return apply


def latched_early(topic: str | None = None, seconds: float = 1.0) -> Transform:
    """One latched message logged ``seconds`` before the rest: the first message of ``topic``
    (default: the channel with the fewest messages, the likeliest latched one) gets the log time
    ``start - seconds`` and is written first, as a logger writes a latched message on subscribing
    (a file that starts less than ``seconds`` after 0 is first moved later as a whole)."""
    def apply(c: McapContent) -> None:
        if topic is not None:
            cid = c.channel_id(topic)
        else:
            counts: dict[int, int] = {}
            for m in c.messages:
                counts[m.channel_id] = counts.get(m.channel_id, 0) + 1
            cid = min(counts, key=lambda k: (counts[k], k))
        d = round(seconds * NS)
        if c.start < d:  # log times are unsigned: the whole file moves later instead
            shift = d - c.start
            for m in c.messages:
                m.log_time += shift
                m.publish_time += shift
        i = next(i for i, m in enumerate(c.messages) if m.channel_id == cid)
        msg = c.messages.pop(i)
        msg.log_time = c.start - d if c.messages else msg.log_time
        c.messages.insert(0, msg)
    return apply


# ------------------------------------------------------------------------ repeated, lost


def duplicate(seed: int = 0, topic: str | None = None) -> Transform:
    """One message logged twice: a copy written right after it (same times, same bytes). Which
    message: drawn with ``seed`` among those of ``topic`` (default: all)."""
    def apply(c: McapContent) -> None:
        idx = _indices(c, topic)
        i = idx[int(np.random.default_rng(seed).integers(len(idx)))]
        c.messages.insert(i + 1, dataclasses.replace(c.messages[i]))
    return apply


def lose(fraction: float = 0.01, seed: int = 0, topic: str | None = None) -> Transform:
    """``fraction`` of the messages (of ``topic``, default all) lost, drawn with ``seed``
    (exactly round(fraction * n) of them, at least one)."""
    def apply(c: McapContent) -> None:
        idx = _indices(c, topic)
        k = max(1, round(fraction * len(idx)))
        gone = set(np.random.default_rng(seed).choice(idx, size=k, replace=False).tolist())
        c.messages = [m for i, m in enumerate(c.messages) if i not in gone]
    return apply


def half_rate(topic: str) -> Transform:
    """``topic`` logged at half rate: every second of its messages (the 2nd, 4th, ... in log-time
    order) is gone."""
    def apply(c: McapContent) -> None:
        cid = c.channel_id(topic)
        ordered = sorted((i for i, m in enumerate(c.messages) if m.channel_id == cid),
                         key=lambda i: (c.messages[i].log_time, i))
        gone = set(ordered[1::2])
        c.messages = [m for i, m in enumerate(c.messages) if i not in gone]
    return apply


# -------------------------------------------------------------------------------- clocks


def clock_offset(topic: str, seconds: float = 0.5) -> Transform:
    """``topic``'s log times on another clock: ``seconds`` added to each (file order kept)."""
    def apply(c: McapContent) -> None:
        cid = c.channel_id(topic)
        d = round(seconds * NS)
        for m in c.messages:
            if m.channel_id == cid:
                m.log_time += d
    return apply


def flush_stamps(topic: str, period_s: float = 1.0) -> Transform:
    """``topic`` stamped at flush time: each log time snapped up to the next multiple of
    ``period_s`` of the clock (one already on a boundary stays), file order kept."""
    def apply(c: McapContent) -> None:
        cid = c.channel_id(topic)
        p = round(period_s * NS)
        for m in c.messages:
            if m.channel_id == cid:
                m.log_time = -(-m.log_time // p) * p
    return apply


def jitter(ms: float = 20.0, seed: int = 0) -> Transform:
    """Every log time moved by a uniform draw in [-ms, +ms] (``seed``), file order kept; a time
    is never moved below zero."""
    def apply(c: McapContent) -> None:
        d = np.random.default_rng(seed).uniform(-ms, ms, size=len(c.messages)) * 1e6
        for m, dt in zip(c.messages, d, strict=True):
            m.log_time = max(0, m.log_time + int(round(dt)))
    return apply


# ----------------------------------------------------------------------------- values


def noise(sigma: float = 0.03, seed: int = 0, topics: Iterable[str] | None = None) -> Transform:
    """Gaussian noise (``sigma``, drawn with ``seed``) added to every float field of every
    message (of ``topics``, default all channels whose encoding can be decoded)."""
    wanted = None if topics is None else set(topics)

    def apply(c: McapContent) -> None:
        rng = np.random.default_rng(seed)
        codecs = _Codecs(c)
        for m in c.messages:
            if wanted is not None and c.topic(m) not in wanted:
                continue
            m.data = codecs.perturb(m, lambda shape: rng.normal(0.0, sigma, size=shape))
    return apply


def step(topic: str, at_s: float, amount: float = 1.0) -> Transform:
    """``amount`` added to every float field of ``topic``'s messages logged ``at_s`` seconds after
    the recording's start or later (a +1 m step, by default)."""
    def apply(c: McapContent) -> None:
        cid = c.channel_id(topic)
        t0 = c.start + round(at_s * NS)
        codecs = _Codecs(c)
        for m in c.messages:
            if m.channel_id == cid and m.log_time >= t0:
                m.data = codecs.perturb(m, lambda shape: np.full(shape, amount))
    return apply


# ----------------------------------------------------------------------------- helpers


def _indices(c: McapContent, topic: str | None) -> list[int]:
    if topic is None:
        return list(range(len(c.messages)))
    cid = c.channel_id(topic)
    return [i for i, m in enumerate(c.messages) if m.channel_id == cid]


Draw = Callable[[tuple[int, ...]], np.ndarray]


class _Codecs:
    """Decode, change the floats of, and encode again the messages of one recording."""

    def __init__(self, content: McapContent) -> None:
        self._content = content
        self._cache: dict[int, tuple[Callable[[bytes], Any], Callable[[Any], bytes],
                                     Callable[[Any, Draw], Any]] | None] = {}

    def perturb(self, m: Message, draw: Draw) -> bytes:
        codec = self._codec(m.channel_id)
        if codec is None:
            return m.data
        decode, encode, change = codec
        return encode(change(decode(m.data), draw))

    def _codec(self, channel_id: int):
        if channel_id not in self._cache:
            ch = self._content.channels[channel_id]
            schema = self._content.schemas.get(ch.schema_id)
            self._cache[channel_id] = None
            if schema is not None and ch.message_encoding == "protobuf" and schema.encoding == "protobuf":
                self._cache[channel_id] = _protobuf_codec(schema)
            elif schema is not None and ch.message_encoding == "cdr" and schema.encoding in ("ros2msg",
                                                                                              "ros2idl"):
                self._cache[channel_id] = _cdr_codec(schema)
        return self._cache[channel_id]


def _protobuf_codec(schema: Schema):
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    fds = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    pending = {f.name: f for f in fds.file}
    added: set[str] = set()

    def add(name: str) -> None:
        if name in added or name not in pending:
            return
        added.add(name)
        for dep in pending[name].dependency:
            add(dep)
        pool.Add(pending[name])

    for name in list(pending):
        add(name)
    cls = message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))

    def decode(data: bytes) -> Any:
        return cls.FromString(data)

    def encode(msg: Any) -> bytes:
        return msg.SerializeToString()

    def change(msg: Any, draw: Draw) -> Any:
        _perturb_pb(msg, draw)
        return msg

    return decode, encode, change


def _perturb_pb(msg: Any, draw: Draw) -> None:
    from google.protobuf.descriptor import FieldDescriptor as FD

    floats = (FD.CPPTYPE_FLOAT, FD.CPPTYPE_DOUBLE)
    for fd in msg.DESCRIPTOR.fields:
        repeated = _is_repeated(fd)
        if fd.cpp_type in floats:
            if repeated:
                values = getattr(msg, fd.name)
                if len(values):
                    new = np.asarray(list(values), dtype=float) + draw((len(values),))
                    del values[:]
                    values.extend(new.tolist())
            else:
                setattr(msg, fd.name, float(getattr(msg, fd.name) + draw((1,))[0]))
        elif fd.cpp_type == FD.CPPTYPE_MESSAGE:
            if fd.message_type.GetOptions().map_entry:
                value_fd = fd.message_type.fields_by_name["value"]
                container = getattr(msg, fd.name)
                for key in sorted(container):
                    if value_fd.cpp_type in floats:
                        container[key] = float(container[key] + draw((1,))[0])
                    elif value_fd.cpp_type == FD.CPPTYPE_MESSAGE:
                        _perturb_pb(container[key], draw)
            elif repeated:
                for sub in getattr(msg, fd.name):
                    _perturb_pb(sub, draw)
            elif msg.HasField(fd.name):
                _perturb_pb(getattr(msg, fd.name), draw)


def _is_repeated(fd: Any) -> bool:
    is_rep = getattr(fd, "is_repeated", None)
    if is_rep is not None:
        return bool(is_rep)
    return fd.label == fd.LABEL_REPEATED


def _cdr_codec(schema: Schema):
    from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
    from rosbags.typesys.msg import normalize_msgtype

    text = schema.data.decode()
    if schema.encoding == "ros2msg":
        types = get_types_from_msg(text, schema.name)
    else:
        types = get_types_from_idl(text)
    store = get_typestore(Stores.EMPTY)
    store.register(types)
    typename = schema.name if schema.name in store.fielddefs else normalize_msgtype(schema.name)

    def decode(data: bytes) -> Any:
        return store.deserialize_cdr(data, typename)

    def encode(msg: Any) -> bytes:
        return bytes(store.serialize_cdr(msg, typename))

    def change(msg: Any, draw: Draw) -> Any:
        return _perturb_ros(msg, draw)

    return decode, encode, change


def _perturb_ros(value: Any, draw: Draw) -> Any:
    if isinstance(value, bool) or isinstance(value, int | str | bytes):
        return value
    if isinstance(value, float):
        return float(value + draw((1,))[0])
    if isinstance(value, np.ndarray):
        if value.dtype.kind == "f" and value.size:
            return (value + draw(value.shape)).astype(value.dtype)
        return value
    if isinstance(value, list):
        return [_perturb_ros(v, draw) for v in value]
    if dataclasses.is_dataclass(value):
        changes = {f.name: _perturb_ros(getattr(value, f.name), draw) for f in dataclasses.fields(value)}
        return dataclasses.replace(value, **changes)
    return value


# ---------------------------------------------------------------------- named artefacts


@dataclass(frozen=True)
class Artefact:
    """One artefact case: a name (``half_rate[/planning]``, ``lose#1``) and its transform."""

    name: str
    kind: str
    transform: Transform


def logging_artefacts(*, deviating_topic: str, other_topic: str | None, span_s: float, deviation_s: float,
                      seeds: Sequence[int] = (0, 1)) -> list[Artefact]:
    """The logging artefacts of issue 36, for a pair whose truth departs on ``deviating_topic``
    at ``deviation_s`` in a recording of ``span_s`` seconds: every file cut keeps the deviation
    (and a second after it) inside. ``other_topic`` is a channel of another module (None: the
    recording has none, and the per-channel artefacts are applied to the deviating one only)."""
    room = span_s - deviation_s - 1.0
    cuts = sorted({c for c in (0.5, min(7.0, room)) if 0.5 <= c <= room})
    out = [Artefact(f"truncate_end[{c:g}s]", "truncate_end", truncate_end(c)) for c in cuts]
    starts = sorted({s for s in (0.1, min(2.0, deviation_s - 1.0)) if 0.1 <= s})
    out += [Artefact(f"late_start[{s:g}s]", "late_start", late_start(s)) for s in starts]
    out.append(Artefact("latched_early[1s]", "latched_early", latched_early(None, 1.0)))
    out += [Artefact(f"duplicate#{s}", "duplicate", duplicate(seed=s)) for s in seeds]
    out += [Artefact(f"lose_1%#{s}", "lose_1%", lose(0.01, seed=s)) for s in seeds]
    for label, topic in (("deviating", deviating_topic), ("other", other_topic)):
        if topic is None:
            continue
        out.append(Artefact(f"half_rate[{topic}]", f"half_rate[{label}]", half_rate(topic)))
        out.append(Artefact(f"clock+0.5s[{topic}]", f"clock+0.5s[{label}]", clock_offset(topic, 0.5)))
        out.append(Artefact(f"flush_1s[{topic}]", f"flush_1s[{label}]", flush_stamps(topic, 1.0)))
    out += [Artefact(f"jitter_20ms#{s}", "jitter_20ms", jitter(20.0, seed=s)) for s in seeds]
    return out


def span_s(path: str | os.PathLike[str]) -> float:
    """A recording's log-time span [s] (from its summary statistics, else from its messages)."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is not None and summary.statistics is not None and summary.statistics.message_count:
            st = summary.statistics
            return (st.message_end_time - st.message_start_time) / NS
        times = [m.log_time for _, _, m in reader.iter_messages(log_time_order=False)]
    return (max(times) - min(times)) / NS if times else math.nan


# ------------------------------------------------------------------------------ judging

RIGHT, REFUSED, WARNED_WRONG, SILENT_WRONG = "right", "refused", "warned wrong", "silent wrong"
VERDICTS = (RIGHT, REFUSED, WARNED_WRONG, SILENT_WRONG)


@dataclass(frozen=True)
class Verdict:
    """How ``rocas.analysis.diff.diff`` answered one case with a known truth."""

    verdict: str
    module: str | None
    warnings: tuple[str, ...]
    detail: str


def judge(accident: str | os.PathLike[str], reference: str | os.PathLike[str], truth: str | None,
          cmg: Any = None) -> Verdict:
    """Diff ``accident`` against ``reference`` with the public :func:`rocas.analysis.diff.diff`
    (default settings) and classify the answer against ``truth`` (a module, or None: no module
    deviated): right; refused (a RocasError, which is not right but not silent either); warned
    wrong (another answer, with warnings / ``complete`` False); silent wrong (another answer and
    no warning)."""
    from rocas.analysis.diff import diff
    from rocas.errors import RocasError

    try:
        r = diff(accident, reference, cmg=cmg)
    except RocasError as exc:
        return Verdict(REFUSED, None, (), f"{type(exc).__name__}: {exc}")
    module, warnings = r.deviating_module, tuple(r.warnings)
    if module == truth:
        verdict = RIGHT
    elif warnings or not r.complete:
        verdict = WARNED_WRONG
    else:
        verdict = SILENT_WRONG
    return Verdict(verdict, module, warnings, f"module {module}" + (f", {len(warnings)} warning(s)"
                                                                    if warnings else ""))


def table(rows: Sequence[tuple[str, Verdict]], title: str = "class") -> str:
    """Counts per class (rows: (class, verdict)) and a total line: n, right, refused, warned
    wrong, silent wrong, right %."""
    classes: dict[str, list[Verdict]] = {}
    for cls, v in rows:
        classes.setdefault(cls, []).append(v)
    width = max([len(title), len("total")] + [len(c) for c in classes])
    head = f"{title:<{width}}  {'n':>4}  {'right':>5}  {'refused':>7}  {'warned wrong':>12}  " \
           f"{'silent wrong':>12}  {'right %':>7}"
    lines = [head, "-" * len(head)]

    def line(name: str, vs: list[Verdict]) -> str:
        n = len(vs)
        c = {k: sum(v.verdict == k for v in vs) for k in VERDICTS}
        pct = 100.0 * c[RIGHT] / n if n else 0.0
        return f"{name:<{width}}  {n:>4}  {c[RIGHT]:>5}  {c[REFUSED]:>7}  {c[WARNED_WRONG]:>12}  " \
               f"{c[SILENT_WRONG]:>12}  {pct:>6.1f}%"

    for cls, vs in classes.items():
        lines.append(line(cls, vs))
    lines.append("-" * len(head))
    lines.append(line("total", [v for _, v in rows]))
    return "\n".join(lines)
