"""Benchmark: what rocas.numerics costs against numpy's own (SIMD, machine-dependent) kernels.

Prints CPU microseconds per call (min and median of R repeats of N calls) for batch sizes 1
and 64, and the ratio against numpy measured in the same run. CPU time, not wall time: the
machine is shared.

    python tests/benchmarks/bench_numerics.py [--calls 2000] [--repeat 7]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from rocas import numerics


def per_call_us(fn, calls: int, repeat: int) -> tuple[float, float]:
    times = []
    for _ in range(repeat):
        t0 = time.process_time()
        for _ in range(calls):
            fn()
        times.append((time.process_time() - t0) / calls * 1e6)
    return min(times), statistics.median(times)


def _pairs(x: np.ndarray, y: np.ndarray) -> dict:
    """(rocas.numerics call, numpy call) per function, on the same inputs."""
    pos = np.abs(x) + 0.1
    return {
        "exp": (lambda: numerics.exp(x), lambda: np.exp(x)),
        "log": (lambda: numerics.log(pos), lambda: np.log(pos)),
        # log without its special-case test, for arguments known positive (Box-Muller's)
        "log_pos": (lambda: numerics.log_positive(pos), lambda: np.log(pos)),
        "arctan": (lambda: numerics.arctan(x), lambda: np.arctan(x)),
        "arctan2": (lambda: numerics.arctan2(y, x), lambda: np.arctan2(y, x)),
        "tanh": (lambda: numerics.tanh(x), lambda: np.tanh(x)),
        "power": (lambda: numerics.power(pos, 2.5), lambda: np.power(pos, 2.5)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    print(f"{'batch':>5} {'function':<8} {'numerics us (min/med)':>22} {'numpy us (min/med)':>19} "
          f"{'ratio':>6}")
    for n in (1, 64):
        pairs = _pairs(rng.uniform(-3, 3, n), rng.uniform(-3, 3, n))
        for name, (ours, theirs) in pairs.items():
            a = per_call_us(ours, args.calls, args.repeat)
            b = per_call_us(theirs, args.calls, args.repeat)
            print(f"{n:>5} {name:<8} {a[0]:>10.1f} / {a[1]:>8.1f} {b[0]:>9.2f} / {b[1]:>7.2f} "
                  f"{a[1] / b[1]:>6.0f}x")


if __name__ == "__main__":
    main()
