"""A mutation engine for MCAP bytes: damage that real logs suffer, and some they should not.

Mutations are pure functions of (seed recordings, ``random.Random``), so a failing input is
reproduced from its seed alone. :func:`layout` parses a *valid* recording into the byte
positions of its records and length fields, so the structure-aware mutations hit record
headers, chunk sizes and the lengths inside uncompressed chunks instead of landing
(almost always) in message payloads as uniform bit flips do.

Kinds (``KINDS``):

- ``truncate``: cut at any byte, or exactly at / just around a record boundary;
- ``bitflip``: flip 1 to 16 bits anywhere, or in a burst inside one record;
- ``splice``: the head of one recording followed by the tail of another (or of itself),
  cut at arbitrary or record-aligned offsets;
- ``length``: overwrite one length field (record length, chunk ``uncompressed_size``,
  compression string length, ``records_length``, an inner record's length, a string,
  byte array or map length) with 0, off-by-one, doubled, halved, huge (up to 2**64 - 1)
  or random values;
- ``records``: delete, duplicate or swap whole records;
- ``stack``: two or three of the above in a row.
"""

from __future__ import annotations

import random
import struct
from dataclasses import dataclass, field

MAGIC = b"\x89MCAP0\r\n"
_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")

# opcodes (MCAP spec)
SCHEMA, CHANNEL, MESSAGE, CHUNK = 0x03, 0x04, 0x05, 0x06

KINDS = ("truncate", "bitflip", "splice", "length", "records", "stack")


@dataclass(frozen=True)
class LengthField:
    """A length field: where it sits, how wide it is (4 or 8 bytes), what it says."""

    offset: int
    width: int
    what: str


@dataclass
class Layout:
    """Byte positions in one valid recording.

    Attributes:
        records: (offset, opcode, total size) of every top-level record, magic excluded.
        lengths: every length field found (top level and inside uncompressed chunks).
        inner: (offset, total size) of records inside uncompressed chunks.
    """

    records: list[tuple[int, int, int]] = field(default_factory=list)
    lengths: list[LengthField] = field(default_factory=list)
    inner: list[tuple[int, int]] = field(default_factory=list)


def _string_lengths(data: bytes, start: int, end: int, opcode: int, out: list[LengthField]) -> None:
    """Length fields inside a schema or channel record body ``data[start:end]``."""
    try:
        if opcode == SCHEMA:
            p = start + 2  # id
            for what in ("schema name", "schema encoding", "schema data"):
                out.append(LengthField(p, 4, what))
                p += 4 + _U32.unpack_from(data, p)[0]
        elif opcode == CHANNEL:
            p = start + 4  # id, schema id
            for what in ("channel topic", "message encoding"):
                out.append(LengthField(p, 4, what))
                p += 4 + _U32.unpack_from(data, p)[0]
            out.append(LengthField(p, 4, "channel metadata map"))
            if p + 4 < end:
                q = p + 4  # first metadata key
                out.append(LengthField(q, 4, "metadata key"))
    except struct.error:
        pass


def layout(data: bytes) -> Layout:
    """Parse a recording's structure (never raises; stops at the first oddity)."""
    lay = Layout()
    try:
        _parse(data, lay)
    except (struct.error, IndexError):
        pass
    lay.lengths = [f for f in lay.lengths if f.offset + f.width <= len(data)]
    return lay


