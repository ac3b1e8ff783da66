"""Benchmark of `rocas analyze` over the catalog recordings as whole processes (prints figures;
not a test).

Each entry's recording is analysed at default settings (``--workers`` and ``--validation`` can
be set), once per repeat, by this checkout and, with ``--baseline REF``, by the code of git
revision REF (extracted with ``git archive`` into a temporary directory and run with
``PYTHONPATH`` pointing at it, in the same environment). The two alternate entry by entry, so
that a change of load on a shared machine touches both. Printed per entry: wall and CPU time
(min over the repeats; CPU is user + system of the process and its workers, which a shared
machine disturbs less), peak RSS, the answer (verdict, module and parameter) of each side; then
per side the median over the entries of each entry's min and of each entry's median, the
median time of each phase (report.json ``timings_s``), the ratios, and the load average
(target of issue #24: a median of at most 10 s wall on 2 cores).

Usage: python tests/benchmarks/bench_analyze.py [--entries a01,a09] [--repeat 1]
           [--baseline REF] [--workers N] [--validation K]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_diff import run_child  # noqa: E402  (a sibling script, not a package)

ROOT = Path(__file__).resolve().parents[2]


def answer(report: dict) -> str:
    params = ",".join(m["parameter"].split(".")[-1] for m in report.get("misconfiguration", []))
    return f"{report.get('verdict')}:{report.get('deviating_module')}:{params or '-'}"


def analyze_once(recording: Path, extra: list[str], pythonpath: str
                 ) -> tuple[float, float, float, dict]:
    with tempfile.TemporaryDirectory() as tmp:
        argv = [sys.executable, "-m", "rocas", "analyze", str(recording), "--out",
                str(Path(tmp) / "run"), "--json", *extra]
        # `python -m` puts the working directory first on sys.path: run in the side's checkout
        env = {**os.environ, "PYTHONPATH": pythonpath}
        wall, cpu, rss, out = run_child(argv, env=env, cwd=pythonpath)
        return wall, cpu, rss, json.loads(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--entries", default="", help="comma-separated prefixes (default: all a*.mcap)")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--baseline", metavar="REF", help="also time git revision REF")
    ap.add_argument("--workers", type=int)
    ap.add_argument("--validation", type=int)
    args = ap.parse_args()
    recs = sorted((ROOT / "recordings").glob("a*.mcap"))
    if args.entries:
        wanted = args.entries.split(",")
        recs = [r for r in recs if any(r.name.startswith(w) for w in wanted)]
    extra = []
    if args.workers is not None:
        extra += ["--workers", str(args.workers)]
    if args.validation is not None:
        extra += ["--validation", str(args.validation)]
    sides: dict[str, str] = {"current": str(ROOT)}
    worktree = None
    if args.baseline:
        worktree = Path(tempfile.mkdtemp(prefix="rocas-baseline-"))
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.baseline, "rocas"],
                                 check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(worktree)], input=archive, check=True)
        sides = {"baseline": str(worktree), "current": str(ROOT)}
    for side, path in sides.items():  # each side must import its own code
        where = subprocess.run([sys.executable, "-c", "import rocas; print(rocas.__file__)"], cwd=path,
                               env={**os.environ, "PYTHONPATH": path}, capture_output=True, text=True)
        if not where.stdout.strip().startswith(path):
            raise SystemExit(f"{side}: rocas imported from {where.stdout.strip()!r}, not {path}")
    runs: dict[str, dict[str, list[tuple[float, float, float]]]] = {s: {} for s in sides}
    answers: dict[str, dict[str, str]] = {s: {} for s in sides}
    phases: dict[str, dict[str, list[float]]] = {s: {} for s in sides}
    try:
        for rec in recs:
            for _ in range(args.repeat):
                for side, path in sides.items():
                    wall, cpu, rss, report = analyze_once(rec, extra, path)
                    runs[side].setdefault(rec.stem, []).append((wall, cpu, rss))
                    answers[side][rec.stem] = answer(report)
                    for phase, t in (report.get("timings_s") or {}).items():
                        phases[side].setdefault(phase, []).append(t)
            line = "  ".join(f"{side}: wall {min(r[0] for r in runs[side][rec.stem]):6.1f} s "
                             f"cpu {min(r[1] for r in runs[side][rec.stem]):6.1f} s "
                             f"rss {max(r[2] for r in runs[side][rec.stem]):5.0f} MB "
                             f"{answers[side][rec.stem]}" for side in sides)
            print(f"{rec.stem[:28]:28s} {line}", flush=True)
    finally:
        if worktree is not None:
            shutil.rmtree(worktree, ignore_errors=True)
    print(f"\n{len(recs)} entries, {args.repeat} run(s) each, settings: {' '.join(extra) or 'defaults'}")
    medians = {}
    for side in sides:
        walls = [min(r[0] for r in v) for v in runs[side].values()]
        cpus = [min(r[1] for r in v) for v in runs[side].values()]
        medians[side] = (statistics.median(walls), statistics.median(cpus))
        mid_walls = [statistics.median(r[0] for r in v) for v in runs[side].values()]
        mid_cpus = [statistics.median(r[1] for r in v) for v in runs[side].values()]
        print(f"{side:9s} median over entries (of each entry's min): wall {medians[side][0]:.1f} s, "
              f"cpu {medians[side][1]:.1f} s; min wall {min(walls):.1f} s, max wall {max(walls):.1f} s")
        print(f"{'':9s} median over entries (of each entry's median): wall "
              f"{statistics.median(mid_walls):.1f} s, cpu {statistics.median(mid_cpus):.1f} s")
        print(f"{'':9s} median phase wall [s]: " + ", ".join(
            f"{k} {statistics.median(v):.2f}" for k, v in phases[side].items()))
    if "baseline" in sides:
        b, c = medians["baseline"], medians["current"]
        print(f"speed-up of the median: wall {b[0] / c[0]:.2f}x, cpu {b[1] / c[1]:.2f}x")
        changed = [k for k in answers["current"] if answers["current"][k] != answers["baseline"][k]]
        print(f"answers changed: {len(changed)}" + (f" ({', '.join(changed)})" if changed else ""))
    print(f"load average at the end: {os.getloadavg()[0]:.1f} (wall times are CPU-bound; "
          "compare CPU on a shared machine)")


if __name__ == "__main__":
    main()
