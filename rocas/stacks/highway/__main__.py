"""``python -m rocas.stacks.highway``: the highway stack's catalog, recordings and analyses.

    python -m rocas.stacks.highway list
    python -m rocas.stacks.highway record h01 out.mcap [--fixed] [--seed N]
    python -m rocas.stacks.highway analyze h01 [--seed N] [--workers 2] [--executor local|ray]

``rocas catalog list|record --stack highway`` and ``rocas bench --stack highway`` reach the same
catalog and analyses through the stack's declared capabilities (:mod:`.stack`).
"""

from __future__ import annotations

import argparse
import sys

from rocas.errors import RocasError


def _run(args: argparse.Namespace) -> int:
    from rocas.stacks.highway.accidents import entries, entry

    if args.command == "list":
        for e in entries():
            truth = f"{e.parameter} -> {e.fix:g}" if e.parameter else "no configuration fix"
            print(f"{e.key:34} {e.scene.env_id:14} {truth}")
        return 0
    e = entry(args.key)
    seed = e.seed if args.seed is None else args.seed
    if args.command == "record":
        from rocas.stacks.highway.record import record

        params = dict(e.params)
        if args.fixed and e.parameter:
            params[e.parameter] = e.fix  # type: ignore[assignment]
        from rocas.stacks.highway.stack import accident_text

        run = record(e.scene, args.out, params, seed)
        print(f"wrote {args.out}: {accident_text(run)}")
        return 0
    from rocas.search.executor import make_executor
    from rocas.stacks.highway.comutation import analyze

    executor = make_executor(args.executor, args.workers)
    try:
        result = analyze(e.scene, e.params, seed, executor=executor)
    finally:
        executor.close()
    print(result.summary())
    if e.parameter:
        hit = e.parameter in result.fix
        print(f"  ground truth {e.parameter} -> {e.fix:g}: {'found' if hit else 'missed'}")
    else:
        print(f"  ground truth: no configuration fix; "
              f"{'none found' if not result.fix else 'a fix was found'}")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m rocas.stacks.highway",
                                 description="the highway stack (highway-env)")
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("list", help="the accident catalog")
    rec = sub.add_parser("record", help="record a catalog entry to MCAP")
    rec.add_argument("key")
    rec.add_argument("out")
    rec.add_argument("--fixed", action="store_true", help="with the ground-truth fix")
    rec.add_argument("--seed", type=int)
    an = sub.add_parser("analyze", help="co-mutation on a catalog entry")
    an.add_argument("key")
    an.add_argument("--seed", type=int)
    an.add_argument("--workers", type=int, default=2)
    an.add_argument("--executor", default="local")
    args = ap.parse_args(argv)
    try:
        return _run(args)
    except RocasError as exc:
        print(f"rocas: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
