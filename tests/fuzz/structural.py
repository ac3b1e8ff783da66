"""Structural damage to real recordings, and how each command answers it (issue 21).

Where :mod:`fuzz.mutate` hunts crashes, this module asks the question a root-cause tool must
answer right: given a damaged accident recording, does a command refuse it, answer with a
warning, or answer *silently* -- and then, is the silent answer the one the undamaged file
gives? The last case with a different answer is the one that must never happen.

Mutations (``KINDS``), each deterministic in its ``random.Random``:

- ``remove``: delete one whole chunk; ``duplicate``: repeat one whole chunk right after it;
- ``reorder``: swap two whole chunks (or, in a one-chunk file, move the chunk after the next
  record);
- ``truncate``: cut the file anywhere;
- ``bitflip``: flip 1 to 16 bits anywhere in the file;
- ``summary``: damage the summary section (flip bits in it, or cut it off with its footer).

Commands and what counts as their answer:

- ``diff``: exit status and the deviating module (``rocas diff A REF --json``);
- ``cmg``: exit status, the control channel and each channel's message count;
- ``replay``: the reconstructed scenario and recorded accident; when those differ from the
  undamaged file's, the replay's verdict (reproduced, accident kind, other party);
- ``analyze``: its input-dependent stage, the reconstruction (scenario and recorded accident):
  everything after it is a deterministic function of the scenario.

A warning is a ``rocas: warning:`` line (for replay and analyze: a line of the reconstruction's
warnings or notes) that the undamaged file does not produce.
"""

from __future__ import annotations

import io
import json
import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzz.mutate import CHUNK, layout

KINDS = ("remove", "duplicate", "reorder", "truncate", "bitflip", "summary")
COMMANDS = ("diff", "cmg", "replay", "analyze")
REFUSED, WARNED, SILENT_SAME, SILENT_CHANGED = "refused", "warned", "silent, same", "silent, changed"


def _chunks(data: bytes) -> list[tuple[int, int]]:
    return [(off, size) for off, op, size in layout(data).records if op == CHUNK]


def _summary_start(data: bytes) -> int | None:
    import struct

    if len(data) < 8 + 29:
        return None
    _, _, start, _, _ = struct.unpack_from("<BQQQI", data, len(data) - 8 - 29)
    return start if 8 < start < len(data) - 37 else None


def mutate(data: bytes, rng: random.Random, kind: str) -> tuple[bytes, str]:
    """One structural mutation of ``data``; returns (bytes, what was done)."""
    chunks = _chunks(data)
    if kind in ("remove", "duplicate", "reorder") and not chunks:
        kind = "truncate"
    if kind == "remove":
        off, size = rng.choice(chunks)
        return data[:off] + data[off + size :], f"remove the chunk at {off}"
    if kind == "duplicate":
        off, size = rng.choice(chunks)
        end = off + size
        return data[:end] + data[off:end] + data[end:], f"duplicate the chunk at {off}"
    if kind == "reorder":
        if len(chunks) >= 2:
            (a, sa), (b, sb) = sorted(rng.sample(chunks, 2))
            out = data[:a] + data[b : b + sb] + data[a + sa : b] + data[a : a + sa] + data[b + sb :]
            return out, f"swap the chunks at {a} and {b}"
        recs = layout(data).records
        (off, size) = chunks[0]
        after = [r for r in recs if r[0] == off + size]
        if not after:
            return data, "nothing to reorder"
        _, _, nsize = after[0]
        end = off + size + nsize
        return data[:off] + data[off + size : end] + data[off : off + size] + data[end:], \
            f"move the chunk at {off} after the next record"
    if kind == "truncate":
        cut = rng.randrange(8, len(data))
        return data[:cut], f"truncate at {cut}"
    if kind == "bitflip":
        buf = bytearray(data)
        n = rng.choice((1, 1, 2, 4, 8, 16))
        where = sorted(rng.randrange(len(buf)) for _ in range(n))
        for i in where:
            buf[i] ^= 1 << rng.randrange(8)
        return bytes(buf), f"flip {n} bits at {where[:4]}"
    if kind == "summary":
        start = _summary_start(data)
        if start is None:
            return data[: len(data) - 8], "cut the magic at the end"
        if rng.random() < 0.3:
            return data[:start], f"cut off the summary at {start}"
        buf = bytearray(data)
        n = rng.choice((1, 2, 4, 8))
        where = sorted(rng.randrange(start, len(buf) - 8) for _ in range(n))
        for i in where:
            buf[i] ^= 1 << rng.randrange(8)
        return bytes(buf), f"flip {n} bits in the summary at {where[:4]}"
    raise ValueError(f"unknown kind {kind!r}")


def case(seeds: list[bytes], number: int) -> tuple[int, str, bytes, str]:
    """Input ``number``: (index of the seed it damages, kind, bytes, what); deterministic."""
    rng = random.Random(number)
    kind = KINDS[number % len(KINDS)]
    which = rng.randrange(len(seeds))
    data, what = mutate(seeds[which], rng, kind)
    return which, kind, data, what


# -- running a command on one input ------------------------------------------------------------


@dataclass(frozen=True)
class Answer:
    """What a command said: refused or not, its answer, its warning lines."""

    refused: bool
    answer: Any
    warnings: frozenset[str]


def _cli(argv: list[str]) -> tuple[int, str, str]:
    from rocas.cli.console import Env
    from rocas.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    code = main(argv, env=Env(stdout=out, stderr=err))
    return int(code), out.getvalue(), err.getvalue()


def _warning_lines(stderr: str, path: Path) -> frozenset[str]:
    return frozenset(ln.replace(str(path), "INPUT") for ln in stderr.splitlines()
                     if ln.startswith("rocas: warning:"))


def run_diff(path: Path, reference: Path) -> Answer:
    code, out, err = _cli(["diff", str(path), str(reference), "--json"])
    if code != 0:
        return Answer(True, code, frozenset())
    return Answer(False, json.loads(out)["deviating_module"], _warning_lines(err, path))


def run_cmg(path: Path) -> Answer:
    code, out, err = _cli(["cmg", str(path), "--format", "json"])
    if code != 0:
        return Answer(True, code, frozenset())
    doc = json.loads(out)
    counts = tuple(sorted((c["topic"], c.get("messages", 0)) for c in doc["channels"]))
    return Answer(False, (doc.get("control_channel"), counts), _warning_lines(err, path))


def reconstruction(path: Path) -> Answer:
    """The reconstruction stage (replay's and analyze's input-dependent part)."""
    from rocas.errors import RocasError
    from rocas.replay.reconstruction import reconstruct

    try:
        rec = reconstruct(path)
    except RocasError:
        return Answer(True, None, frozenset())
    lines = tuple(getattr(rec, "warnings", ())) + tuple(rec.notes)
    key = (repr(rec.scenario), repr(rec.original))
    return Answer(False, (key, rec), frozenset(ln.replace(str(path), "INPUT") for ln in lines))


def replay_verdict(rec: Any) -> tuple[Any, ...]:
    from rocas.replay.run import replay

    report = replay(rec)
    acc = report.accident
    return (report.reproduced, acc.kind if acc else None, acc.other if acc else None)


def classify(got: Answer, base: Answer, changed: bool) -> str:
    """One input's outcome against the undamaged file's answer ``base``."""
    if got.refused:
        return REFUSED
    if got.warnings - base.warnings:
        return WARNED
    return SILENT_CHANGED if changed else SILENT_SAME
