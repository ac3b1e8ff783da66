"""How often the highway stack's module substitution names the module at fault.

Module substitution (``rocas.stacks.highway.substitution.second_opinion``) reruns an accident
with ideal control: "control" when that avoids it, "planning" (by elimination) when it
persists. Measured on the six catalog entries (their ground-truth module; h06 has none) and
on injected accidents from ``bench_cfrca.injected_accidents`` (the injected parameter's
module), two simulations per accident. ``--sweep N`` adds a wider probe: on N drawn scenes
that are safe with the defaults, every driver parameter at each end of its range, kept when
it makes an accident.

    python tests/benchmarks/bench_substitution.py --injected 30 [--sweep 40]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))
sys.path.insert(0, str(HERE))

import numpy as np  # noqa: E402
from bench_cfrca import injected_accidents  # noqa: E402

from rocas.stacks.highway.accidents import entries  # noqa: E402
from rocas.stacks.highway.draw import draw  # noqa: E402
from rocas.stacks.highway.params import parameters  # noqa: E402
from rocas.stacks.highway.substitution import SubstitutionOpinion, second_opinion  # noqa: E402
from rocas.stacks.highway.world import simulate  # noqa: E402

#: (parameter, its module, substitution's module, the module when any accident under ideal
#: control counts as the accident persisting)
Row = tuple[str, str, str | None, str]


def _raw(o: SubstitutionOpinion) -> str:
    return "planning" if o.ideal_control.accident else "control"


def _line(label: str, truth: str, o: SubstitutionOpinion, took: float) -> str:
    b, i = o.baseline, o.ideal_control
    ideal = (f"{i.what()} at {i.accident_t_s:.2f} s" if i.accident
             else f"none (margin {i.min_margin_m:.2f} m)")
    return (f"{label:44} truth {truth or '-':9} -> {o.module or '-':9} "
            f"(as is: {b.what()} at {b.accident_t_s:.2f} s; ideal control: {ideal}) {took:.2f} s")


def _catalog() -> tuple[int, int]:
    hits = judged = 0
    print("catalog entries")
    for e in entries():
        t0 = time.perf_counter()
        o = second_opinion(e.scene, e.params, e.seed)
        print("  " + _line(e.key, e.module, o, time.perf_counter() - t0), flush=True)
        if e.module:
            judged += 1
            hits += o.module == e.module
    return hits, judged


def _injected(count: int, seed: int) -> list[Row]:
    rows = []
    print(f"\ninjected accidents (bench_cfrca.injected_accidents({seed}))")
    for item in injected_accidents(seed):
        if len(rows) >= count:
            break
        scene, name, value = item[0], item[-2], item[-1]
        tuned = dict(item[1]) if len(item) == 4 else {}  # (scene, tuned, name, value)
        t0 = time.perf_counter()
        o = second_opinion(scene, {**tuned, name: value}, 0)
        module = name.split(".")[0]
        rows.append((name, module, o.module, _raw(o)))
        print("  " + _line(f"{scene.name} {name}={value:.3g}", module, o,
                           time.perf_counter() - t0), flush=True)
    return rows


def _sweep(scenes: int, seed: int) -> list[Row]:
    rows: list[Row] = []
    print(f"\nsweep: every parameter at its range ends on {scenes} drawn scenes")
    for k in range(scenes):
        scene, _, _ = draw(np.random.default_rng([seed, 1000 + k]), f"sweep-{seed}-{k}")
        if simulate(scene, {}, 0).accident:
            continue
        for p in parameters():
            for value in sorted({p.low, p.high} - {p.default}):
                o = second_opinion(scene, {p.full_name: value}, 0)
                if o.accident:
                    rows.append((f"{p.full_name}={value:.3g}", p.module, o.module, _raw(o)))
                    if o.module != p.module:
                        print(f"  {scene.name} {rows[-1][0]}: named {o.module}", flush=True)
    return rows


def _summary(title: str, rows: list[Row]) -> None:
    n = len(rows)
    right = sum(r[1] == r[2] for r in rows)
    print(f"{title}: substitution's module is the injected parameter's in {right}/{n} "
          f"({100 * right / max(n, 1):.1f} %); counting any accident under ideal control as "
          f"the accident persisting: {sum(r[1] == r[3] for r in rows)}/{n}")
    for module in sorted({r[1] for r in rows}):
        mine = [r for r in rows if r[1] == module]
        named = Counter(str(r[2]) for r in mine)
        print(f"  injected {module:9} {sum(r[2] == module for r in mine)}/{len(mine)}  "
              f"named: {dict(sorted(named.items()))}")
    for name in sorted({r[0] for r in rows}):
        mine = [r for r in rows if r[0] == name]
        print(f"  {name:32} {sum(r[1] == r[2] for r in mine)}/{len(mine)}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--injected", type=int, default=30)
    ap.add_argument("--sweep", type=int, default=0, help="scenes of the range-end sweep")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    start = time.perf_counter()
    hits, judged = _catalog()
    rows = _injected(args.injected, args.seed)
    swept = _sweep(args.sweep, args.seed) if args.sweep else []
    print(f"\ncatalog: substitution's module is the ground truth's in {hits}/{judged} entries "
          f"with a module (h06 has none)")
    _summary("injected", rows)
    if swept:
        _summary("sweep", [(r[0].split("=")[0], *r[1:]) for r in swept])
    print(f"{time.perf_counter() - start:.0f} s in all")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
