"""Benchmark: `rocas analyze` over structurally different catalog variants (prints figures; not a
test).

The variants are catalog-format files written by ``rocas catalog generate --family F`` (rotated,
mirrored, other speeds, actors and starts; each kept only when it still crashes as documented
and a documented fix repairs it, re-simulated). Each is recorded as ``rocas catalog record``
records an entry (the analysis replays the recording, as it does a shipped one), analysed, and
scored as ``rocas bench`` scores an entry: the verdict, the deviating module, and a documented
fix's parameter moved that fix's way.

Prints one line per variant, hits per entry, per family and overall, and for each miss what the
diff saw: the earliest change point of every channel, the walk, and the trigger the physical
search chose. ``DIR/results.json`` keeps everything.

Usage:
    python tests/benchmarks/bench_variants.py tests/scenarios/variants/mixed_s0 \\
        tests/scenarios/variants/rigid_s0 \\
        [--seed 0] [--validation 0] [--budget 240] [--workers 1] [--out runs/bench_variants]
        [--only A1 --only A9] [--from-scenario]

Regenerate the shipped sets with
``rocas catalog generate --family mixed --instances 2 --seed 0 -o tests/scenarios/variants/mixed_s0``
and ``rocas catalog generate --family rotate --family mirror --instances 1 --only A3 --only A4
--seed 0 -o tests/scenarios/variants/rigid_s0`` (no mixed draw of the narrow A3 and A4 races
passes the filter in 16 tries, so the second set covers them).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from rocas.catalog import accident_matches
from rocas.catalog.variants import load_variant
from rocas.pipeline.analyze import analyze
from rocas.pipeline.bench import _expected, _found, score
from rocas.pipeline.config import AnalyzeConfig
from rocas.rollout import simulate


def _family(name: str) -> str:
    """The family from a variant's name (``<entry key>__<family>_s<seed>_k<index>``)."""
    return name.split("__", 1)[1].split("_s", 1)[0] if "__" in name else "?"


def _diff_lines(run_dir: Path) -> list[str]:
    """What the diff saw: each channel's first change point, earliest first."""
    path = run_dir / "diff.json"
    if not path.exists():
        return ["no diff (no reference was found)"]
    d = json.loads(path.read_text())
    chans = sorted(((c["change_point_s"], c["topic"]) for c in d["channels"]
                    if c["change_point_s"] is not None), key=lambda x: x[0])
    lines = ["change points: " + ", ".join(f"{topic} {t:.2f} s" for t, topic in chans[:6])
             + (" ..." if len(chans) > 6 else "")]
    lines.append("walk: " + " -> ".join(str(step) for step in d.get("path", [])))
    return lines


def _trigger(report: dict[str, Any]) -> str:
    trig = report.get("triggering_entity") or {}
    if not trig:
        return "none"
    props = ", ".join(f"{p['name']} {p['original']} -> {p['mutated']}"
                      for p in trig.get("properties", []))
    return f"{trig.get('entity')} ({props})"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("directories", nargs="+", metavar="DIR",
                    help="folders of variant files (catalog format)")
    ap.add_argument("--seed", type=int, default=0, help="analysis seed (default 0)")
    ap.add_argument("--validation", type=int, default=0, help="validation variants (default 0)")
    ap.add_argument("--budget", type=int, default=AnalyzeConfig().budget)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--out", default="runs/bench_variants")
    ap.add_argument("--only", action="append", default=[], metavar="ID",
                    help="only variants of this entry (A1 ...; repeatable)")
    ap.add_argument("--from-scenario", action="store_true",
                    help="analyse the scenario (simulated) instead of its recording (replayed)")
    args = ap.parse_args(argv)

    cfg = AnalyzeConfig(seed=args.seed, budget=args.budget, workers=args.workers,
                        validation_variants=args.validation)
    out = Path(args.out) / f"seed{args.seed}"
    (out / "recordings").mkdir(parents=True, exist_ok=True)
    files = sorted(f for d in args.directories for f in Path(d).glob("*.toml"))
    only = {i.upper() for i in args.only}
    rows = []
    for f in files:
        v = load_variant(f)
        if only and v.truth.id.upper() not in only:
            continue
        source: Any = v.scenario
        if not args.from_scenario:
            rec = out / "recordings" / f"{v.key}.mcap"
            if not rec.exists():
                res = simulate(v.scenario, output=rec)
                if not accident_matches(v.truth, res.outcome):
                    print(f"{v.key}: the recording is not the documented accident "
                          f"({res.outcome.summary()}); skipped", file=sys.stderr)
                    continue
            source = rec
        run_dir = out / "runs" / v.key
        t0 = time.perf_counter()
        report = analyze(source, run_dir, cfg, resume=(run_dir / "state.json").exists()).to_json()
        wall = time.perf_counter() - t0
        exp, fnd = _expected(v.truth, replayed=not args.from_scenario), _found(report)
        marks = score(exp, fnd)
        row = {"name": v.key, "type": v.truth.id, "family": _family(v.key), "hit": marks["hit"],
               "marks": marks, "expected": exp, "found": fnd, "trigger": _trigger(report),
               "seconds": round(sum(report["timings_s"].values()), 2), "wall_s": round(wall, 1)}
        rows.append(row)
        changes = ", ".join(f"{c['parameter']} {c['original']:.3g} -> {c['mutated']:.3g}"
                            for c in fnd["changes"]) or "-"
        print(f"{'HIT ' if row['hit'] else 'MISS'} {v.truth.id:>3} {row['family']:<8} {v.key}: "
              f"{fnd['verdict']}, module {fnd['deviating_module']} ({exp['deviating_module']}), "
              f"{changes}; trigger {row['trigger']} [{row['seconds']:.0f} s]", flush=True)
        if not row["hit"]:
            for line in _diff_lines(run_dir):
                print(f"        {line}", flush=True)

    if not rows:
        print("no variants analysed", file=sys.stderr)
        return 1
    print(f"\nseed {args.seed}: {sum(r['hit'] for r in rows)} of {len(rows)} variants hit")
    for key, label in (("type", "entry"), ("family", "family")):
        groups: dict[str, list[bool]] = {}
        for r in rows:
            groups.setdefault(r[key], []).append(r["hit"])
        order = sorted(groups, key=lambda g: (int(g[1:]) if key == "type" else 0, g))
        print(f"per {label}: " + ", ".join(f"{g} {sum(h)}/{len(h)}" for g, h in
                                             ((g, groups[g]) for g in order)))
    entries_all = {r["type"] for r in rows}
    entries_hit = {t for t in entries_all if all(r["hit"] for r in rows if r["type"] == t)}
    print(f"entries with every variant hit: {len(entries_hit)} of {len(entries_all)}")
    secs = sorted(r["seconds"] for r in rows)
    print(f"analysis time: min {secs[0]:.1f} s, median {secs[len(secs) // 2]:.1f} s, "
          f"max {secs[-1]:.1f} s")
    (out / "results.json").write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
