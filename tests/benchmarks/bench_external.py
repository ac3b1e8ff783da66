"""Benchmark of the external-process adapter against in-process simulation (prints figures;
not a timed test).

On a lav catalog scenario (default L1, 14 s): one recorded simulation in-process
(``rocas.rollout.rollout`` with an output) against the same through the adapter's
single-run mode (``ExternalStack.run``, a fresh cache each repeat), and a batch of N variants
(an analysis's generation) in-process (``rollout_batch``) against the adapter's batch mode
(``ExternalStack.simulate_batch``, split over 1 and 2 processes), per simulation; then a
repeated batch from the adapter's cache. Wall time (the adapter's cost is mostly process
start-up and imports, which CPU time of this process would not see): min and median of R
repeats, and the ratio against in-process measured in the same run.

    python tests/benchmarks/bench_external.py [--entry L1] [--repeat 3] [--batch 24]
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
STACK_FILE = ROOT / "tests" / "stacks" / "lav-process.toml"


def timed(fn: Callable[[int], object], repeat: int) -> list[float]:
    out = []
    for k in range(repeat):
        t0 = time.perf_counter()
        fn(k)
        out.append(time.perf_counter() - t0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--entry", default="L1")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--batch", type=int, default=24)
    args = ap.parse_args()

    from rocas.catalog import entry
    from rocas.rollout import rollout, rollout_batch
    from rocas.stacks.external import ExternalStack
    from rocas.stacks.registry import get_stack

    e = entry(args.entry, "lav")
    s, lav, n = e.scenario, get_stack("lav"), args.batch
    params = [{"brake.brake_threshold": 0.05 + 0.9 * i / n} for i in range(n)]
    seeds = list(range(n))
    rollout(lav, s)  # warm: imports, map compilation, model weights
    with tempfile.TemporaryDirectory() as tmp:
        def ext(k: int, processes: int = 2) -> ExternalStack:
            x = ExternalStack.from_file(STACK_FILE, Path(tmp, f"cache{k}-{processes}"))
            return dataclasses.replace(x, command=(sys.executable, *x.command[1:]),
                                       processes=processes, min_per_process=1)

        rows = {
            "1 recorded run, in-process": timed(
                lambda k: rollout(lav, s, output=Path(tmp, f"in{k}.mcap")), args.repeat),
            "1 recorded run, adapter": timed(lambda k: ext(k).run(s), args.repeat),
            f"batch of {n}, in-process": timed(
                lambda k: rollout_batch(lav, [s] * n, params, seeds), args.repeat),
            f"batch of {n}, adapter, 1 process": timed(
                lambda k: ext(k, 1).simulate_batch([s] * n, params, seeds), args.repeat),
            f"batch of {n}, adapter, 2 processes": timed(
                lambda k: ext(k, 2).simulate_batch([s] * n, params, seeds), args.repeat),
        }
        cached = ext(0, 2)
        rows[f"batch of {n}, adapter, cached"] = timed(
            lambda k: cached.simulate_batch([s] * n, params, seeds), args.repeat)
    print(f"lav {e.id} ({s.duration_s:g} s scenario), wall seconds, {args.repeat} repeats")
    base = {"1": statistics.median(rows["1 recorded run, in-process"]),
            "b": statistics.median(rows[f"batch of {n}, in-process"])}
    for name, ts in rows.items():
        per = n if name.startswith("batch") else 1
        ref = base["b"] if name.startswith("batch") else base["1"]
        med = statistics.median(ts)
        print(f"  {name:38s} min {min(ts):7.3f}  median {med:7.3f}  "
              f"per simulation {med / per:7.4f}  x{med / ref:6.2f} in-process")


if __name__ == "__main__":
    main()
