"""`rocas diff` on two ~1 GB recordings: wall time, throughput and peak memory.

Writes an accident/reference pair of the acme stack (tests/foreign_stack.py) to a temporary
directory, streaming to disk, with a realistic lidar channel (16,384 ranges per scan at
20 Hz, centimetre range noise independent in the two runs) that makes up most of the bytes, until each
file reaches the target size. Then, as whole processes, alternately ``--repeat`` times
(bench_diff.compare_whole_processes):

1. ``rocas diff ACCIDENT REFERENCE --json``;
2. a baseline that merely reads and decodes both files with mcap + mcap-protobuf-support;

and prints min and median of wall and CPU time, the ratios (target: diff <= 3x) and each
child's peak RSS (its own ``ru_maxrss`` from ``wait4``). The files are deleted at the end
unless ``--keep DIR`` names a directory to write them to (or reuse them from).

Usage::

    python tests/benchmarks/bench_large.py [--gb 1.0] [--dir /tmp] [--repeat 2] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from mcap.writer import CompressionType, Writer

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from bench_diff import bytecode_cached_env, compare_whole_processes  # noqa: E402
from foreign_stack import (  # noqa: E402
    CONTROL,
    RATES,
    TOPOLOGY,
    TYPES,
    _message,
    _onset,
    build_classes,
)

from rocas.recording.writer import register_protobuf_channel  # noqa: E402

RANGES_PER_SCAN = 16_384


def write_big_run(path: Path, *, accident: bool, target_bytes: int | None, duration_s: float | None,
                  deviating: str = "forecaster") -> float:
    """Write one run until it holds ``target_bytes`` (or lasts ``duration_s``); returns its duration."""
    classes = build_classes()
    rng = np.random.default_rng(7 + (1000 if accident else 0))
    base = np.round(np.linspace(1.0, 80.0, RANGES_PER_SCAN), 2)
    readers: dict[str, list[str]] = {}
    for m, (reads, _) in TOPOLOGY.items():
        for t in reads:
            readers.setdefault(t, []).append(m)
    onset_s = None
    start_sec = 1_700_000_000 if accident else 1_700_086_400
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD, chunk_size=1 << 20)
        w.start(profile="", library="acme-logger")
        ids: dict[str, int] = {}
        schema_ids: dict[str, int] = {}
        for module, (_, writes) in TOPOLOGY.items():
            for topic in writes:
                kw = dict(writers=[module], readers=readers.get(topic, []),
                          role="control" if topic == CONTROL else None)
                if topic in TYPES:
                    ids[topic] = register_protobuf_channel(w, topic, classes[TYPES[topic]],
                                                           schema_ids=schema_ids, **kw)
                else:
                    sid = w.register_schema("acme.Status", "jsonschema", b"{}")
                    ids[topic] = w.register_channel(topic, "json", sid, {"rocas.writers": module})
        step = 1.0 / 100  # the scheduler's tick [s]; every rate divides 100 Hz
        tick = 0
        seq = dict.fromkeys(RATES, 0)
        while True:
            t = 0.01 + tick * step
            if duration_s is not None and t >= duration_s:
                break
            if target_bytes is not None and f.tell() >= target_bytes:
                break
            if onset_s is None:
                # deviation starts at 60% of the run: estimated from the bytes per second so far
                onset_s = (duration_s or 1e9) * 0.6
            onset = _onset(deviating, onset_s) if accident else {}
            abs_t = start_sec + t
            stamp = {"sec": int(abs_t), "nsec": int((abs_t % 1) * 1e9)}
            for topic, hz in RATES.items():
                if tick % (100 // hz):
                    continue
                i = seq[topic]
                if topic == "/sensing/cloud":
                    msg = classes["PointCloud"]()
                    msg.stamp.sec, msg.stamp.nsec = stamp["sec"], stamp["nsec"]
                    # range noise of a few cm on every return, independent in the two runs
                    ranges = base + np.round(rng.normal(0, 0.02, RANGES_PER_SCAN), 3)
                    msg.ranges.extend(ranges.astype(np.float32).tolist())
                    msg.ring = i % 16
                else:
                    writer_module = next(m for m, (_, ws) in TOPOLOGY.items() if topic in ws)
                    dev = writer_module in onset and t >= onset[writer_module]
                    msg = _message(classes, topic, i, t, stamp, dev, rng, distractor=False)
                data = json.dumps(msg).encode() if isinstance(msg, dict) else msg.SerializeToString()
                w.add_message(ids[topic], log_time=int(abs_t * 1e9), publish_time=int(abs_t * 1e9),
                              data=data, sequence=i)
                seq[topic] += 1
            tick += 1
        w.finish()
    return tick * step


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gb", type=float, default=1.0, help="size of each recording [GB]")
    ap.add_argument("--dir", default=None, help="where to write the temporary recordings")
    ap.add_argument("--keep", default=None, metavar="DIR",
                    help="write the pair to DIR and keep it (reused when it is there)")
    ap.add_argument("--repeat", type=int, default=2, help="runs of each process (default 2)")
    ap.add_argument("--cold", action="store_true",
                    help="run the children in this environment (bench_diff.py --cold)")
    args = ap.parse_args()
    target = int(args.gb * 1e9)
    with tempfile.TemporaryDirectory(prefix="rocas-bench-large-", dir=args.dir) as tmp:
        where = Path(args.keep) if args.keep else Path(tmp)
        where.mkdir(parents=True, exist_ok=True)
        acc, ref = where / "accident.mcap", where / "reference.mcap"
        if not (acc.exists() and ref.exists()):
            t0 = time.perf_counter()
            # the reference decides the duration; the accident then covers the same time
            duration = write_big_run(ref, accident=False, target_bytes=target, duration_s=None)
            write_big_run(acc, accident=True, target_bytes=None, duration_s=duration)
            print(f"written in {time.perf_counter() - t0:.0f} s")
        sizes = [acc.stat().st_size, ref.stat().st_size]
        print(f"recordings: accident {sizes[0] / 1e6:.0f} MB, reference {sizes[1] / 1e6:.0f} MB")
        with tempfile.TemporaryDirectory() as pycache:  # bytecode as installed (bench_diff)
            out = compare_whole_processes(str(acc), str(ref), args.repeat,
                                          "lidar-heavy pair (bench_large)", 3.0,
                                          None if args.cold else bytecode_cached_env(pycache))
        res = json.loads(out)
        print(f"  deviating module {res['deviating_module']}, messages read "
              f"{res['messages_read']}")


if __name__ == "__main__":
    main()
