"""Benchmark of the Rerun output (prints figures; not a test).

A 30-second accident of the built-in stack (roundabout_red_truck extended to 30 s) and its
reference (the truck repainted white) are simulated; then:

- time to read each recording for the scene (load_execution) and to log it;
- time and size of the full analysis .rrd (three executions, diff, two searches, verdict);
- the same against the time of the analysis work it visualises here (two simulations + diff),
  which is a lower bound of `rocas analyze` (its searches run hundreds of simulations); target:
  the .rrd adds under 10 % to the analysis.

Usage: python tests/benchmarks/bench_viz.py
"""

from __future__ import annotations

import dataclasses
import tempfile
import time
from pathlib import Path

import numpy as np

from rocas.analysis.diff import diff
from rocas.rollout import simulate
from rocas.scenarios.loader import load_example
from rocas.search.ga import GenerationStats
from rocas.viz.analysis import write_analysis_rrd
from rocas.viz.execution import load_execution
from rocas.viz.scene import log_scene
from rocas.viz.signals import log_signals
from rocas.viz.stream import rrd_recording


def main() -> None:
    import rerun  # noqa: F401  (import once, outside the timings)

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        scn = dataclasses.replace(load_example("roundabout_red_truck"), duration_s=30.0)
        t = time.perf_counter()
        simulate(scn, output=d / "accident.mcap")
        white = tuple(dataclasses.replace(a, color="white") if a.id == "red_truck" else a for a in scn.actors)
        simulate(dataclasses.replace(scn, actors=white), output=d / "reference.mcap")
        t_sim = time.perf_counter() - t
        t = time.perf_counter()
        result = diff(d / "accident.mcap", d / "reference.mcap")
        t_diff = time.perf_counter() - t

        t = time.perf_counter()
        ex = load_execution(d / "accident.mcap")
        t_load = time.perf_counter() - t
        t = time.perf_counter()
        with rrd_recording(d / "scene.rrd") as rec:
            log_scene(rec, ex, "executions/accident")
            log_signals(rec, ex, "executions/accident")
        t_log = time.perf_counter() - t

        rng = np.random.default_rng(0)
        gens = [
            GenerationStats(g, 24 * (g + 1), g, 1.0 - 0.2 * g, rng.random((24, 3)), rng.random(24) - 0.1 * g)
            for g in range(10)
        ]
        t = time.perf_counter()
        write_analysis_rrd(
            d / "analysis.rrd",
            accident=d / "accident.mcap",
            reference=d / "reference.mcap",
            fixed=d / "reference.mcap",
            diff_result=result,
            searches={"physical": gens, "cyber": gens},
            verdict_md="# Verdict\n",
            highlight="red_truck",
        )
        t_rrd = time.perf_counter() - t
        mcap_mb = (d / "accident.mcap").stat().st_size / 1e6
        print(
            f"30 s accident: {ex.duration_s:.1f} s, {len(ex.ego_t)} poses, {len(ex.obstacles)} obstacle "
            f"frames, accident.mcap {mcap_mb:.2f} MB"
        )
        print(
            f"scene of one execution: read {t_load:.3f} s, log {t_log:.3f} s, "
            f"{(d / 'scene.rrd').stat().st_size / 1e6:.2f} MB"
        )
        print(
            f"analysis .rrd (3 executions, diff, 2 searches, verdict): {t_rrd:.3f} s, "
            f"{(d / 'analysis.rrd').stat().st_size / 1e6:.2f} MB"
        )
        base = t_sim + t_diff
        print(
            f"analysis work shown (2 simulations {t_sim:.2f} s + diff {t_diff:.2f} s = {base:.2f} s): "
            f".rrd adds {100 * t_rrd / base:.1f} % (a full rocas analyze runs hundreds of simulations)"
        )


if __name__ == "__main__":
    main()
