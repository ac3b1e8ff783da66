"""Accidents analysed per hour by ``rocas triage`` with the local executor and with Ray, on one
small campaign, and whether both give the same campaign.json groups.

    nice python tests/benchmarks/bench_triage.py CAMPAIGN_INPUTS... [--workers 2] [--budget 240]
        [--executor local --executor ray]

e.g. on the accidents ``rocas catalog generate --family mixed --instances 2 -o DIR`` writes.
Each executor analyses the campaign from scratch in its own temporary directory (``--repeat``
times; min and median printed); the figures of a shared machine move with its load.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from rocas.campaign import collect_inputs, groups_signature, triage
from rocas.pipeline import AnalyzeConfig


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("inputs", nargs="+")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--budget", type=int, default=240)
    ap.add_argument("--validation", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--executor", action="append", choices=("local", "ray"), default=[],
                    help="the executors to measure (repeatable; default local and ray)")
    args = ap.parse_args()
    inputs = collect_inputs(args.inputs)
    rates: dict[str, list[float]] = {}
    groups = {}
    for name in args.executor or ["local", "ray"]:
        cfg = AnalyzeConfig(budget=args.budget, workers=args.workers, executor=name,
                            validation_variants=args.validation)
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory(prefix=f"bench-triage-{name}-") as d:
                start = time.perf_counter()
                campaign = triage(inputs, Path(d) / "c", cfg)
                hours = (time.perf_counter() - start) / 3600
            rates.setdefault(name, []).append(len(inputs) / hours)
            groups[name] = groups_signature(campaign)
            sc = campaign.get("scores")
            if sc:
                print(f"{name:>5}: completeness {100 * sc['completeness']:.1f} % (worst type "
                      f"{100 * sc['worst_completeness']:.0f} %), purity {100 * sc['purity']:.1f} % "
                      f"(worst group {100 * sc['worst_purity']:.0f} %), {len(campaign['groups'])} groups",
                      flush=True)
                if "groups_documented" in sc:
                    print(f"{name:>5}: root cause the documented one (module, parameter, direction): "
                          f"{sc['groups_documented']} of {sc['groups_with_truth']} groups, "
                          f"{sc['accidents_documented']} of {sc['accidents_with_truth']} accidents "
                          f"({100 * sc['documented_share']:.1f} %)", flush=True)
        r = rates[name]
        print(f"{name:>5}: {len(inputs)} accidents, min {min(r):.0f} / median "
              f"{statistics.median(r):.0f} accidents per hour ({args.workers} workers)", flush=True)
    if len(rates) == 2:
        ratio = statistics.median(rates["ray"]) / statistics.median(rates["local"])
        print(f"ray / local: {ratio:.2f}")
        print(f"identical campaign.json groups: {groups['local'] == groups['ray']}")


if __name__ == "__main__":
    main()
