"""The LAV-like stack as a separate program, the way an external simulator is driven:

    python -m rocas.stacks.lav.run --scenario S.json --config C.json --out run.mcap

``S.json`` is a scenario in rocas's format (``scenario_to_dict``); ``C.json`` is
``{"params": {"brake.brake_threshold": 0.5, ...}, "seed": 0}``. Exit 0 with the recording
written, 2 with one line on stderr when an input is bad.
"""

from __future__ import annotations

import argparse
import json
import sys

from rocas.errors import RocasError


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="lav-sim", description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--config", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    from rocas.scenarios.loader import scenario_from_dict
    from rocas.stacks.registry import get_stack
    from rocas.stacks.rollout import rollout

    try:
        with open(args.scenario, encoding="utf-8") as f:
            scenario = scenario_from_dict(json.load(f), source=args.scenario)
        with open(args.config, encoding="utf-8") as f:
            config = json.load(f)
        res = rollout(get_stack("lav"), scenario, config.get("params", {}),
                      config.get("seed"), output=args.out)
    except (OSError, ValueError, RocasError) as exc:
        print(f"lav-sim: error: {exc}", file=sys.stderr)
        return 2
    print(res.outcomes[0].summary())
    return 0


if __name__ == "__main__":
    sys.exit(main())
