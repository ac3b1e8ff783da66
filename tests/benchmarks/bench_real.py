"""Benchmark: `rocas diff` on real recordings from three stacks, with known truth (issue 36, item 5).

Recordings, their provenance and topology: tests/data/real/README.md and real.json. Cases
(tests/real_logs.py): (a) a recording against itself with independent sensor-level noise
(sigma 3 cm) on every float field of both sides, truth no module; (b) the same plus a +1 step
on one channel at a known time, truth that channel's writer; (c) (b) plus each logging artefact
of tests/artefacts.py on one side; (d) real pairs, the same drive with one module re-run, truth
that module. Each is diffed with the public ``rocas.analysis.diff.diff`` (default settings, the
recording's --cmg file) and classified right / refused / warned wrong / silent wrong.

Prints a table per class (and per artefact in c), the totals, the failing cases and the time.

    python tests/benchmarks/bench_real.py [--no-artefacts] [--failures FILE] [-v]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))

import artefacts as A  # noqa: E402
import real_logs  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--no-artefacts", action="store_true", help="classes a, b and d only")
    ap.add_argument("--failures", help="write the failing cases' names to this file")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every case as it is judged")
    args = ap.parse_args()

    m = real_logs.manifest()
    print("recordings:")
    for rec in m["recordings"]:
        print(f"  {rec['name']:<13} {rec['file']:<38} {A.span_s(real_logs.REAL / rec['file']):5.1f} s  "
              f"{rec['stack']}")
    t0 = time.perf_counter()
    rows: list[tuple[str, A.Verdict]] = []
    failures: list[str] = []
    with tempfile.TemporaryDirectory(prefix="bench-real-") as tmp:
        for case in real_logs.cases(artefacts=not args.no_artefacts):
            v = case.judge(Path(tmp))
            rows.append((case.cls, v))
            if v.verdict != A.RIGHT:
                failures.append(f"{case.name}: {v.verdict} ({v.detail}; truth {case.truth})")
            if args.verbose:
                print(f"  {case.name:<75} {v.verdict:<13} {v.detail}")
    elapsed = time.perf_counter() - t0

    def summary(cls_rows, title):
        print(A.table(cls_rows, title))

    print()
    summary([(c if not c.startswith("c:") else "c:artefacts", v) for c, v in rows], "class")
    arts = [(c[2:], v) for c, v in rows if c.startswith("c:")]
    if arts:
        print()
        summary(arts, "c: artefact")
    n = len(rows)
    right = sum(v.verdict == A.RIGHT for _, v in rows)
    silent = sum(v.verdict == A.SILENT_WRONG for _, v in rows)
    print(f"\nright {right}/{n} ({100.0 * right / n:.1f} %), silent wrong {silent}, time {elapsed:.1f} s")
    print(f"\nfailing cases ({len(failures)}):")
    for f in failures:
        print(f"  {f}")
    if args.failures:
        Path(args.failures).write_text("".join(f + "\n" for f in failures))


if __name__ == "__main__":
    main()
