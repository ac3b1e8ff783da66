"""The injected-misconfiguration benchmark of the highway stack, measured as CF-RCA is.

CF-RCA (IEEE RA-L 2026) reports the misconfigured parameter found in 98.3 % of 12,926
MetaDrive scenarios. Here: draw random highway-env scenes from three families
(``rocas.stacks.highway.draw``), set one driver parameter of the ego to a harmful value, keep
the runs that crash and that restoring the parameter repairs, run rocas's co-mutation on each
(``rocas.stacks.highway.comutation.analyze``) and count how often the fix it proposes moves
the injected parameter back the right way, how often the diff, module substitution and the
answer name the injected parameter's module, the confidence, and the time per accident.

rocas undoes each departure from the driver's declared defaults, which makes CF-RCA's protocol
(every other parameter at its default) easy; ``--departures 0.3`` tunes the rest of the
configuration first (each other parameter leaves its default with probability 0.3), so the
injected parameter is one departure among several.

    python tests/benchmarks/bench_cfrca.py --accidents 100 --minutes 30 --workers 2
    python tests/benchmarks/bench_cfrca.py --accidents 100 --workers 2 --departures 0.3
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass
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


@dataclass(frozen=True)
class Row:
    """One analysed accident: the injected parameter and what rocas answered."""

    name: str
    hit: bool  # the chosen fix moves the injected parameter back
    among: bool  # ... or one of the other shrunk fixes does
    diff_module: bool  # the diff against the chosen reference named the injected module
    module: bool  # the answer's module is the injected parameter's
    substitution: bool  # module substitution named the injected parameter's module
    confidence: str | None
    departures: int  # other parameters off their defaults (--departures)
    rivals: int  # ... of which undoing one alone also avoids the accident
    seconds: float


def rivals(scene, tuned: Mapping[str, float], name: str, value: float,
           defaults: Mapping[str, float]) -> int:
    """The other departures whose undoing alone also avoids the accident (what makes picking
    the injected one among them more than reading the configuration)."""
    return sum(not simulate(scene, {**tuned, name: value, k: defaults[k]}, 0).accident
               for k in tuned)


def analyse(args: argparse.Namespace, executor) -> list[Row]:
    defaults = {p.full_name: p.default for p in parameters()}
    start = time.perf_counter()
    rows: list[Row] = []
    for scene, tuned, name, value in injected_accidents(args.seed, args.departures):
        if len(rows) >= args.accidents or time.perf_counter() - start > args.minutes * 60:
            break
        t0 = time.perf_counter()
        a = analyze(scene, {**tuned, name: value}, 0, executor=executor)
        took = time.perf_counter() - t0
        hit = restores(a.fix, name, value, defaults[name])
        module = name.split(".")[0]
        row = Row(name, hit,
                  hit or any(restores(f, name, value, defaults[name]) for f in a.alternatives),
                  a.deviating_module == module, a.module == module,
                  a.substitution is not None and a.substitution.module == module,
                  a.confidence, len(tuned), rivals(scene, tuned, name, value, defaults), took)
        rows.append(row)
        print(f"{scene.name:14} {name:34} {value:7.3g} ({len(tuned)} tuned, {row.rivals} "
              f"rival) -> module {a.module} (diff {a.deviating_module}, substitution "
              f"{a.substitution.module if a.substitution else None}, {a.confidence}) fix "
              f"{dict(a.fix)} {'HIT' if hit else 'among others' if row.among else 'MISS'} "
              f"{took:.1f} s ({sum(a.simulations.values())} sims)", flush=True)
    return rows


def share(rows: list[Row], field: str) -> str:
    k = sum(bool(getattr(r, field)) for r in rows)
    return f"{k}/{len(rows)} ({100 * k / len(rows):.1f} %)"


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
    executor = make_executor(args.executor, args.workers)
    start = time.perf_counter()
    try:
        rows = analyse(args, executor)
    finally:
        executor.close()
    if not rows:
        print("no accident analysed in the time given")
        return 1
    times = [r.seconds for r in rows]
    print(f"\naccidents analysed: {len(rows)} (aimed at {args.accidents}; "
          f"{time.perf_counter() - start:.0f} s in all)")
    print(f"injected parameter moved the right way: {share(rows, 'hit')}   beside {CF_RCA}")
    print(f"... or among the other shrunk fixes shown: {share(rows, 'among')}")
    print(f"diff named the injected parameter's module: {share(rows, 'diff_module')}")
    print(f"module substitution named it: {share(rows, 'substitution')}")
    print(f"the answer's module (the diff's, revised to the fix's): {share(rows, 'module')}")
    levels = {lvl: sum(r.confidence == lvl for r in rows)
              for lvl in ("stable", "contested", "unstable", None)}
    print(f"confidence: {levels}")
    if args.departures:
        print(f"other departures per accident: mean "
              f"{statistics.mean(r.departures for r in rows):.1f}; accidents where undoing "
              f"another departure alone also avoids it: {share(rows, 'rivals')}")
    print(f"time per accident: min {min(times):.1f} s, median {statistics.median(times):.1f} s")
    for name in sorted({r.name for r in rows}):
        mine = [r for r in rows if r.name == name]
        print(f"  {name:42} {sum(r.hit for r in mine)}/{len(mine)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