def _parse(data: bytes, lay: Layout) -> None:
    pos = len(MAGIC)
    while pos + 9 <= len(data):
        opcode, length = data[pos], _U64.unpack_from(data, pos + 1)[0]
        end = pos + 9 + length
        if end > len(data):
            break
        lay.records.append((pos, opcode, 9 + length))
        lay.lengths.append(LengthField(pos + 1, 8, f"record length (opcode {opcode:#04x})"))
        body = pos + 9
        if opcode in (SCHEMA, CHANNEL):
            _string_lengths(data, body, end, opcode, lay.lengths)
        elif opcode == CHUNK:
            lay.lengths.append(LengthField(body + 16, 8, "chunk uncompressed_size"))
            p = body + 28
            lay.lengths.append(LengthField(p, 4, "chunk compression length"))
            clen = _U32.unpack_from(data, p)[0]
            compression = data[p + 4 : p + 4 + clen]
            p += 4 + clen
            lay.lengths.append(LengthField(p, 8, "chunk records_length"))
            rlen = _U64.unpack_from(data, p)[0]
            if compression == b"":
                q, rend = p + 8, min(p + 8 + rlen, end)
                while q + 9 <= rend:
                    iop, ilen = data[q], _U64.unpack_from(data, q + 1)[0]
                    lay.inner.append((q, 9 + ilen))
                    lay.lengths.append(LengthField(q + 1, 8, f"inner record length ({iop:#04x})"))
                    if iop in (SCHEMA, CHANNEL):
                        _string_lengths(data, q + 9, q + 9 + ilen, iop, lay.lengths)
                    q += 9 + ilen
        if opcode == 0x02:  # footer
            break
        pos = end


def _put(buf: bytearray, f: LengthField, value: int) -> None:
    value %= 1 << (8 * f.width)
    (_U32 if f.width == 4 else _U64).pack_into(buf, f.offset, value)


def _get(buf: bytes, f: LengthField) -> int:
    return (_U32 if f.width == 4 else _U64).unpack_from(buf, f.offset)[0]


def _boundaries(lay: Layout) -> list[int]:
    return [off for off, _, _ in lay.records] + [off for off, _ in lay.inner]


def truncate(data: bytes, lay: Layout, rng: random.Random) -> tuple[bytes, str]:
    bounds = _boundaries(lay)
    if bounds and rng.random() < 0.5:
        cut = rng.choice(bounds) + rng.choice((-1, 0, 0, 1, 9, 10))
    else:
        cut = rng.randrange(0, len(data) + 1)
    cut = max(0, min(cut, len(data)))
    return data[:cut], f"truncate at {cut}"


def bitflip(data: bytes, lay: Layout, rng: random.Random) -> tuple[bytes, str]:
    if not data:
        return data, "nothing to flip"
    buf = bytearray(data)
    n = rng.choice((1, 1, 2, 4, 8, 16))
    if lay.records and rng.random() < 0.5:
        off, _, size = rng.choice(lay.records)
        lo, hi = off, off + size
    else:
        lo, hi = 0, len(buf)
    where = []
    for _ in range(n):
        i = rng.randrange(lo, hi)
        buf[i] ^= 1 << rng.randrange(8)
        where.append(i)
    return bytes(buf), f"flip {n} bits at {sorted(where)[:4]}..."


def splice(data: bytes, lay: Layout, rng: random.Random, other: bytes, other_lay: Layout,
           ) -> tuple[bytes, str]:
    if rng.random() < 0.5 and lay.records and other_lay.records:
        a = rng.choice(_boundaries(lay) or [len(MAGIC)])
        b = rng.choice(_boundaries(other_lay) or [len(MAGIC)])
    else:
        a, b = rng.randrange(0, len(data) + 1), rng.randrange(0, len(other) + 1)
    return data[:a] + other[b:], f"splice head[:{a}] + other[{b}:]"


def corrupt_length(data: bytes, lay: Layout, rng: random.Random) -> tuple[bytes, str]:
    if not lay.lengths:
        return bitflip(data, lay, rng)
    f = rng.choice(lay.lengths)
    buf = bytearray(data)
    old = _get(buf, f)
    top = (1 << (8 * f.width)) - 1
    new = rng.choice((
        0, 1, old - 1, old + 1, old + 9, old * 2, old // 2, len(data), len(data) - f.offset,
        3 << 30, 1 << 31, (1 << 32) - 1, 1 << 40, (1 << 63) - 1, top, rng.randrange(top + 1),
        old ^ (1 << rng.randrange(8 * f.width)),
    ))
    _put(buf, f, new)
    return bytes(buf), f"{f.what} at {f.offset}: {old} -> {new % (top + 1)}"


