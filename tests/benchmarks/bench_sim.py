"""Benchmark of the built-in simulator (prints figures; not a timed test).

Batch mode with the full ADS on a 30-second scenario for batch sizes 1, 8, 64, 256
(variant-ticks per second), and recording mode (a 30-second scenario written to MCAP).

Targets: >= 20,000 variant-ticks/s at batch 64 on one core (64 x 600 ticks in <= 2 s);
recording a 30-second scenario in <= 1 s.

    python tests/benchmarks/bench_sim.py [--scenario junction_straight] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

from rocas.scenarios import load_example
from rocas.sim.engine import simulate, simulate_batch


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="junction_straight")
    parser.add_argument("--sizes", default="1,8,64,256")
    parser.add_argument("--repeat", type=int, default=3, help="best of R runs")
    args = parser.parse_args()
    scenario = load_example(args.scenario)
    ticks = scenario.num_ticks
    print(f"scenario {scenario.name}: {scenario.duration_s:g} s, {ticks} ticks, "
          f"{len(scenario.actors)} actors, {len(scenario.objects)} objects; "
          f"pid {os.getpid()}, cpus {os.cpu_count()}")
    simulate_batch(scenario, seeds=[0])  # warm caches (map compilation, weights)
    print(f"{'batch':>6} {'seconds':>9} {'variant-ticks/s':>16} {'ms/tick':>8}")
    for n in (int(x) for x in args.sizes.split(",")):
        best = float("inf")
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            simulate_batch(scenario, seeds=list(range(n)))
            best = min(best, time.perf_counter() - t0)
        print(f"{n:>6} {best:>9.3f} {n * ticks / best:>16,.0f} {1000 * best / ticks:>8.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        best = float("inf")
        for i in range(args.repeat):
            path = os.path.join(tmp, f"run{i}.mcap")
            t0 = time.perf_counter()
            result = simulate(scenario, output=path)
            best = min(best, time.perf_counter() - t0)
        size = os.path.getsize(path)
        print(f"recording mode: {best:.3f} s for {ticks} ticks, {result.messages} messages, "
              f"{size / 1e6:.2f} MB")


if __name__ == "__main__":
    main()
