"""Damaged recordings against diff, cmg, replay and analyze: refused, warned, or silent (issue 21).

Each input damages the accident recording of one pair with a structural mutation
(:mod:`fuzz.structural`: remove, duplicate or reorder whole chunks, truncate, flip bits, damage
the summary). Pairs: the twelve catalog recordings (recordings/a*.mcap) with their entries'
reference runs (simulated here), and the demo pair (recordings/demo/). Per command the table
counts the inputs refused (exit 3), answered with a warning the undamaged file does not give,
answered silently with the undamaged file's answer, and answered silently with a *changed*
answer -- the figure that must be 0.

replay and analyze run on the catalog inputs only (the demo recordings are scripted, with no
world to replay). analyze is measured by its input-dependent stage, the reconstruction: every
later phase is a deterministic function of the reconstructed scenario, so an unchanged
scenario is an unchanged analysis; its warnings are the reconstruction's ``warnings`` (the
reader's damage, and a ``rocas.ego`` start that misses the first recorded pose). The pipeline's
replay phase (rocas/pipeline/replay_phase.py) copies these warnings into ``replay.json``, and
the report shows them (JSON ``warnings``/``complete``, report.md, the terminal).

Usage (from the repository root; ``PYTHONPATH=OTHER_CHECKOUT`` measures another version of
rocas with the same inputs)::

    python tests/benchmarks/bench_damage.py [--inputs 3000] [--workers 2] [--first 0]
"""

from __future__ import annotations

import argparse
import collections
import multiprocessing as mp
import os
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE.parent))

_STATE: dict = {}


def _pairs(workdir: Path) -> list[tuple[Path, Path, bool]]:
    """(accident, reference, catalog?) for every pair; references simulated into ``workdir``."""
    from rocas.catalog import entries
    from rocas.rollout import simulate

    out = []
    for e in entries():
        ref = workdir / f"{e.key}_reference.mcap"
        if not ref.exists():
            simulate(e.reference_scenario, output=ref)
        out.append((ROOT / "recordings" / f"{e.key}.mcap", ref, True))
    demo = ROOT / "recordings" / "demo"
    out.append((demo / "a01_scripted_accident.mcap", demo / "a01_scripted_reference.mcap", False))
    return out


def _baselines(pairs) -> list[dict]:
    from fuzz.structural import reconstruction, replay_verdict, run_cmg, run_diff

    out = []
    for acc, ref, catalog in pairs:
        b = {"diff": run_diff(acc, ref), "cmg": run_cmg(acc)}
        if catalog:
            rec = reconstruction(acc)
            b["reconstruction"] = rec
            b["verdict"] = replay_verdict(rec.answer[1])
        out.append(b)
    return out


def _init(tmp: str) -> None:
    _STATE["input"] = Path(tmp) / f"input-{os.getpid()}.mcap"


def _run(number: int) -> tuple[int, str, str, dict[str, str]]:
    from fuzz.structural import (
        REFUSED,
        SILENT_CHANGED,
        SILENT_SAME,
        WARNED,
        Answer,
        case,
        classify,
        reconstruction,
        replay_verdict,
        run_cmg,
        run_diff,
    )

    pairs, seeds, bases = _STATE["pairs"], _STATE["seeds"], _STATE["bases"]
    which, kind, data, what = case(seeds, number)
    _, ref, catalog = pairs[which]
    base = bases[which]
    path = _STATE["input"]
    path.write_bytes(data)
    out = {}
    got = run_diff(path, ref)
    out["diff"] = classify(got, base["diff"], got.answer != base["diff"].answer)
    got = run_cmg(path)
    out["cmg"] = classify(got, base["cmg"], got.answer != base["cmg"].answer)
    if catalog:
        b = base["reconstruction"]
        got = reconstruction(path)
        same = not got.refused and got.answer[0] == b.answer[0]
        verdict_changed = False
        if not got.refused and not same:
            try:
                verdict_changed = replay_verdict(got.answer[1]) != base["verdict"]
            except Exception:  # noqa: BLE001 - a replay that fails is a refusal, not a verdict
                got = Answer(True, None, frozenset())
        out["replay"] = classify(got, b, verdict_changed)
        damage = frozenset(getattr(got.answer[1], "warnings", ())) if not got.refused else frozenset()
        got_a = Answer(got.refused, None, damage)
        base_a = Answer(False, None, frozenset(getattr(b.answer[1], "warnings", ())))
        out["analyze"] = classify(got_a, base_a, not got.refused and not same)
    worst = [c for c, o in out.items() if o == SILENT_CHANGED]
    assert {REFUSED, WARNED, SILENT_SAME, SILENT_CHANGED} >= set(out.values())
    return number, kind, what + (f" (silent change: {', '.join(worst)})" if worst else ""), out


def _table(table, by_kind, wall: float, workers: int) -> None:
    from fuzz.structural import COMMANDS, REFUSED, SILENT_CHANGED, SILENT_SAME, WARNED

    n = sum(by_kind.values())
    print(f"inputs: {n} ({', '.join(f'{k} {v}' for k, v in sorted(by_kind.items()))}); "
          f"{wall:.0f} s on {workers} workers")
    cols = (REFUSED, WARNED, SILENT_SAME, SILENT_CHANGED)
    print(f"| command | inputs | {' | '.join(cols)} |")
    print("|---|---:|" + "---:|" * len(cols))
    for c in COMMANDS:
        print(f"| {c} | {sum(table[c].values())} | "
              + " | ".join(str(table[c][o]) for o in cols) + " |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--inputs", type=int, default=3000)
    ap.add_argument("--first", type=int, default=0, help="first input number (seed)")
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--workdir", default=None, help="where reference runs are kept (reused)")
    ap.add_argument("--report-every", type=int, default=0,
                    help="also print the table after every N inputs (0: only at the end)")
    args = ap.parse_args()

    from fuzz.structural import COMMANDS, SILENT_CHANGED

    import rocas

    print(f"rocas from {Path(rocas.__file__).parent}")
    workdir = Path(args.workdir or tempfile.mkdtemp(prefix="rocas-damage-"))
    workdir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    pairs = _pairs(workdir)
    _STATE["pairs"] = pairs
    _STATE["seeds"] = [p[0].read_bytes() for p in pairs]
    _STATE["bases"] = _baselines(pairs)
    print(f"{len(pairs)} pairs, baselines in {time.perf_counter() - t0:.0f} s", flush=True)
    table = {c: collections.Counter() for c in COMMANDS}
    by_kind: collections.Counter[str] = collections.Counter()
    worst: list[str] = []
    t1 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="rocas-damage-in-") as tmp:
        ctx = mp.get_context("fork")  # the workers inherit the pairs and baselines
        with ctx.Pool(args.workers, initializer=_init, initargs=(tmp,)) as pool:
            numbers = range(args.first, args.first + args.inputs)
            for number, kind, what, out in pool.imap_unordered(_run, numbers, chunksize=4):
                by_kind[kind] += 1
                for c, o in out.items():
                    table[c][o] += 1
                if SILENT_CHANGED in out.values():
                    worst.append(f"  input {number} ({kind}): {what}")
                done = sum(by_kind.values())
                if args.report_every and done % args.report_every == 0 and done < args.inputs:
                    _table(table, by_kind, time.perf_counter() - t1, args.workers)
    _table(table, by_kind, time.perf_counter() - t1, args.workers)
    for line in sorted(worst)[:30]:
        print(line)


if __name__ == "__main__":
    main()
