"""``rocas bench``: rocas analyze over the accident catalog, scored against its ground truth."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rocas._json import dumps as json_dumps
from rocas.catalog import shipped_recordings
from rocas.cli.analyze import add_search_arguments
from rocas.cli.console import Env, safe
from rocas.scenarios.model import DEFAULT_STACK
from rocas.stacks.registry import get_stack

HELP = "run rocas analyze over the accident catalog and print Table 4 with hit/miss marks"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("ids", nargs="*", metavar="ID", help="catalog entries (default: all), e.g. a09 a12")
    p.add_argument("--out", metavar="DIR", default="runs/bench", help="where run directories go")
    p.add_argument("--stack", default=DEFAULT_STACK, metavar="NAME",
                   help="score this stack's catalog (default ads, the built-in ADS; lav: the "
                        "LAV-like stack's, recordings in recordings/lav/; highway: highway-env's "
                        "IDM/MOBIL driver, benched in its own world)")
    p.add_argument("--recordings", metavar="DIR", default=None,
                   help="directory with the catalog recordings (default recordings/, or "
                        "recordings/NAME/ with --stack NAME)")
    add_search_arguments(p, "the searches, the validation variants and generated instances")
    from rocas.search.executor import executor_names

    p.add_argument("--executor", default="local",
                   help=f"where simulations run: {', '.join(executor_names())} (default local; "
                        "ray joins RAY_ADDRESS or starts a local Ray); the answers do not "
                        "depend on it")
    p.add_argument("--compare-scope", type=int, default=3, metavar="N",
                   help="entries also analysed with --scope all (default 3)")
    p.add_argument("--instances", type=int, default=0, metavar="K",
                   help="also analyse K generated variants per type and report accuracy")
    p.add_argument("--seeds", metavar="S,S,...", type=_seed_list,
                   help="run the bench once per seed (e.g. 0,1,2,3,4; instead of --seed) and print "
                        "the hits per seed and per entry")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def _seed_list(text: str) -> list[int]:
    try:
        seeds = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of seeds: {text!r}") from None
    if not seeds or min(seeds) < 0:
        raise argparse.ArgumentTypeError(f"seeds are whole numbers of at least 0: {text!r}")
    return seeds


def run(args: argparse.Namespace, env: Env) -> int:
    from rocas.pipeline.bench import run_bench, run_bench_seeds
    from rocas.pipeline.config import AnalyzeConfig

    own = getattr(get_stack(args.stack), "bench", None)
    if own is not None:
        return _run_own_bench(own, args, env)
    cfg = AnalyzeConfig(seed=args.seed, budget=args.budget, workers=args.workers,
                        executor=args.executor,
                        validation_variants=args.validation, screening=args.screening,
                        alternate_references=args.references, second_opinion=args.second_opinion)
    recordings = Path(args.recordings) if args.recordings else shipped_recordings(args.stack)
    analysed = _analysed(args.ids, args.stack, recordings, env)
    kwargs: dict[str, Any] = {"recordings": recordings, "compare_scope": args.compare_scope,
                              "stack": args.stack,
                              "instances": args.instances,
                              "progress": lambda msg: print(msg, file=env.stderr, flush=True)}
    try:
        res = (run_bench_seeds(args.ids, Path(args.out), cfg, args.seeds, **kwargs) if args.seeds
               else run_bench(args.ids, Path(args.out), cfg, **kwargs))
    except KeyboardInterrupt as exc:
        exc.kept = (f"finished analyses and phases are kept in {args.out}; "  # type: ignore[attr-defined]
                    "the same command resumes them")
        raise
    res = {**res, "analysed": analysed}
    if args.json:
        env.stdout.write(json_dumps(res, indent=2) + "\n")
    elif args.seeds:
        for seed, one in zip(args.seeds, res["runs"], strict=True):
            env.out().print(f"[bold]Seed {seed}[/bold]")
            render({**one, "analysed": res["analysed"]}, env)
        render_seeds(res, env)
    else:
        render(res, env)
    return 0


def _analysed(ids: list[str], stack: str, recordings: Path, env: Env) -> str:
    """What the bench analyses: ``recordings``, ``scenarios`` (simulated, none of the entries'
    recordings is in ``recordings``) or ``recordings and scenarios``; says on stderr which
    entries are simulated and how to point the bench at the recordings."""
    from rocas.catalog import entries, entry
    from rocas.pipeline.bench import recording_for

    chosen = [entry(i, stack) for i in ids] if ids else list(entries(stack))
    missing = [e.id for e in chosen if recording_for(e.key, recordings) is None]
    if not missing:
        return "recordings"
    which = "no catalog recordings" if len(missing) == len(chosen) \
        else f"no recordings of {', '.join(missing)}"
    env.warn(f"{which} found in {recordings}/: analysing the scenarios, simulated "
             "(--recordings DIR reads them from DIR)")
    return "scenarios" if len(missing) == len(chosen) else "recordings and scenarios"


#: options of ``rocas bench`` a stack's own bench takes (the others are rocas's pipeline's)
_OWN_BENCH_OPTIONS = ("ids", "out", "stack", "seed", "seeds", "workers", "executor", "json")


def _run_own_bench(own: Any, args: argparse.Namespace, env: Env) -> int:
    """``rocas bench --stack NAME`` for a stack that declares its own bench (it analyses in
    its own world; rocas.stacks.base.CAPABILITIES): the same table, per seed with --seeds.

    Raises:
        UsageError: an option only rocas's own pipeline reads was given.
    """
    from rocas.cli.inputs import refuse_options_not_taken

    refuse_options_not_taken(args, add_arguments, [], _OWN_BENCH_OPTIONS,
                             f"stack {args.stack} benches in its own world",
                             unlisted=("ids", "stack"))
    out = Path(args.out)
    res = own(args.ids, args.seeds or [args.seed], workers=args.workers, executor=args.executor,
              progress=lambda msg: print(msg, file=env.stderr, flush=True))
    out.mkdir(parents=True, exist_ok=True)
    (out / "bench.json").write_text(json_dumps(res, indent=1) + "\n")
    if args.json:
        env.stdout.write(json_dumps(res, indent=2) + "\n")
        return 0
    for seed, one in zip(res["seeds"], res["runs"], strict=True):
        if args.seeds:
            env.out().print(f"[bold]Seed {seed}[/bold]")
        render(one, env)
    if args.seeds:
        render_seeds(res, env)
    elif res["median_seconds"] is not None:
        env.out().print(f"Median analysis: {res['median_seconds']:.1f} s")
    return 0


def _num(v: float) -> str:
    return f"{float(v):.3g}"


def _mark(ok: bool) -> str:
    return "[green]✓[/green]" if ok else "[red]✗[/red]"


def _confidence_cell(c: dict | None) -> str:
    if not c:
        return "—"
    text = f"{c['level']} {c['same']}/{c['runs']}" if c["runs"] else c["level"]
    if c["stance"]:
        text += f", subst. {c['stance']}"
    return text


def render(res: dict, env: Env) -> None:
    from rich.table import Table

    from rocas.pipeline.report import change

    con = env.out()
    who = f"stack {safe(res.get('stack', DEFAULT_STACK))}"
    how = {"scenarios": ", scenarios simulated (no recordings)",
           "recordings and scenarios": ", some scenarios simulated (no recording)"
           }.get(res.get("analysed", ""), "")
    t = Table(title=f"Table 4 for {who}{how}: {res['hits']} of {res['total']} hit")
    for c in ("id", "trigger found", "module (expected)", "misconfiguration found (expected)",
              "verdict", "confidence", "s"):
        t.add_column(c)
    for r in res["entries"]:
        e, f, m = r["expected"], r["found"], r["marks"]
        trig = f"{f['trigger_entity']}.{f['trigger_property']}" if f["trigger_entity"] else "—"
        if m.get("trigger") is not None:
            trig = f"{_mark(m['trigger'])} {trig} ({e['trigger_replayed']}.{e['trigger_property']})"
        found = ", ".join(change(c, "->") for c in f["changes"]) or "—"
        if f.get("robust"):
            found += ", robust " + ", ".join(_num(v) for v in f["robust"].values())
        wanted = "; ".join(", ".join(f"{k} {_num(v)}" for k, v in fix.items())
                           for fix in e["fixes"]) or "no fix"
        t.add_row(r["type"], trig,
                  f"{_mark(m['module'])} {f['deviating_module'] or '—'} ({e['deviating_module']})",
                  f"{_mark(m['parameter'])} {found} ({wanted})",
                  f"{_mark(m['verdict'])} {f['verdict']}", _confidence_cell(r.get("confidence")),
                  f"{r['seconds']:.1f}")
    con.print(t)
    a = res.get("agreement")
    if a and a["analyses"]:
        con.print(f"Confidence: {a['stable']} stable, {a['contested']} contested, {a['unstable']} unstable "
                  f"of {a['analyses']}; references unanimous in {a['unanimous']}, another reference "
                  f"adopted in {a['adopted']}; module substitution agrees or is consistent in "
                  f"{a['second_opinion_agrees']}")
    for line in _phase_lines(res):
        con.print(line)
    if res["search_space_reduction_mean"] is not None:
        con.print(f"Search space reduction: {100 * res['search_space_reduction_mean']:.1f} % "
                  "of the parameters (the paper: 85.8 %)")
    if res["scope_comparison"]:
        con.print(_scope_table(res["scope_comparison"]))
    for p in res["instances"]:
        repaired = (f", the documented fix repairs {p['fix_holds']}" if p["fixable"]
                    else " (no fix exists to check)")
        con.print(f"{p['type']}: {p['crashed']} of {p['tried']} variants crash{repaired}; "
                  f"{p['hits']} of {p['analyzed']} analysed correctly")


def _phase_lines(res: dict) -> list[str]:
    """The time per phase (seconds summed over the entries and share) and, when the rows carry
    them, the simulations per phase (``simulations``, or the built-in report's
    ``evaluations``)."""
    seconds: dict[str, float] = {}
    sims: dict[str, int] = {}
    for r in res["entries"]:
        for k, v in (r.get("timings_s") or {}).items():
            seconds[k] = seconds.get(k, 0.0) + v
        for k, v in (r.get("simulations") or r.get("evaluations") or {}).items():
            sims[k] = sims.get(k, 0) + int(v)
    tb = res["time_breakdown"]
    lines = ["Time per phase: " + ", ".join(
        f"{k} {seconds[k]:.1f} s ({100 * v:.1f} %)" if k in seconds else f"{k} {100 * v:.1f} %"
        for k, v in tb.items())
        + f" (total {res['time_total_s']:.1f} s; the paper: 16.4 % physical, 7.3 % diff, "
          "76.3 % cyber)"]
    if sims:
        lines.append("Simulations per phase: " + ", ".join(f"{k} {v}" for k, v in sims.items())
                     + f" (total {sum(sims.values())})")
    return lines


def render_seeds(res: dict, env: Env) -> None:
    """Hits per entry and seed, and per seed."""
    from rich.table import Table

    seeds = [str(s) for s in res["seeds"]]
    t = Table(title=f"Hits per seed: {res['every_seed']} of {res['total']} entries hit at every seed")
    t.add_column("id")
    for s in seeds:
        t.add_column(f"seed {s}")
    for row in res["entries"]:
        t.add_row(row["type"], *(f"{_mark(row['hits'][s])} {row['found'][s]['module'] or '—'}"
                                 for s in seeds))
    t.add_row("hits", *(f"{res['hits_per_seed'][s]} of {res['total']}" for s in seeds))
    per_seed = res.get("agreement_per_seed") or {}
    if all(s in per_seed and per_seed[s]["analyses"] for s in seeds):
        t.add_row("stable / contested / unstable",
                  *(f"{per_seed[s]['stable']} / {per_seed[s]['contested']} / {per_seed[s]['unstable']}"
                    for s in seeds))
    env.out().print(t)
    if res["median_seconds"] is not None:
        env.out().print(f"Median rocas analyze: {res['median_seconds']:.1f} s")


def _ratio(a: float | None, b: float | None) -> str:
    return f"{a / b:.1f}x" if a and b else "—"


def _scope_table(rows: list[dict]) -> Any:
    """Simulations until the first fix was known, per scope and search; the cell also gives
    the fix's position in its batch and marks whether the search ended on a documented fix's
    parameter, moved that fix's way."""
    from rich.table import Table

    t = Table(title="Cyber search: simulations until the first fix is known (position in its batch); "
                    "✓ = ended on a documented fix's parameter, moved its way")
    t.add_column("id")
    for search in ("screening", "plain GA"):
        for scope in ("module", "all"):
            t.add_column(f"{scope}, {search}", justify="right")
        t.add_column("all / module", justify="right")
    totals: dict[tuple[str, str], int] = {}
    for c in rows:
        cells = [c["id"]]
        for key, runs in (("screening", c), ("plain", c["plain"])):
            for scope in ("module", "all"):
                r = runs[scope]
                n = r["first_fix_batch_evaluations"]
                if n is not None:
                    totals[(key, scope)] = totals.get((key, scope), 0) + n
                cells.append(f"{n if n is not None else 'none'} ({r['first_fix_evaluation'] or '-'}) "
                             f"{_mark(r['parameter_hit'])}")
            cells.append(_ratio(runs["all"]["first_fix_batch_evaluations"],
                                runs["module"]["first_fix_batch_evaluations"]))
        t.add_row(*cells)
    t.add_row("total", str(totals.get(("screening", "module"), "—")),
              str(totals.get(("screening", "all"), "—")),
              _ratio(totals.get(("screening", "all")), totals.get(("screening", "module"))),
              str(totals.get(("plain", "module"), "—")), str(totals.get(("plain", "all"), "—")),
              _ratio(totals.get(("plain", "all")), totals.get(("plain", "module"))))
    return t
