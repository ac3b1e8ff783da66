"""`rocas diff` on two ~1 GB recordings: wall time, throughput and peak memory.

Writes an accident/reference pair of the acme stack (tests/foreign_stack.py) to a temporary
directory, streaming to disk, with a realistic lidar channel (16,384 ranges per scan at
20 Hz, centimetre range noise independent in the two runs) that makes up most of the bytes, until each
file reaches the target size. Then, each in its own child process:

1. ``rocas diff ACCIDENT REFERENCE --json``;
2. a baseline that merely reads and decodes both files with ``mcap_protobuf``.

Peak RSS is the child's own ``ru_maxrss``. The files are deleted at the end.

Usage::

    python tests/benchmarks/bench_large.py [--gb 1.0] [--dir /tmp]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from mcap.writer import CompressionType, Writer

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

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


_CHILD_DIFF = """
import io, json, resource, sys
from rocas.cli.console import Env
from rocas.cli.main import main
out, err = io.StringIO(), io.StringIO()
code = main(["diff", sys.argv[1], sys.argv[2], "--json"], env=Env(stdout=out, stderr=err))
res = json.loads(out.getvalue()) if code == 0 else {}
print(json.dumps({"code": int(code), "stderr": err.getvalue()[-2000:],
                  "deviating_module": res.get("deviating_module"),
                  "messages_read": res.get("messages_read"),
                  "maxrss_kb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}))
"""

_CHILD_BASELINE = """
import json, resource, sys
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
n = 0
for path in sys.argv[1:]:
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        topics = [c.topic for c in reader.get_summary().channels.values()
                  if c.message_encoding == "protobuf"]
        for _schema, _channel, _message, _decoded in reader.iter_decoded_messages(topics=topics):
            n += 1
print(json.dumps({"code": 0, "decoded": n,
                  "maxrss_kb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}))
"""


def run_child(code: str, *args: str) -> tuple[dict, float]:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"child failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1]), wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gb", type=float, default=1.0, help="size of each recording [GB]")
    ap.add_argument("--dir", default=None, help="where to write the temporary recordings")
    args = ap.parse_args()
    target = int(args.gb * 1e9)
    with tempfile.TemporaryDirectory(prefix="rocas-bench-large-", dir=args.dir) as tmp:
        acc, ref = Path(tmp) / "accident.mcap", Path(tmp) / "reference.mcap"
        t0 = time.perf_counter()
        # the reference decides the duration; the accident then covers the same time
        duration = write_big_run(ref, accident=False, target_bytes=target, duration_s=None)
        write_big_run(acc, accident=True, target_bytes=None, duration_s=duration)
        gen_s = time.perf_counter() - t0
        sizes = [acc.stat().st_size, ref.stat().st_size]
        total_mb = sum(sizes) / 1e6
        print(f"recordings: accident {sizes[0] / 1e6:.0f} MB, reference {sizes[1] / 1e6:.0f} MB, "
              f"{duration:.0f} s of driving each, written in {gen_s:.0f} s")
        res, wall = run_child(_CHILD_DIFF, str(acc), str(ref))
        if res["code"] != 0:
            print(f"rocas diff failed with exit {res['code']}: {res['stderr']}")
        print(f"rocas diff: exit {res['code']}, {wall:.1f} s wall, {total_mb / wall:.1f} MB/s, "
              f"peak RSS {res['maxrss_kb'] / 1024:.0f} MB, deviating module "
              f"{res['deviating_module']}, messages read {res['messages_read']}")
        base, bwall = run_child(_CHILD_BASELINE, str(acc), str(ref))
        print(f"baseline (mcap_protobuf read + decode, both files): {bwall:.1f} s wall, "
              f"{total_mb / bwall:.1f} MB/s, peak RSS {base['maxrss_kb'] / 1024:.0f} MB, "
              f"{base['decoded']} protobuf messages")
        ok = res["code"] == 0 and res["maxrss_kb"] / 1024 < 500
        print(f"peak memory under 500 MB: {'yes' if ok else 'NO'}")


if __name__ == "__main__":
    main()
