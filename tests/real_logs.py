"""Cases with a known answer built from the real recordings of tests/data/real/ (issue 36, item 5).

Shared by tests/benchmarks/bench_real.py (every case) and tests/analysis/test_real_logs.py (a fast
subset). Classes:

- ``a:noise``: a recording against itself, independent gaussian noise (``SIGMA``) on every float
  field on both sides: truth None (noise alone names no module);
- ``b:step``: the same, plus +1 on every float field of one channel from a known time on in the
  accident: truth the channel's writer;
- ``c:<artefact>``: a ``b:step`` case with one logging artefact (tests/artefacts.py) on one side;
- ``d:pair``: a real pair, the same drive with one module re-run: truth that module.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import artefacts as A

REAL = Path(__file__).resolve().parent / "data" / "real"
SIGMA = 0.03  # [m, or the field's unit]: sensor-level noise of a few centimetres
NOISE_SEEDS = (0, 1)


@dataclass(frozen=True)
class Case:
    """One case: each side is (source file, base transforms, artefact transforms); the base
    (noise, step) is computed once per distinct base and reused by the artefacts on top of it."""

    name: str
    cls: str
    truth: str | None
    cmg: Path
    accident: tuple[Path, tuple[A.Transform, ...], tuple[A.Transform, ...]]
    reference: tuple[Path, tuple[A.Transform, ...], tuple[A.Transform, ...]]

    def files(self, tmp: Path) -> tuple[Path, Path]:
        """The two files of the case (written into ``tmp`` where a side is transformed)."""
        out = []
        for side, (src, base, extra) in (("accident", self.accident), ("reference", self.reference)):
            if not base and not extra:
                out.append(src)
                continue
            content = _based(src, base)
            for t in extra:
                t(content)
            dst = tmp / f"{side}.mcap"
            A.write(content, dst)
            out.append(dst)
        return out[0], out[1]

    def judge(self, tmp: Path) -> A.Verdict:
        acc, ref = self.files(tmp)
        return A.judge(acc, ref, self.truth, cmg=self.cmg)


#: (source, ids of the base transforms) -> (the transforms, kept alive so that their ids are not
#: reused, and the content with them applied)
_BASES: dict[tuple, tuple[tuple[A.Transform, ...], A.McapContent]] = {}


def _based(src: Path, base: tuple[A.Transform, ...]) -> A.McapContent:
    """A fresh copy of ``src`` with ``base`` applied (the result is kept for the next case)."""
    key = (str(src), tuple(id(t) for t in base))
    if key not in _BASES:
        content = A.read(src)
        for t in base:
            t(content)
        _BASES[key] = (base, content)
    c = _BASES[key][1]
    return dataclasses.replace(c, messages=[dataclasses.replace(m) for m in c.messages])


def manifest() -> dict:
    return json.loads((REAL / "real.json").read_text())


def _noise(seed: int, side: str) -> A.Transform:
    # independent draws for the two sides, reproducible from the case's seed
    return A.noise(SIGMA, seed=1000 * seed + (1 if side == "accident" else 2))


def cases(*, artefacts: bool = True, pairs: bool = True, noise_seeds=NOISE_SEEDS) -> Iterator[Case]:
    m = manifest()
    for rec in m["recordings"]:
        path, cmg = REAL / rec["file"], REAL / rec["cmg"]
        noise = {s: (_noise(s, "accident"), _noise(s, "reference")) for s in noise_seeds}
        for s in noise_seeds:
            yield Case(f"{rec['name']}:noise#{s}", "a:noise", None, cmg,
                       (path, (noise[s][0],), ()), (path, (noise[s][1],), ()))
        for st in rec["steps"]:
            step = A.step(st["topic"], st["at_s"], 1.0)
            for s in noise_seeds:
                yield Case(f"{rec['name']}:step[{st['topic']}@{st['at_s']:g}s]#{s}", "b:step", st["truth"],
                           cmg, (path, (noise[s][0], step), ()), (path, (noise[s][1],), ()))
            if not artefacts:
                continue
            span = A.span_s(path)
            arts = A.logging_artefacts(deviating_topic=st["topic"], other_topic=rec["other_topic"],
                                       span_s=span, deviation_s=st["at_s"])
            s = noise_seeds[0]
            for art in arts:
                for side in ("reference", "accident"):
                    acc_extra = (art.transform,) if side == "accident" else ()
                    ref_extra = (art.transform,) if side == "reference" else ()
                    yield Case(f"{rec['name']}:step[{st['topic']}]+{art.name}@{side}", f"c:{art.kind}",
                               st["truth"], cmg, (path, (noise[s][0], step), acc_extra),
                               (path, (noise[s][1],), ref_extra))
    if pairs:
        for p in m["pairs"]:
            yield Case(p["name"], "d:pair", p["truth"], REAL / p["cmg"],
                       (REAL / p["accident"], (), ()), (REAL / p["reference"], (), ()))
