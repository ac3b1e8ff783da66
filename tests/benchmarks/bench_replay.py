"""Benchmark of replay fidelity (prints figures; not a test).

Each shipped example is simulated with the defaults into a recording, then rebuilt from that
recording alone and re-run (``rocas.replay``): the original and replayed accidents, whether it
reproduced, the ego's RMSE / max error before the accident, and the replay's wall time
(reading, reconstruction and the re-run). These are the figures of docs/replay.md.

    python tests/benchmarks/bench_replay.py [NAME ...]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from rocas.replay import replay
from rocas.rollout import simulate
from rocas.scenarios import load_example

EXAMPLES = ("left_turn_oncoming", "foggy_crossing", "junction_straight", "roundabout_red_truck",
            "wet_truck_turn")


def _accident(a: dict | None) -> str:
    if a is None:
        return "clean"
    other = f" with {a['other']}" if a.get("other") else ""
    return f"{a['kind']}{other}, {a['time_s']:.2f} s"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", default=list(EXAMPLES))
    args = ap.parse_args()
    print("| example | original | replay | reproduced | ego RMSE / max [m] | wall [s] |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.names:
            path = Path(tmp) / f"{name}.mcap"
            simulate(load_example(name), output=path)
            r = replay(path).to_dict()
            print(f"| {name} | {_accident(r['original_accident'])} | {_accident(r['accident'])} "
                  f"| {'yes' if r['reproduced'] else '**no**'} | {r['ego_rmse_m']:.2f} / "
                  f"{r['ego_max_error_m']:.2f} | {r['wall_time_s']:.1f} |")


if __name__ == "__main__":
    main()
