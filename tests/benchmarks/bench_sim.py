"""Benchmark of the built-in simulator (prints figures; not a timed test).

Batch mode with the full ADS on a 30-second scenario for batch sizes 1, 64, 256
(variant-ticks per second of CPU time, min and median of R repeats), against a baseline:
the same benchmark run on another git revision's ``rocas`` (by default ``main``, extracted
with ``git archive`` into a temporary directory) in the same run, the two alternated repeat
by repeat in child processes so both see the same machine load. Also recording mode (a
30-second scenario written to MCAP).

Targets (issue #24, one core, junction_straight): >= 100,000 variant-ticks/s at batch 256,
>= 50,000 at batch 64, and batch 1 at least 3x the baseline.

With ``--breakdown``, instead: where a step's time goes, per part of the stack and the world
(localization, perception, ..., the actors, the oracles), as a fixed cost per step [us] and a
marginal cost per variant and step [us], fitted by least squares to the CPU time of each part
at several batch sizes (one child a size, this tree's code). Throughput at batch B is
B / (fixed + B * marginal); with no fixed cost at all it could not pass 1 / marginal.

    python tests/benchmarks/bench_sim.py [--scenario junction_straight] [--repeat 3]
        [--sizes 1,64,256] [--baseline main | --no-baseline]
    python tests/benchmarks/bench_sim.py --breakdown [--sizes 1,16,64,256,512]

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
from rocas.rollout import simulate_batch
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


# a child times each part of the stack's step at one batch size (this tree's code): every
# method or function below is wrapped with a CPU-time accumulator; "rest" is what is left of
# the whole batch (the engine's loop, its records, the digests)
_BREAKDOWN_CHILD = """
import json, sys, time
import rocas.stacks.ads.stack as stack, rocas.sim.engine as engine
from rocas.stacks.ads.control import Control
from rocas.stacks.ads.localization import Canbus, Localization
from rocas.stacks.ads.perception import Perception
from rocas.stacks.ads.planning import Planning
from rocas.stacks.ads.prediction import Prediction
from rocas.sim.oracles import Oracles
from rocas.scenarios import load_example
from rocas.rollout import simulate_batch
name, n, repeat = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
spent = {}
def timed(label, fn):
    def wrapper(*args, **kwargs):
        t0 = time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            spent[label] = spent.get(label, 0.0) + time.process_time() - t0
    return wrapper
for label, owner, attr in [
        ("localization", Localization, "step"), ("canbus", Canbus, "feedback"),
        ("canbus", Canbus, "actuate"), ("ground truth", stack, "ground_truth"),
        ("lights", stack, "light_state"), ("perception", Perception, "step"),
        ("prediction", Prediction, "step"), ("planning", Planning, "step"),
        ("control", Control, "step"), ("ego dynamics", engine, "bicycle_step"),
        ("actors", engine, "step_actors"), ("oracles", Oracles, "update")]:
    setattr(owner, attr, timed(label, getattr(owner, attr)))
scenario = load_example(name)
simulate_batch(scenario, seeds=[0])  # warm caches (map compilation, weights)
best = None
for _ in range(repeat):
    spent.clear()
    t0 = time.process_time()
    simulate_batch(scenario, seeds=list(range(n)))
    total = time.process_time() - t0
    parts = dict(spent, rest=total - sum(spent.values()), total=total)
    if best is None or total < best["total"]:
        best = parts
print(json.dumps({"parts": best, "ticks": scenario.num_ticks}))
"""


def breakdown(scenario: str, sizes: list[int], repeat: int) -> None:
    """Fixed and marginal cost of each part of a step (see the module's docstring)."""
    import numpy as np

    runs = []
    for n in sizes:
        done = subprocess.run([sys.executable, "-c", _BREAKDOWN_CHILD, scenario, str(n),
                               str(repeat)], env=dict(os.environ, PYTHONPATH=str(ROOT)),
                              capture_output=True, text=True, check=True, cwd=ROOT)
        runs.append(json.loads(done.stdout))
        total = runs[-1]["parts"]["total"]
        print(f"batch {n}: {total:.3f} s CPU (best of {repeat}), "
              f"{n * runs[-1]['ticks'] / total:,.0f} variant-ticks/s", flush=True)
    ticks = runs[0]["ticks"]
    design = np.stack([np.ones(len(sizes)), np.array(sizes, float)], axis=1)
    labels = [k for k in runs[0]["parts"] if k != "total"] + ["total"]
    print(f"{'part':>13} {'fixed us/step':>14} {'marginal us/vt':>15} "
          + " ".join(f"{'share@' + str(n):>10}" for n in sizes))
    for label in labels:
        secs = np.array([r["parts"].get(label, 0.0) for r in runs])
        (fixed, marginal), *_ = np.linalg.lstsq(design, secs, rcond=None)
        shares = " ".join(f"{100 * s / r['parts']['total']:>9.1f}%" for s, r in zip(secs, runs, strict=True))
        print(f"{label:>13} {1e6 * fixed / ticks:>14.1f} {1e6 * marginal / ticks:>15.2f} {shares}")
        if label == "total":
            print(f"bound with no fixed cost: {ticks / marginal:,.0f} variant-ticks/s "
                  f"(1 / marginal); at batch 256 with this fixed cost: "
                  f"{256 * ticks / (fixed + 256 * marginal):,.0f}")


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
    from rocas.rollout import simulate
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
    parser.add_argument("--breakdown", action="store_true",
                        help="fixed and marginal cost of each part of a step, this tree only")
    args = parser.parse_args()
    if args.breakdown:
        sizes = [int(x) for x in args.sizes.split(",")]
        if len(set(sizes)) < 2:
            raise SystemExit("bench_sim: --breakdown fits a line: give two or more --sizes")
        print(f"scenario {args.scenario}; load {os.getloadavg()[0]:.2f}; CPU seconds")
        breakdown(args.scenario, sizes, args.repeat)
        return
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
