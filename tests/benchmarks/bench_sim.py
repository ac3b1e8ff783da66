"""Benchmark of the built-in simulator (prints figures; not a timed test).

Batch mode with the full ADS on a 30-second scenario for batch sizes 1, 64, 256
(variant-ticks per second of CPU time, min and median of R repeats), against a baseline:
the same benchmark run on another git revision's ``rocas`` (by default ``main``, extracted
with ``git archive`` into a temporary directory) in the same run, the two alternated repeat
by repeat in child processes so both see the same machine load. Also recording mode (a
30-second scenario written to MCAP).

Targets (issue #24, one core, junction_straight): >= 100,000 variant-ticks/s at batch 256,
>= 50,000 at batch 64, and batch 1 at least 3x the baseline.

    python tests/benchmarks/bench_sim.py [--scenario junction_straight] [--repeat 3]
        [--sizes 1,64,256] [--baseline main | --no-baseline]

CPU time (``time.process_time``), not wall time: the machine is shared.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# a child measures one batch size with whichever ``rocas`` its sys.path finds first
_CHILD = """
import json, sys, time
from rocas.scenarios import load_example
from rocas.ads.run import simulate_batch
name, n, repeat = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
scenario = load_example(name)
simulate_batch(scenario, seeds=[0])  # warm caches (map compilation, weights)
times = []
for _ in range(repeat):
    t0 = time.process_time()
    simulate_batch(scenario, seeds=list(range(n)))
    times.append(time.process_time() - t0)
import rocas
print(json.dumps({"times": times, "ticks": scenario.num_ticks, "module": rocas.__file__}))
"""


def measure(code_root: Path, scenario: str, n: int, repeat: int) -> tuple[list[float], int]:
    """CPU seconds of ``repeat`` batches of ``n`` variants, measured in a child process that
    imports ``rocas`` from ``code_root``."""
    env = dict(os.environ, PYTHONPATH=str(code_root))
    done = subprocess.run([sys.executable, "-c", _CHILD, scenario, str(n), str(repeat)],
                          env=env, capture_output=True, text=True, check=True, cwd=code_root)
    out = json.loads(done.stdout)
    if Path(out["module"]).resolve().parents[1] != code_root.resolve():
        raise SystemExit(f"bench_sim: the child imported {out['module']}, not {code_root}")
    return out["times"], out["ticks"]


def extract(ref: str, into: Path) -> str:
    """``rocas/`` of git revision ``ref`` into ``into``; returns the commit id."""
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", ref],
                            capture_output=True, text=True, check=True).stdout.strip()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "rocas"],
                             capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return commit


def recording_mode(scenario_name: str, repeat: int) -> None:
    sys.path.insert(0, str(ROOT))  # this checkout's rocas, as the children import it
    from rocas.ads.run import simulate
    from rocas.scenarios import load_example

    scenario = load_example(scenario_name)
    with tempfile.TemporaryDirectory() as tmp:
        times = []
        for i in range(repeat):
            path = os.path.join(tmp, f"run{i}.mcap")
            t0 = time.process_time()
            result = simulate(scenario, output=path)
            times.append(time.process_time() - t0)
        size = os.path.getsize(path)
    print(f"recording mode: {min(times):.3f} s min, {statistics.median(times):.3f} s median "
          f"for {scenario.num_ticks} ticks, {result.messages} messages, {size / 1e6:.2f} MB")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="junction_straight")
    parser.add_argument("--sizes", default="1,64,256")
    parser.add_argument("--repeat", type=int, default=3, help="repeats per batch size")
    parser.add_argument("--baseline", default="main", help="git revision to compare with")
    parser.add_argument("--no-baseline", action="store_true")
    args = parser.parse_args()
    print(f"scenario {args.scenario}; pid {os.getpid()}, cpus {os.cpu_count()}, "
          f"load {os.getloadavg()[0]:.2f}; CPU seconds, {args.repeat} repeats")
    with tempfile.TemporaryDirectory() as tmp:
        base_root = None
        if not args.no_baseline:
            base_root = Path(tmp)
            commit = extract(args.baseline, base_root)
            print(f"baseline: {args.baseline} ({commit}); this tree: {ROOT}")
        print(f"{'batch':>5} {'code':>8} {'min s':>7} {'med s':>7} {'vt/s (min)':>11} "
              f"{'vt/s (med)':>11} {'speed-up min/med':>17}")
        for n in (int(x) for x in args.sizes.split(",")):
            # one repeat per child, the two codes alternating, so that both see the same load
            times, base_times, ticks = [], [], 0
            for _ in range(args.repeat):
                if base_root is not None:
                    base_times += measure(base_root, args.scenario, n, 1)[0]
                got, ticks = measure(ROOT, args.scenario, n, 1)
                times += got
            rows = [("this", times)]
            if base_root is not None:
                rows.insert(0, ("baseline", base_times))
            base = rows[0][1]
            for label, ts in rows:
                lo, med = min(ts), statistics.median(ts)
                ratio = (f"{min(base) / lo:.2f}x / {statistics.median(base) / med:.2f}x"
                         if label == "this" and base_root is not None else "")
                print(f"{n:>5} {label:>8} {lo:>7.3f} {med:>7.3f} {n * ticks / lo:>11,.0f} "
                      f"{n * ticks / med:>11,.0f} {ratio:>17}", flush=True)
    recording_mode(args.scenario, args.repeat)


if __name__ == "__main__":
    main()
