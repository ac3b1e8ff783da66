"""Benchmark of reconstruction error against ground truth (prints figures; not a test).

Each scenario file (catalog format) is simulated into a recording, rebuilt from that recording
alone (``rocas.replay.reconstruct``) and re-run closed loop. Per scenario it prints whether the
accident was reproduced, the ego's RMSE before the accident, and how far the replayed actors
drove from the original ones: position, speed and heading error, RMS and max, over the ticks
from each actor's first to its last sighting before the accident ("seen"), and the position
RMS over every tick before the accident ("all": includes the guessed motion before the first
sighting). Each replayed actor is compared with the original actor nearest it while seen.

    python tests/benchmarks/bench_replay_error.py [FILE.toml ...] [--set module.param=value]
        [--json OUT.json]

Without files: the 12 catalog entries and tests/scenarios/variants/layouts/*.toml.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from rocas.catalog.variants import load_variant
from rocas.replay import reconstruct, replay
from rocas.replay.frames import wrap
from rocas.rollout import simulate

ROOT = Path(__file__).resolve().parents[2]
DEFAULTS = (sorted((ROOT / "rocas/catalog").glob("a*.toml"))
            + sorted((ROOT / "tests/scenarios/variants/layouts").glob("*.toml")))


def actor_errors(rec: Any, rep: Any, truth: Any, until_s: float) -> dict[str, Any]:
    """Errors of the replayed actors against the original ones before ``until_s``.

    Args:
        rec: the Reconstruction; rep: its ReplayReport; truth: the original RunResult.
        until_s: the original accident's time (or the end of the run) [s].

    Returns:
        per-actor rows and pooled figures: position [m], speed [m/s], heading [deg].
    """
    dt = rec.scenario.dt_s
    end = min(int(np.floor(until_s / dt + 1e-9)), len(truth.times) - 1, len(rep.times) - 1)
    rows, pooled = [], {"pos": [], "speed": [], "heading": [], "all": []}
    if truth.actors.shape[1] == 0:
        return {"rows": rows, **{k: (0.0, 0.0) for k in pooled}}
    for j, tr in enumerate(rec.tracks):
        if tr.stationary:
            continue
        a = int(np.ceil(tr.times[0] / dt - 1e-9))
        b = min(int(np.floor(tr.times[-1] / dt + 1e-9)), end)
        if b <= a:
            continue
        ticks = np.arange(a, b + 1)
        got = rep.actors[ticks, j]                                      # (n, 4)
        d = np.hypot(*(got[:, None, :2] - truth.actors[ticks, :, :2]).transpose(2, 0, 1))
        k = int(np.argmin(d.mean(0)))
        want = truth.actors[ticks, k]
        pos = d[:, k]
        spd = np.abs(got[:, 3] - want[:, 3])
        moving = (want[:, 3] > 1.0) & (got[:, 3] > 1.0)
        hdg = np.degrees(np.abs(wrap(got[moving, 2] - want[moving, 2]))) if moving.any() \
            else np.zeros(1)
        every = np.hypot(*(rep.actors[:end + 1, j, :2] - truth.actors[:end + 1, k, :2]).T)
        rows.append({"actor": tr.name, "truth_index": k, "seen_s": [a * dt, b * dt],
                     "pos_rms": float(np.sqrt(np.mean(pos**2))), "pos_max": float(pos.max()),
                     "speed_rms": float(np.sqrt(np.mean(spd**2))), "speed_max": float(spd.max()),
                     "heading_rms": float(np.sqrt(np.mean(hdg**2))),
                     "heading_max": float(hdg.max()),
                     "all_rms": float(np.sqrt(np.mean(every**2)))})
        for key, v in (("pos", pos), ("speed", spd), ("heading", hdg), ("all", every)):
            pooled[key].append(v)
    out: dict[str, Any] = {"rows": rows}
    for key, vs in pooled.items():
        v = np.concatenate(vs) if vs else np.zeros(1)
        out[key] = (float(np.sqrt(np.mean(v**2))), float(v.max()))
    return out


def measure(path: Path, params: dict[str, float], folder: Path) -> dict[str, Any]:
    """Simulate, reconstruct and replay one scenario file; its figures."""
    entry = load_variant(path)
    rec_path = folder / f"{entry.key}.mcap"
    start = time.perf_counter()
    truth = simulate(entry.scenario, params or None, output=rec_path)
    rec = reconstruct(rec_path)
    rep = replay(rec, params or None)
    until = rep.compared_until_s
    err = actor_errors(rec, rep, truth, until)
    acc = rep.accident
    return {"name": entry.key, "reproduced": rep.reproduced, "only_emergency": rep.only_emergency,
            "original": rec.original.to_dict() if rec.original else None,
            "replay": acc.to_dict() if acc else None,
            "ego_rmse": rep.ego_rmse_m, "ego_max": rep.ego_max_error_m, "until_s": until,
            "actors": err, "wall_s": time.perf_counter() - start}


def _acc(a: dict[str, Any] | None) -> str:
    return "clean" if a is None else f"{a['kind'][:4]} {a['time_s']:.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", type=Path, default=list(DEFAULTS))
    ap.add_argument("--set", dest="sets", action="append", default=[],
                    help="module.param=value for the original run and the replay")
    ap.add_argument("--json", type=Path, help="write every figure (per actor too) here")
    ap.add_argument("--actors", action="store_true", help="print one line per actor too")
    args = ap.parse_args()
    params = {k: float(v) for k, v in (s.split("=", 1) for s in args.sets)}
    print("| scenario | original | replay | repro | ego RMSE [m] | pos RMS/max [m] | "
          "speed RMS/max [m/s] | heading RMS/max [deg] | pos all RMS [m] |")
    print("|---|---|---|---|---|---|---|---|---|")
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for f in args.files:
            r = measure(f, params, Path(tmp))
            results.append(r)
            e = r["actors"]
            print(f"| {r['name']} | {_acc(r['original'])} | {_acc(r['replay'])} | "
                  f"{'yes' if r['reproduced'] else '**no**'} | {r['ego_rmse']:.2f} | "
                  f"{e['pos'][0]:.2f}/{e['pos'][1]:.2f} | {e['speed'][0]:.2f}/{e['speed'][1]:.2f}"
                  f" | {e['heading'][0]:.1f}/{e['heading'][1]:.1f} | {e['all'][0]:.2f} |",
                  flush=True)
            if args.actors:
                for a in e["rows"]:
                    print(f"|  {a['actor']} (seen {a['seen_s'][0]:.1f}-{a['seen_s'][1]:.1f} s) "
                          f"| | | | | {a['pos_rms']:.2f}/{a['pos_max']:.2f} | "
                          f"{a['speed_rms']:.2f}/{a['speed_max']:.2f} | {a['heading_rms']:.1f}/"
                          f"{a['heading_max']:.1f} | {a['all_rms']:.2f} |")
    n = len(results)
    pos = [r["actors"]["pos"][0] for r in results]
    print(f"\ntotal: reproduced {sum(r['reproduced'] for r in results)} of {n}; "
          f"mean ego RMSE {np.mean([r['ego_rmse'] for r in results]):.3f} m "
          f"(max {max(r['ego_rmse'] for r in results):.2f}); "
          f"mean actor pos RMS {np.mean(pos):.3f} m; worst actor pos max "
          f"{max(r['actors']['pos'][1] for r in results):.2f} m; mean speed RMS "
          f"{np.mean([r['actors']['speed'][0] for r in results]):.3f} m/s; mean heading RMS "
          f"{np.mean([r['actors']['heading'][0] for r in results]):.2f} deg; "
          f"wall {sum(r['wall_s'] for r in results):.0f} s")
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