def edit_records(data: bytes, lay: Layout, rng: random.Random) -> tuple[bytes, str]:
    recs = lay.records[:-1] if len(lay.records) > 1 else lay.records  # keep the footer
    if not recs:
        return truncate(data, lay, rng)
    off, op, size = rng.choice(recs)
    chunk = data[off : off + size]
    how = rng.choice(("delete", "duplicate", "swap"))
    if how == "delete":
        return data[:off] + data[off + size :], f"delete record {op:#04x} at {off}"
    if how == "duplicate":
        return data[: off + size] + chunk + data[off + size :], f"duplicate record {op:#04x} at {off}"
    off2, op2, size2 = rng.choice(recs)
    if off2 == off:
        return data, "swap a record with itself"
    (a, sa), (b, sb) = sorted([(off, size), (off2, size2)])
    out = data[:a] + data[b : b + sb] + data[a + sa : b] + data[a : a + sa] + data[b + sb :]
    return out, f"swap records at {a} and {b}"


def mutate(seeds: list[tuple[bytes, Layout]], rng: random.Random, kind: str | None = None,
           ) -> tuple[bytes, str]:
    """One mutated input from one (or, for splices, two) of ``seeds``; returns (bytes, what)."""
    kind = kind or rng.choice(KINDS)
    data, lay = rng.choice(seeds)
    if kind == "truncate":
        return truncate(data, lay, rng)
    if kind == "bitflip":
        return bitflip(data, lay, rng)
    if kind == "splice":
        other, other_lay = rng.choice(seeds)
        return splice(data, lay, rng, other, other_lay)
    if kind == "length":
        return corrupt_length(data, lay, rng)
    if kind == "records":
        return edit_records(data, lay, rng)
    steps = []
    for _ in range(rng.randint(2, 3)):
        sub = rng.choice(KINDS[:-1])
        if sub == "splice":
            other, other_lay = rng.choice(seeds)
            data, what = splice(data, layout(data), rng, other, other_lay)
        else:
            data, what = mutate([(data, layout(data))], rng, sub)
        steps.append(what)
    return data, " then ".join(steps)


def case(seeds: list[tuple[bytes, Layout]], seed: int) -> tuple[str, bytes, str]:
    """The fuzz input number ``seed``: (kind, bytes, description); deterministic."""
    rng = random.Random(seed)
    kind = KINDS[seed % len(KINDS)]
    data, what = mutate(seeds, rng, kind)
    return kind, data, what


# -- seeds and the harness shared by tests/fuzz and tests/benchmarks/bench_fuzz.py ------------


