"""Benchmark of `rocas diff` (prints figures; not a test).

Generates accident/reference pairs of the built-in channel mix at realistic rates and
sizes (rocas.recording.synthetic: 100 Hz pose/chassis/control, 10 Hz perception/prediction/
planning with 30 obstacles and 80-point forecasts, ~1 MB/s of serialized messages), then:

- diff wall time and messages per second on the 30 s pair;
- the same run's baseline: merely reading and decoding both files with mcap +
  mcap-protobuf-support (one DecoderFactory per file), and the ratio (target <= 3x);
- peak memory (max RSS of a fresh process running the diff) for 1x and 10x the length
  (target: flat, since both files are streamed);
- the change-point solver: ``ruptures.KernelCPD(kernel="linear")`` against
  ``ruptures.Pelt(model="l2")`` (the same segmentation) on noisy step series of 300 and 1200
  bins, and the speed-up.

Usage: python tests/benchmarks/bench_diff.py [--long-factor 10]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

from rocas.analysis import diff
from rocas.recording.synthetic import MixConfig, write_mix_pair

PEAK_SCRIPT = """
import resource, sys, time
from rocas.analysis import diff
t = time.perf_counter()
r = diff(sys.argv[1], sys.argv[2])
print(time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
      r.deviating_module)
"""


def raw_bytes(path: str) -> int:
    with open(path, "rb") as f:
        return sum(len(m.data) for _, _, m in make_reader(f).iter_messages())


def read_and_decode(path: str) -> int:
    n = 0
    with open(path, "rb") as f:
        for _ in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            n += 1
    return n


def peak(acc: str, ref: str) -> tuple[float, float, str]:
    out = subprocess.run([sys.executable, "-c", PEAK_SCRIPT, acc, ref], check=True,
                         capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1]), out[2]


def pelt_speedup(repeat: int) -> None:
    import numpy as np
    import ruptures

    for n in (300, 1200):
        rng = np.random.default_rng(0)
        y = (np.where(np.arange(n) >= n * 2 // 3, 1.0, 0.0) + 0.05 * rng.standard_normal(n))
        y = y.reshape(-1, 1)
        times = {}
        for name, algo in (("KernelCPD linear", ruptures.KernelCPD(kernel="linear", min_size=2,
                                                                      jump=1)),
                           ("Pelt l2", ruptures.Pelt(model="l2", min_size=2, jump=1))):
            best = float("inf")
            for _ in range(repeat):
                t = time.perf_counter()
                ends = algo.fit(y).predict(pen=0.05)
                best = min(best, time.perf_counter() - t)
            times[name] = (best, ends)
        (tk, ek), (tp, ep) = times["KernelCPD linear"], times["Pelt l2"]
        print(f"change points, {n} bins: KernelCPD linear {1000 * tk:.2f} ms, Pelt l2 "
              f"{1000 * tp:.1f} ms ({tp / tk:,.0f}x), same result: {ek == ep}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--long-factor", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        cfg = MixConfig(duration_s=30.0)
        t = time.perf_counter()
        acc, ref = write_mix_pair(tmp, cfg, "x1")
        gen_s = time.perf_counter() - t
        size = (os.path.getsize(acc) + os.path.getsize(ref)) / 1e6
        payload = (raw_bytes(acc) + raw_bytes(ref)) / 1e6
        print(f"30 s pair: {size:.1f} MB on disk (zstd), {payload:.1f} MB of serialized "
              f"messages; generated in {gen_s:.1f} s")

        base, full = [], []
        for _ in range(args.repeat):
            t = time.perf_counter()
            n = read_and_decode(acc) + read_and_decode(ref)
            base.append(time.perf_counter() - t)
            t = time.perf_counter()
            r = diff(acc, ref)
            full.append(time.perf_counter() - t)
        b, d = min(base), min(full)
        print(f"read+decode both (mcap-protobuf-support): {b:.2f} s  ({n / b:,.0f} msg/s)")
        print(f"rocas diff:                             {d:.2f} s  ({n / d:,.0f} msg/s, "
              f"{payload / d:.1f} MB/s)  -> {r.deviating_module}")
        print(f"ratio diff / read+decode: {d / b:.2f}x  (target <= 3x)")

        s1, m1, dev1 = peak(acc, ref)
        print(f"peak RSS  1x ({cfg.duration_s:.0f} s): {m1:.0f} MB  (diff {s1:.1f} s, {dev1})")
        long_cfg = MixConfig(duration_s=cfg.duration_s * args.long_factor,
                             deviate_at_s=cfg.duration_s * args.long_factor - 10)
        acc10, ref10 = write_mix_pair(tmp, long_cfg, "x10")
        s10, m10, dev10 = peak(acc10, ref10)
        print(f"peak RSS {args.long_factor}x ({long_cfg.duration_s:.0f} s): {m10:.0f} MB  "
              f"(diff {s10:.1f} s, {dev10}); ratio {m10 / m1:.2f}")
    pelt_speedup(args.repeat)


if __name__ == "__main__":
    main()
