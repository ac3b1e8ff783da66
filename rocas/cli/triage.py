"""``rocas triage INPUTS...``: analyse every accident of a campaign and group them by root cause."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rocas._fs import check_parent_exists
from rocas._json import dumps as json_dumps
from rocas.cli.analyze import add_executor_arguments, add_search_arguments
from rocas.cli.console import Env, safe
from rocas.cli.exit_codes import ExitStatus

HELP = "analyse every accident of a campaign and group them by root cause"

#: triage's cheaper default: the validation computes the robust value, which no grouping reads
TRIAGE_VALIDATION = 0


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="accident recordings (.mcap), scenario files (.toml, .json), directories "
                        "holding them, or quoted glob patterns")
    p.add_argument("--out", metavar="DIR", default="runs/campaign",
                   help="campaign directory (default runs/campaign)")
    add_search_arguments(p, seeded="every analysis's searches")
    p.set_defaults(validation=TRIAGE_VALIDATION)
    for action in p._actions:  # the validation's default is triage's own: say so in --help
        if action.dest == "validation":
            action.help = ("perturbed variants in each accident's regression test (default "
                           f"{TRIAGE_VALIDATION}: the robust value is not needed to group)")
    p.add_argument("--population", type=int, default=24, help="individuals per generation (default 24)")
    add_executor_arguments(p)
    p.add_argument("--resume", action="store_true", help="continue the campaign in --out")
    p.add_argument("--json", action="store_true", help="print campaign.json instead of the tables")
    p.add_argument("--quiet", "-q", action="store_true",
                   help="no progress bar on stderr: only the result")


def run(args: argparse.Namespace, env: Env) -> int:
    from rocas.campaign import collect_inputs, triage
    from rocas.errors import UsageError
    from rocas.pipeline.config import AnalyzeConfig

    cfg = AnalyzeConfig(seed=args.seed, budget=args.budget, population=args.population,
                        executor=args.executor, workers=args.workers,
                        validation_variants=args.validation, screening=args.screening,
                        alternate_references=args.references, second_opinion=args.second_opinion)
    if args.address and args.executor != "ray":
        raise UsageError("--address is for --executor ray", "add --executor ray, or drop --address")
    inputs = collect_inputs(args.inputs)
    out = Path(args.out)
    check_parent_exists(out)
    executor = None
    if args.executor == "ray":
        from rocas.search.ray_executor import RayExecutor

        executor = RayExecutor(args.workers, address=args.address)
    try:
        with (_QuietBar() if args.quiet else _CampaignBar(env, len(inputs))) as bar:
            campaign = triage(inputs, out, cfg, resume=args.resume, progress=bar, executor=executor)
    finally:
        if executor is not None:
            executor.close()
    if args.json:
        env.stdout.write(json_dumps(campaign, indent=2) + "\n")
    else:
        render(campaign, out, env)
    return ExitStatus.SUCCESS


class _QuietBar:
    """``--quiet``: the campaign's progress callback that shows nothing."""

    def __enter__(self) -> _QuietBar:
        return self

    def __exit__(self, *exc: Any) -> None:
        return None

    def __call__(self, k: int, n: int, name: str, phase: str, info: dict[str, Any]) -> None:
        return None


class _CampaignBar:
    """One progress bar for the campaign: accidents finished, and the accident and phase under way."""

    def __init__(self, env: Env, total: int) -> None:
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        self._p = Progress(TextColumn("triage"), BarColumn(), MofNCompleteColumn(),
                           TextColumn("{task.fields[info]}"), TimeElapsedColumn(),
                           console=env.err(), transient=False)
        self._task = self._p.add_task("triage", total=total, info="")

    def __enter__(self) -> _CampaignBar:
        self._p.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        self._p.__exit__(*exc)

    def __call__(self, k: int, n: int, name: str, phase: str, info: dict[str, Any]) -> None:
        if phase == "done":
            self._p.update(self._task, completed=k + 1,
                           info=safe(f"{name}: {info.get('verdict') or 'failed'}"))
            return
        detail = f", gen {info['generation']}" if "generation" in info else ""
        self._p.update(self._task, completed=k, info=safe(f"{name}: {phase}{detail}"))


def render(c: dict[str, Any], out: Path, env: Env) -> None:
    """The groups, the failures and the scores as tables."""
    from rich.table import Table

    con = env.out()
    t = Table(title=f"{c['analysed']} of {c['accidents_total']} accidents in {len(c['groups'])} groups")
    for col in ("group", "root cause", "accidents", "agreement", "documented types",
                "documented root cause"):
        t.add_column(col)
    for g in c["groups"]:
        t.add_row(safe(g["id"]), safe(g["root_cause"]), str(g["count"]),
                  safe(", ".join(f"{k} {v}" for k, v in g["agreement"].items())),
                  safe(", ".join(f"{k} {v}" for k, v in g["types"].items())),
                  {True: "yes", False: "no"}.get(g.get("documented"), ""))
    con.print(t)
    for f in c["failed"]:
        con.print(safe(f"failed: {f['name']} ({f['source']}): {f['reason']}"), soft_wrap=True)
    sc = c.get("scores")
    if sc:
        con.print(f"completeness {100 * sc['completeness']:.1f} % (worst type "
                  f"{100 * sc['worst_completeness']:.1f} %), purity {100 * sc['purity']:.1f} % "
                  f"(worst group {100 * sc['worst_purity']:.1f} %) over {sc['accidents_with_truth']} "
                  "accidents with a documented type", soft_wrap=True)
        if "groups_documented" in sc:
            con.print(f"root cause the documented one (module, parameter, direction): "
                      f"{sc['groups_documented']} of {sc['groups_with_truth']} groups, "
                      f"{sc['accidents_documented']} of {sc['accidents_with_truth']} accidents "
                      f"({100 * sc['documented_share']:.1f} %)", soft_wrap=True)
    else:
        con.print("completeness and purity: no accident has a documented type")
    con.print(f"campaign directory: {safe(out)} (campaign.json, campaign.md)", soft_wrap=True)
