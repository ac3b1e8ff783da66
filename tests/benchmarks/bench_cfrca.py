"""The injected-misconfiguration benchmark of the highway stack, measured as CF-RCA is.

CF-RCA (IEEE RA-L 2026) reports the misconfigured parameter found in 98.3 % of 12,926
MetaDrive scenarios. Here: draw random highway-env scenes from three families
(``rocas.stacks.highway.draw``), set one driver parameter of the ego to a harmful value, keep
the runs that crash and that restoring the parameter repairs, run rocas's co-mutation on each
(``rocas.stacks.highway.comutation.analyze``) and count how often the fix it proposes moves
the injected parameter back the right way, how often the diff names the injected parameter's
module, and the time per accident.

    python tests/benchmarks/bench_cfrca.py --accidents 100 --minutes 30 --workers 2
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Mapping
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from rocas.search.executor import make_executor  # noqa: E402
from rocas.stacks.highway.comutation import analyze  # noqa: E402
from rocas.stacks.highway.draw import draw  # noqa: E402
from rocas.stacks.highway.params import parameters  # noqa: E402
from rocas.stacks.highway.world import simulate  # noqa: E402

CF_RCA = "CF-RCA (IEEE RA-L 2026): 98.3 % of 12,926 MetaDrive scenarios"


def departures(rng: np.random.Generator, share: float, injected: str) -> dict[str, float]:
    """A tuned configuration: each parameter but the injected one leaves its default with
    probability ``share``, by a factor between 0.75 and 1.33 (POLITENESS, whose default is 0:
    to between 0 and 0.5), within its range."""
    out = {}
    for p in parameters():
        if p.full_name == injected or rng.uniform() >= share:
            continue
        value = (float(rng.uniform(0.0, 0.5)) if p.default == 0
                 else p.default * float(np.exp(rng.uniform(np.log(0.75), np.log(4 / 3)))))
        out[p.full_name] = float(np.clip(value, p.low, p.high))
    return out


def injected_accidents(seed: int, share: float = 0.0):
    """Yield (scene, tuned configuration, parameter, harmful value) for runs that crash and
    that restoring the parameter to its default repairs, forever (scene k is drawn from the
    generator seeded with (seed, k), its configuration's departures, with probability
    ``share`` per parameter, from (seed, k, 1))."""
    k = 0
    while True:
        scene, name, value = draw(np.random.default_rng([seed, k]), f"bench-{seed}-{k}")
        tuned = departures(np.random.default_rng([seed, k, 1]), share, name) if share else {}
        k += 1
        if (simulate(scene, {**tuned, name: value}, 0).accident
                and not simulate(scene, tuned, 0).accident):
            yield scene, tuned, name, value


def restores(fix: Mapping[str, float], name: str, injected: float, default: float) -> bool:
    """``fix`` moves the injected parameter from its harmful value towards its default."""
    moved = fix.get(name)
    return moved is not None and np.sign(moved - injected) == np.sign(default - injected)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--accidents", type=int, default=100)
    ap.add_argument("--minutes", type=float, default=60.0, help="stop after this long")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--executor", default="local")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--departures", type=float, default=0.0, metavar="SHARE",
                    help="tune the configuration first: each other parameter leaves its "
                         "default with this probability (0: every other parameter at its "
                         "default, as CF-RCA's injections)")
    args = ap.parse_args(argv)
    defaults = {p.full_name: p.default for p in parameters()}
    executor = make_executor(args.executor, args.workers)
    start = time.perf_counter()
    rows = []
    try:
        for scene, tuned, name, value in injected_accidents(args.seed, args.departures):
            if len(rows) >= args.accidents or time.perf_counter() - start > args.minutes * 60:
                break
            t0 = time.perf_counter()
            a = analyze(scene, {**tuned, name: value}, 0, executor=executor)
            took = time.perf_counter() - t0
            hit = restores(a.fix, name, value, defaults[name])
            among = hit or any(restores(f, name, value, defaults[name]) for f in a.alternatives)
            module = name.split(".")[0]
            rows.append((name, hit, a.deviating_module == module, took, among,
                         a.module == module))
            print(f"{scene.name:14} {name:42} {value:7.3g} ({len(tuned)} tuned) -> module {a.module} (diff "
                  f"{a.deviating_module}) "
                  f"fix {dict(a.fix)} {'HIT' if hit else 'among others' if among else 'MISS'} {took:.1f} s "
                  f"({sum(a.simulations.values())} sims)", flush=True)
    finally:
        executor.close()
    n = len(rows)
    if not n:
        print("no accident analysed in the time given")
        return 1
    times = [r[3] for r in rows]
    print(f"\naccidents analysed: {n} (aimed at {args.accidents}; "
          f"{time.perf_counter() - start:.0f} s in all)")
    print(f"injected parameter moved the right way: {sum(r[1] for r in rows)}/{n} "
          f"({100 * sum(r[1] for r in rows) / n:.1f} %)   beside {CF_RCA}")
    print(f"... or among the other shrunk fixes shown: {sum(r[4] for r in rows)}/{n} "
          f"({100 * sum(r[4] for r in rows) / n:.1f} %)")
    print(f"diff named the injected parameter's module: {sum(r[2] for r in rows)}/{n} "
          f"({100 * sum(r[2] for r in rows) / n:.1f} %)")
    print(f"the answer's module (the diff's, revised to the fix's): {sum(r[5] for r in rows)}/{n} "
          f"({100 * sum(r[5] for r in rows) / n:.1f} %)")
    print(f"time per accident: min {min(times):.1f} s, median {statistics.median(times):.1f} s")
    for name in sorted({r[0] for r in rows}):
        mine = [r for r in rows if r[0] == name]
        print(f"  {name:42} {sum(r[1] for r in mine)}/{len(mine)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
