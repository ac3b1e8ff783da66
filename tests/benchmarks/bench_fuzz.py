"""The fuzzing campaign: >= 10,000 mutated recordings through the reader and `rocas diff`.

Each input (seed = its number, so any failure is reproduced with ``fuzz.mutate.case``) is a
mutation of one of the seed recordings; a worker process feeds it to the reader (scan, decode,
attachments) and to ``rocas diff INPUT REFERENCE --json`` in-process. Per input a time limit
(SIGALRM in the worker, and a wall-clock guard in the parent for hangs in C code); the workers
run under an address-space limit so a runaway allocation fails instead of swapping.

Prints: inputs run, outcomes (ok / crash / hang / memory), the first failures with their seeds,
inputs per second and the workers' peak RSS.

Usage::

    python tests/benchmarks/bench_fuzz.py [--inputs 10000] [--workers 2] [--timeout 5]
"""

from __future__ import annotations

import argparse
import collections
import multiprocessing as mp
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

_STATE: dict = {}


def _init(seed_dir: str, limit_s: float, address_space_gb: float) -> None:
    from fuzz.mutate import load_seeds

    soft = int(address_space_gb * (1 << 30))
    resource.setrlimit(resource.RLIMIT_AS, (soft, resource.getrlimit(resource.RLIMIT_AS)[1]))
    paths = sorted(Path(seed_dir).glob("*.mcap"))
    _STATE["seeds"] = load_seeds(paths)
    _STATE["reference"] = Path(seed_dir) / "acme_lz4.mcap"
    _STATE["input"] = Path(tempfile.mkdtemp(prefix="rocas-fuzz-")) / "input.mcap"
    _STATE["limit_s"] = limit_s


def _run(seed: int) -> tuple[int, str, str, str]:
    from fuzz.mutate import Hang, case, run_one

    kind, data, what = case(_STATE["seeds"], seed)
    try:
        run_one(data, _STATE["input"], _STATE["reference"], limit_s=_STATE["limit_s"])
        outcome, detail = "ok", ""
    except Hang as exc:
        outcome, detail = "hang", str(exc)
    except MemoryError as exc:
        outcome, detail = "memory", repr(exc)
    except BaseException as exc:  # noqa: BLE001 - every other escape is a crash to report
        outcome, detail = "crash", f"{type(exc).__name__}: {str(exc)[:300]}"
    return seed, kind, outcome, f"{what} -> {detail}" if detail else what


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--inputs", type=int, default=10_000)
    ap.add_argument("--first", type=int, default=0, help="first input number (seed)")
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--timeout", type=float, default=5.0, help="per input and stage [s]")
    ap.add_argument("--address-space-gb", type=float, default=4.0)
    args = ap.parse_args()

    from fuzz.mutate import write_seeds

    with tempfile.TemporaryDirectory(prefix="rocas-fuzz-seeds-") as seed_dir:
        write_seeds(seed_dir)
        outcomes: collections.Counter[str] = collections.Counter()
        by_kind: collections.Counter[str] = collections.Counter()
        failures: list[tuple[int, str, str, str]] = []
        t0 = time.perf_counter()
        ctx = mp.get_context("fork")
        pool = ctx.Pool(args.workers, initializer=_init,
                        initargs=(seed_dir, args.timeout, args.address_space_gb),
                        maxtasksperchild=2000)
        seeds = range(args.first, args.first + args.inputs)
        pending = {s: pool.apply_async(_run, (s,)) for s in seeds}
        for s, res in pending.items():
            try:
                seed, kind, outcome, what = res.get(timeout=args.timeout * 2 + 60)
            except mp.TimeoutError:
                seed, kind, outcome, what = s, "?", "hang", "no answer from the worker (stuck in C?)"
            outcomes[outcome] += 1
            by_kind[kind] += 1
            if outcome != "ok":
                failures.append((seed, kind, outcome, what))
        pool.close()
        pool.join()
        wall = time.perf_counter() - t0

    n = sum(outcomes.values())
    peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"inputs: {n} (reader + rocas diff each), by kind: {dict(sorted(by_kind.items()))}")
    print(f"outcomes: ok {outcomes['ok']}, crashes {outcomes['crash']}, hangs {outcomes['hang']}, "
          f"memory {outcomes['memory']}")
    print(f"time: {wall:.0f} s ({n / wall:.0f} inputs/s on {args.workers} workers, "
          f"limit {args.timeout:g} s per input and stage)")
    print(f"peak RSS of a worker: {peak_mb:.0f} MB (address space limit "
          f"{args.address_space_gb:g} GiB)")
    for seed, kind, outcome, what in failures[:20]:
        print(f"  {outcome}: seed {seed} ({kind}) {what}")


if __name__ == "__main__":
    main()
