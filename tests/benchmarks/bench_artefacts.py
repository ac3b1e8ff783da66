"""Benchmark: `rocas diff` on pairs with a known answer, one ordinary logging artefact applied to
one side (issue 36, item 5 and its first section).

Pairs (tests/data/pairs/pairs.json, see the README there): the shipped demo pair (truth:
prediction) and accident/reference pairs that `rocas analyze` wrote for catalog entries (truth:
the run's diff module). For each pair, each artefact of ``artefacts.logging_artefacts`` (file
ends earlier, logger started later, a latched message a second early, a message logged twice, 1 %
lost, a channel at half rate / on a clock 0.5 s ahead / stamped at flush time (the deviating
channel and another), +-20 ms jitter; the seeded ones with two seeds), applied to the reference
and then to the accident side, the pair is diffed with the public ``rocas.analysis.diff.diff``
(default settings) and classified: right, refused (RocasError), warned wrong, silent wrong.
Every file cut keeps the deviation and a second after it inside both files.

Prints the clean pairs' answers, a table per artefact class and the totals, the failing cases'
names and the time; ``--failures FILE`` writes the failing cases' names (one a line) to FILE.

With ``--noise SIGMA`` both sides also carry independent noise on every float (issue 36: two
real runs never agree bit for bit), the artefact on top of it.

    python tests/benchmarks/bench_artefacts.py [--pairs demo_a01,a05] [--failures FILE] [-v]
        [--noise 0.03]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))

import artefacts as A  # noqa: E402

PAIRS = ROOT / "tests" / "data" / "pairs" / "pairs.json"


def load_pairs(names: list[str] | None = None) -> list[dict]:
    pairs = json.loads(PAIRS.read_text())["pairs"]
    if names:
        unknown = set(names) - {p["name"] for p in pairs}
        if unknown:
            raise SystemExit(f"unknown pair(s) {sorted(unknown)}; known: {[p['name'] for p in pairs]}")
        pairs = [p for p in pairs if p["name"] in names]
    return pairs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pairs", help="comma-separated pair names (default: all)")
    ap.add_argument("--failures", help="write the failing cases' names to this file")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every case as it is judged")
    ap.add_argument("--noise", type=float, default=0.0, metavar="SIGMA",
                    help="also put independent gaussian noise of SIGMA on every float of both "
                    "sides (seeded; the artefacts with their first seed only), as two real runs "
                    "of the same drive differ")
    args = ap.parse_args()
    pairs = load_pairs(args.pairs.split(",") if args.pairs else None)

    t_start = time.perf_counter()
    rows: list[tuple[str, A.Verdict]] = []
    failures: list[str] = []
    print("clean pairs (no artefact):")
    with tempfile.TemporaryDirectory(prefix="bench-artefacts-") as tmp:
        for p in pairs:
            acc, ref = ROOT / p["accident"], ROOT / p["reference"]
            base_a: tuple = ()
            base_b: tuple = ()
            if args.noise:
                base_a, base_b = (A.noise(args.noise, seed=1),), (A.noise(args.noise, seed=2),)
                noisy_a, noisy_b = Path(tmp) / "noisy-accident.mcap", Path(tmp) / "noisy-reference.mcap"
                A.rewrite(acc, noisy_a, *base_a)
                A.rewrite(ref, noisy_b, *base_b)
                acc, ref = noisy_a, noisy_b
            clean = A.judge(acc, ref, p["truth"])
            print(f"  {p['name']:<10} truth {p['truth']:<11} -> {clean.verdict} ({clean.detail})")
            span = min(A.span_s(acc), A.span_s(ref))
            arts = A.logging_artefacts(deviating_topic=p["deviating_topic"], other_topic=p["other_topic"],
                                       span_s=span, deviation_s=p["deviation_s"],
                                       seeds=(0,) if args.noise else (0, 1))
            for art in arts:
                for side in ("reference", "accident"):
                    out = Path(tmp) / f"{p['name']}-{side}.mcap"
                    if side == "reference":
                        A.rewrite(ref, out, art.transform)
                        v = A.judge(acc, out, p["truth"])
                    else:
                        A.rewrite(acc, out, art.transform)
                        v = A.judge(out, ref, p["truth"])
                    name = f"{p['name']}:{art.name}@{side}"
                    rows.append((art.kind, v))
                    if v.verdict != A.RIGHT:
                        failures.append(f"{name}: {v.verdict} ({v.detail})")
                    if args.verbose:
                        print(f"  {name:<55} {v.verdict:<13} {v.detail}")
    elapsed = time.perf_counter() - t_start

    print()
    print(f"artefact cases: {len(pairs)} pairs x artefacts x 2 sides, truth per pair")
    print(A.table(rows, "artefact class"))
    n = len(rows)
    right = sum(v.verdict == A.RIGHT for _, v in rows)
    silent = sum(v.verdict == A.SILENT_WRONG for _, v in rows)
    print(f"\nright {right}/{n} ({100.0 * right / n:.1f} %), silent wrong {silent}, "
          f"time {elapsed:.1f} s ({1000 * elapsed / n:.0f} ms a case, rewrite included)")
    print(f"\nfailing cases ({len(failures)}):")
    for f in failures:
        print(f"  {f}")
    if args.failures:
        Path(args.failures).write_text("".join(f + "\n" for f in failures))


if __name__ == "__main__":
    main()
