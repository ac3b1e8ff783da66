"""``rocas catalog list|record|generate``: the accident catalog (types A1-A12).

- ``list [--json]``: id, title, responsible module, parameter(s), fix value, consequence.
- ``record DIR [--only A9 ...]``: simulate every entry with the ADS defaults and write its
  accident recording ``DIR/<key>.mcap`` (the files shipped in ``recordings/``).
- ``generate --instances K [-o DIR] [--seed S]``: K seeded variants per type that still
  crash and that a documented fix still repairs; reports per type how many were tried, crash
  and are repaired, and writes the kept variants as scenario TOML.
- ``generate --family F [--family G ...] --instances K [-o DIR] [--record]``: K variants per
  type and family (rotated, mirrored, other speeds, actors, starts, or all mixed; see
  rocas.catalog.variants), checked the same way, written as catalog-format files with their
  ground truth (and, with ``--record``, their accident recordings beside them).
- ``generate --family F --family G ... --per-type --instances K [--max-tries N]``: K variants
  per type in all: the families are tried in the order given (at most N draws each), each
  topping up what the ones before kept (the campaign of ``rocas triage``, docs/cli.md).

``--stack NAME`` works on another stack's catalog (``--stack lav``: L1-L6, recorded into
``recordings/lav/``); ``--family`` is the built-in catalog's only. A stack that drives in
another simulator's world brings its own catalog (``--stack highway``: h01-h06, highway-env's;
the capabilities ``catalog_entries`` and ``record_catalog``, rocas.stacks.base.CAPABILITIES):
``list`` and ``record`` take it, ``generate`` refuses it in one line.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from rocas._fs import check_parent_exists
from rocas.catalog.families import FAMILIES
from rocas.cli.console import Env, safe
from rocas.errors import UsageError
from rocas.scenarios.model import DEFAULT_STACK

HELP = "the accident catalog (A1-A12): list it, record its accidents, generate instances"


def add_arguments(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    stack = argparse.ArgumentParser(add_help=False)
    stack.add_argument("--stack", default=DEFAULT_STACK, metavar="NAME",
                       help="the stack whose catalog to use (default ads, the built-in ADS; "
                            "lav: the LAV-like stack's; highway: highway-env's, list and "
                            "record only)")
    ls = sub.add_parser("list", help="show the entries and their ground truth", parents=[stack])
    ls.add_argument("--json", action="store_true", help="print the ground truth as JSON")
    rec = sub.add_parser("record", help="write the accident recording of every entry",
                         parents=[stack])
    rec.add_argument("directory", metavar="DIR", help="output directory (e.g. recordings/)")
    rec.add_argument("--only", action="append", default=[], metavar="ID",
                     help="record only this entry (repeatable)")
    gen = sub.add_parser("generate", help="seeded variants of every type that still crash and "
                                            "that a documented fix still repairs",
                         parents=[stack])
    gen.add_argument("--instances", type=int, required=True, metavar="K",
                     help="variants per type")
    gen.add_argument("-o", "--output", metavar="DIR", default=None,
                     help="write the kept variants as scenario TOML files here")
    gen.add_argument("--seed", type=int, default=0, help="base seed (default 0)")
    gen.add_argument("--only", action="append", default=[], metavar="ID",
                     help="only this type (repeatable)")
    gen.add_argument("--family", action="append", default=[], metavar="F",
                     choices=[*FAMILIES, "all"],
                     help="structurally different variants of this family (repeatable; all "
                          "for every one): " + "; ".join(f"{k}: {v}" for k, v in FAMILIES.items()))
    gen.add_argument("--record", action="store_true",
                     help="with --family and -o: also write each kept variant's accident "
                          "recording (DIR/<name>.mcap)")
    gen.add_argument("--per-type", action="store_true",
                     help="with --family: K variants per type in all, not per family; the "
                          "families are tried in the order given, each topping up what the ones "
                          "before kept")
    gen.add_argument("--max-tries", type=int, default=None, metavar="N",
                     help="with --family: draws tried per type and family at most (default 8 "
                          "times the variants wanted)")
    gen.add_argument("--json", action="store_true", help="print the counts as JSON")


def _selected(only: list[str], stack: str = DEFAULT_STACK):  # noqa: ANN202
    from rocas.catalog import entries, entry

    return [entry(i, stack) for i in only] if only else list(entries(stack))


def _truth_json(e) -> dict:  # noqa: ANN001
    t = e.truth
    return {"id": t.id, "key": e.key, "title": t.title, "paper": t.paper,
            "consequence": t.consequence, "collision_with": t.collision_with,
            "situation": t.situation, "module": t.module, "trigger_entity": t.trigger_entity,
            "trigger_property": t.trigger_property, "reference": dict(t.reference),
            "parameters": list(t.parameters), "fix": dict(t.fix),
            "alternatives": [dict(a) for a in t.alternatives], "fixable": t.fixable,
            "no_fix_reason": t.no_fix_reason, "override": t.override,
            "diff_module": t.diff_module, "diff_change_s": t.diff_change_s,
            "duration_s": e.scenario.duration_s}


def _own_catalog(stack: str) -> Any | None:
    """The stack when it brings its own catalog (``catalog_entries`` and ``record_catalog``: a
    stack of another simulator's world) instead of a folder of :mod:`rocas.catalog`; else None.

    Raises:
        UsageError: the stack has no catalog of either kind.
    """
    from rocas.stacks.registry import get_stack

    s = get_stack(stack)
    if getattr(s, "catalog", None):
        return None
    if callable(getattr(s, "catalog_entries", None)):
        return s
    raise UsageError(f"stack {stack!r} has no accident catalog",
                     "catalogs exist for: " + ", ".join(_stacks_with_a_catalog()))


def _stacks_with_a_catalog() -> list[str]:
    """The registered stacks with a catalog of either kind (the built-in stack first); a stack
    that cannot be loaded here (its optional extra is missing) is left out."""
    from rocas.catalog import stacks_with_catalog
    from rocas.errors import RocasError
    from rocas.stacks.registry import get_stack, names

    own = []
    for n in names():
        try:
            if callable(getattr(get_stack(n), "catalog_entries", None)):
                own.append(n)
        except RocasError:
            continue
    return [*stacks_with_catalog(), *(n for n in own if n not in stacks_with_catalog())]


def _list(args: argparse.Namespace, env: Env) -> int:
    from rich.table import Table

    own = _own_catalog(args.stack)
    if own is not None:
        return _list_own(own, args, env)
    items = _selected([], args.stack)
    if args.json:
        print(json.dumps([_truth_json(e) for e in items], indent=2), file=env.stdout)
        return 0
    table = Table(title=f"rocas accident catalog of stack {safe(args.stack)}")
    for col in ("id", "title", "module", "parameter(s)", "fix", "consequence"):
        table.add_column(col)
    for e in items:
        t = e.truth
        # one line per parameter, in the order of the parameter column; an alternative's
        # value reads "or v"
        lines = []
        for name in t.parameters:
            alt = [a[name] for a in t.alternatives if name in a]
            lines.append(f"{t.fix[name]:g}" if name in t.fix
                         else f"or {alt[0]:g}" if alt else "")
        fix = "\n".join(lines) if t.fixable else "none exists"
        table.add_row(t.id, t.title, t.module, "\n".join(t.parameters), fix,
                      t.consequence + (f" ({t.collision_with})" if t.collision_with else ""))
    env.out().print(table)
    return 0


def _list_own(stack: Any, args: argparse.Namespace, env: Env) -> int:
    """``list`` of a stack's own catalog (its ``catalog_entries`` rows)."""
    from rich.table import Table

    rows = stack.catalog_entries()
    if args.json:
        print(json.dumps(rows, indent=2), file=env.stdout)
        return 0
    table = Table(title=f"rocas accident catalog of stack {safe(args.stack)}")
    for col in ("id", "title", "module", "parameter(s)", "fix", "world"):
        table.add_column(col)
    for r in rows:
        fix = "\n".join(f"{r['fix'][p]:g}" for p in r["parameters"]) if r["fixable"] \
            else "none exists"
        table.add_row(safe(r["id"]), safe(r["title"]), safe(r["module"] or "—"),
                      safe("\n".join(r["parameters"]) or "—"), fix, safe(r["world"]))
    env.out().print(table)
    return 0


def _record(args: argparse.Namespace, env: Env) -> int:
    from rocas.catalog import accident_matches
    from rocas.rollout import simulate

    own = _own_catalog(args.stack)
    out_dir = Path(args.directory)
    check_parent_exists(out_dir)
    out_dir.mkdir(exist_ok=True)
    if own is not None:
        return _record_own(own, args.only, out_dir, env)
    failed = []
    written: list[str] = []
    for e in _selected(args.only, args.stack):
        path = out_dir / f"{e.key}.mcap"
        try:
            res = simulate(e.scenario, output=path)
        except KeyboardInterrupt as exc:
            exc.kept = _kept(written, out_dir, "recording")  # type: ignore[attr-defined]
            raise
        written.append(path.name)
        ok = accident_matches(e.truth, res.outcome)
        if not ok:
            failed.append(e.id)
        print(f"{e.id}: {res.outcome.summary()} -> {path} ({res.messages} messages)"
              + ("" if ok else "  [NOT the documented accident]"), file=env.stdout)
    if failed:
        raise UsageError(f"entries not ending in their documented accident: {', '.join(failed)}")
    return 0


def _record_own(stack: Any, only: list[str], out_dir: Path, env: Env) -> int:
    """``record`` of a stack's own catalog (its ``record_catalog``), in its own world.

    Raises:
        UsageError: a recording does not end in the entry's documented accident.
    """
    failed = []
    written: list[str] = []
    try:
        for r in stack.record_catalog(only or None, out_dir):
            written.append(Path(r["path"]).name)
            if not r["documented"]:
                failed.append(r["id"])
            print(f"{r['id']}: {r['outcome']} -> {r['path']}"
                  + ("" if r["documented"] else "  [NOT the documented accident]"),
                  file=env.stdout)
    except KeyboardInterrupt as exc:
        exc.kept = _kept(written, out_dir, "recording")  # type: ignore[attr-defined]
        raise
    if failed:
        raise UsageError(f"entries not ending in their documented accident: {', '.join(failed)}")
    return 0


def _generate(args: argparse.Namespace, env: Env) -> int:
    from rocas.catalog import generate_instances, scenario_toml

    own = _own_catalog(args.stack)
    if own is not None:
        from rocas.catalog import stacks_with_catalog

        raise UsageError(f"stack {args.stack}'s catalog drives in "
                         f"{getattr(own, 'world', 'another simulator')}'s world, where rocas "
                         "cannot generate instances",
                         f"list and record take --stack {args.stack}; generate works for: "
                         + ", ".join(stacks_with_catalog()))
    if args.instances < 1:
        raise UsageError("--instances must be >= 1")
    if args.record and not (args.family and args.output):
        raise UsageError("--record needs --family and -o DIR (where the recordings go)")
    if args.max_tries is not None and (args.max_tries < 1 or not args.family):
        raise UsageError("--max-tries needs --family and a count >= 1")
    if args.per_type and not args.family:
        raise UsageError("--per-type needs --family (the families that make up each type's K)")
    if args.family:
        from rocas.stacks.registry import get_stack

        if not getattr(get_stack(args.stack), "variant_families", False):
            raise UsageError(f"stack {args.stack!r} does not declare variant families",
                             "use --instances alone, or a stack with variant_families")
        return _generate_variants(args, env)
    out_dir = Path(args.output) if args.output else None
    rows = []
    written: list[str] = []
    try:
        for e in _selected(args.only, args.stack):
            rep = generate_instances(e, args.instances, seed=args.seed)
            rows.append({"id": e.id, "key": e.key, "tried": rep.tried, "crashed": rep.crashed,
                         "fix_holds": rep.fix_holds, "kept": len(rep.instances)})
            if out_dir is not None:
                from rocas._fs import atomic_path

                for _, sc in rep.instances:
                    with atomic_path(out_dir / f"{sc.name}.toml") as tmp:
                        tmp.write_text(scenario_toml(sc), encoding="utf-8")
                    written.append(f"{sc.name}.toml")
            if not args.json:
                fixed = (f", the documented fix repairs {rep.fix_holds}" if e.truth.fixable else
                         " (no fix exists to check)")
                print(f"{e.id}: {rep.crashed}/{rep.tried} tried variants crash{fixed}; kept "
                      f"{len(rep.instances)}", file=env.stdout)
    except KeyboardInterrupt as exc:
        exc.kept = _kept(written, out_dir, "scenario file")  # type: ignore[attr-defined]
        raise
    if args.json:
        print(json.dumps(rows, indent=2), file=env.stdout)
    return 0


def _generate_variants(args: argparse.Namespace, env: Env) -> int:
    from rocas._fs import atomic_path
    from rocas.catalog.variants import generate_variants, variant_toml

    families = list(FAMILIES) if "all" in args.family else list(dict.fromkeys(args.family))
    out_dir = Path(args.output) if args.output else None
    rows = []
    written: list[str] = []
    short: list[str] = []  # --per-type: the types the families could not make K of
    try:
        for e in _selected(args.only):
            wanted = args.instances
            for family in families:
                if wanted == 0:
                    break  # --per-type: the families before made this type's K
                rep = generate_variants(e, family, wanted, seed=args.seed, max_tries=args.max_tries)
                if args.per_type:
                    wanted -= len(rep.variants)
                rows.append({"id": e.id, "key": e.key, "family": family, "tried": rep.tried,
                             "invalid": rep.invalid, "crashed": rep.crashed,
                             "fix_holds": rep.fix_holds, "kept": len(rep.variants),
                             "reference_avoids": sum(v.reference_avoids for v in rep.variants),
                             "variants": [v.name for v in rep.variants]})
                if out_dir is not None:
                    for v in rep.variants:
                        with atomic_path(out_dir / f"{v.name}.toml") as tmp:
                            tmp.write_text(variant_toml(v), encoding="utf-8")
                        written.append(f"{v.name}.toml")
                        if args.record:
                            _record_variant(v, out_dir)
                if not args.json:
                    fixed = (f", the documented fix repairs {rep.fix_holds}" if e.truth.fixable
                             else " (no fix exists to check)")
                    invalid = f" ({rep.invalid} not valid scenarios)" if rep.invalid else ""
                    print(f"{e.id} {family}: {rep.crashed}/{rep.tried} tried variants crash"
                          f"{invalid}{fixed}; kept {len(rep.variants)}", file=env.stdout)
            if args.per_type and wanted > 0:
                short.append(f"{e.id} ({args.instances - wanted} of {args.instances})")
    except KeyboardInterrupt as exc:
        exc.kept = _kept(written, out_dir, "variant file")  # type: ignore[attr-defined]
        raise
    if args.json:
        print(json.dumps(rows, indent=2), file=env.stdout)
    if short:
        env.err().print(f"warning: fewer than {args.instances} variants kept for {', '.join(short)} "
                        "(add another --family to top them up)",
                        soft_wrap=True)
    return 0


def _record_variant(v, out_dir: Path) -> None:  # noqa: ANN001
    """The variant's accident recording, as ``rocas catalog record`` writes an entry's."""
    from rocas.catalog import accident_matches
    from rocas.rollout import simulate

    res = simulate(v.scenario, output=out_dir / f"{v.name}.mcap")
    if not accident_matches(v.entry.truth, res.outcome):  # the check simulated the same run
        raise UsageError(f"{v.name}: the recording does not end in the documented accident "
                         f"({res.outcome.summary()})")


def _kept(written: list[str], where: Path | None, what: str) -> str:
    """The Ctrl-C line's account of the files that were finished before the interruption."""
    if not written or where is None:
        return "no output was written"
    names = ", ".join(written[:3]) + (", ..." if len(written) > 3 else "")
    return f"{len(written)} complete {what}{'s' if len(written) != 1 else ''} kept in {where}: {names}"


def run(args: argparse.Namespace, env: Env) -> int:
    return {"list": _list, "record": _record, "generate": _generate}[args.action](args, env)