def write_seeds(directory) -> list:
    """Write the seed recordings into ``directory``; returns their paths.

    The seeds cover what the reader must handle: zstd, lz4 and uncompressed chunks, many small
    chunks, an unchunked file, protobuf and JSON channels, an attachment and metadata.
    """
    from pathlib import Path

    from foreign_stack import write_run
    from mcap.writer import CompressionType, Writer

    from rocas.msgs import control_pb2, planning_pb2
    from rocas.recording import RecordingWriter, register_protobuf_channel

    d = Path(directory)
    paths = []
    for name, accident, comp in (("acme_zstd", True, CompressionType.ZSTD),
                                 ("acme_lz4", False, CompressionType.LZ4),
                                 ("acme_none", True, CompressionType.NONE)):
        p = d / f"{name}.mcap"
        write_run(p, accident=accident, duration_s=1.5, deviate_at_s=0.5, distractor_at_s=None,
                  compression=comp)
        paths.append(p)
    p = d / "rocas_small_chunks.mcap"
    with RecordingWriter(p, chunk_size=1024, compression="zstd") as w:
        w.add_channel("/control", control_pb2.ControlCommand, writers=["control"], role="control")
        w.add_channel("/planning", planning_pb2.ADCTrajectory, writers=["planning"],
                      readers=["control"])
        for i in range(60):
            w.write("/control", control_pb2.ControlCommand(throttle=i), log_time_ns=i * 10**8)
            w.write("/planning", planning_pb2.ADCTrajectory(lane_id=f"l{i}"),
                    log_time_ns=i * 10**8 + 1)
        w.add_attachment("rocas/world.json", b'{"lanes": []}', media_type="application/json")
    paths.append(p)
    p = d / "unchunked.mcap"
    with open(p, "wb") as f:
        w = Writer(f, use_chunking=False)
        w.start()
        cid = register_protobuf_channel(w, "/control", control_pb2.ControlCommand,
                                        writers=["control"], role="control")
        sid = w.register_schema("acme.Status", "jsonschema", b"{}")
        jid = w.register_channel("/status", "json", sid, {"rocas.writers": "diag"})
        w.add_metadata("run", {"driver": "fuzz"})
        for i in range(40):
            t = i * 10**8
            w.add_message(cid, log_time=t, publish_time=t,
                          data=control_pb2.ControlCommand(brake=i).SerializeToString())
            w.add_message(jid, log_time=t, publish_time=t, data=b'{"ok": true, "n": %d}' % i)
        w.finish()
    paths.append(p)
    return paths


def load_seeds(paths) -> list[tuple[bytes, Layout]]:
    out = []
    for p in paths:
        data = open(p, "rb").read()
        out.append((data, layout(data)))
    return out


def read_everything(path) -> int:
    """What the commands do with a recording: scan, decode every message, attachments.

    Returns the number of decoded messages. Raises only :class:`rocas.errors.RocasError`
    for inputs it refuses; anything else is a bug.
    """
    from rocas.recording import open_recording

    rec = open_recording(path)
    n = sum(1 for _ in rec.decoded())
    rec.report.warnings(str(path))
    for _ in rec.attachments():
        pass
    rec.summary_start_time_ns()
    return n


class Hang(Exception):
    """An input took longer than its time limit."""


def time_limit(seconds: float):
    """Raise :class:`Hang` in the main thread after ``seconds`` (SIGALRM; POSIX only)."""
    import contextlib
    import signal

    @contextlib.contextmanager
    def limit():
        def on_alarm(signum, frame):
            raise Hang(f"no answer after {seconds} s")

        old = signal.signal(signal.SIGALRM, on_alarm)
        signal.setitimer(signal.ITIMER_REAL, seconds)
        try:
            yield
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, old)

    return limit()


def run_one(data: bytes, path, reference, *, limit_s: float = 5.0, diff: bool = True) -> str:
    """Feed one input to the reader and (if ``diff``) to ``rocas diff INPUT REFERENCE``.

    Returns ``"ok"``; raises :class:`Hang` past ``limit_s`` per stage, AssertionError when
    ``rocas diff`` exits with anything but 0 (success) or 3 (refused input) or prints a
    traceback, and whatever unexpected exception the reader raised.
    """
    import io

    from rocas.cli.console import Env
    from rocas.cli.main import main
    from rocas.errors import RocasError

    with open(path, "wb") as f:
        f.write(data)
    with time_limit(limit_s):
        try:
            read_everything(path)
        except RocasError:
            pass
    if diff:
        out, err = io.StringIO(), io.StringIO()
        with time_limit(limit_s):
            code = main(["diff", str(path), str(reference), "--json"],
                        env=Env(stdout=out, stderr=err))
        text = err.getvalue()
        assert code in (0, 3), f"rocas diff exited {code}: {text[-500:]}"
        assert "Traceback" not in text and "internal error" not in text, text[-500:]
        if code == 3:
            assert text.count("rocas: error:") == 1, text
    return "ok"
