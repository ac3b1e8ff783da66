"""Any registered stack as a separate program, the way an external simulator is driven (the
command of a stack file, :mod:`rocas.stacks.external`):

    python -m rocas.rollout.command --stack lav --scenario S.json --config C.json --out run.mcap

``S.json`` is a scenario in rocas's format (``scenario_to_dict``); ``C.json`` is
``{"params": {"brake.brake_threshold": 0.5, ...}, "seed": 0}``. Exit 0 with the recording
written, 2 with one line on stderr when an input is bad.

    python -m rocas.rollout.command --stack lav --batch B.json --out rows.npz

is the batch mode an analysis uses (:mod:`rocas.stacks.external`): every run of ``B.json``
(variants of one scenario structure) in one batch, their trajectories and outcomes in the
``.npz``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

from rocas.errors import RocasError


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="rocas-stack-process", description=__doc__.splitlines()[0])
    ap.add_argument("--stack", required=True, help="the registered stack to run")
    ap.add_argument("--scenario")
    ap.add_argument("--config")
    ap.add_argument("--batch")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    if (args.batch is None) == (args.scenario is None or args.config is None):
        ap.error("give --scenario and --config, or --batch")
    from rocas.rollout import rollout
    from rocas.scenarios.loader import scenario_from_dict
    from rocas.stacks.registry import get_stack

    try:
        if args.batch is not None:
            return _batch(args.stack, args.batch, args.out)
        with open(args.scenario, encoding="utf-8") as f:
            scenario = scenario_from_dict(json.load(f), source=args.scenario,
                                          check_ranges=False)
        with open(args.config, encoding="utf-8") as f:
            config = json.load(f)
        res = rollout(get_stack(args.stack), scenario, config.get("params", {}),
                      config.get("seed"), output=args.out)
    except (OSError, ValueError, KeyError, RocasError) as exc:
        print(f"rocas-stack-process: error: {exc}", file=sys.stderr)
        return 2
    print(res.outcome.summary())
    return 0


def _batch(stack: str, batch: str, out: str) -> int:
    import numpy as np

    from rocas.rollout import rollout_batch
    from rocas.scenarios.loader import scenario_from_dict
    from rocas.sim.recorder import outcome_metadata
    from rocas.stacks.registry import get_stack

    with open(batch, encoding="utf-8") as f:
        runs = json.load(f)["runs"]
    res = rollout_batch(get_stack(stack),
                        [scenario_from_dict(r["scenario"], source=batch, check_ranges=False)
                         for r in runs],
                        [r.get("params", {}) for r in runs], [int(r["seed"]) for r in runs])
    part = out + ".part.npz"
    np.savez(part, times=res.times, ego=res.ego, actors=res.actors, min_gap=res.min_gap,
             actor_ids=np.array(res.actor_ids, dtype=str),
             outcomes=np.array(json.dumps([outcome_metadata(o) for o in res.outcomes])))
    os.replace(part, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
