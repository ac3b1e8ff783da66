"""``rocas analyze``: the paper's whole pipeline (sections 4-5) with a resumable run directory.

Phases: replay -> physical mutation -> differential analysis -> cyber mutation (then
minimisation) -> validation. Every phase writes its result into the run directory; searches
checkpoint every generation, so ``resume=True`` continues an interrupted run from its last
finished phase and generation without recomputing or losing anything.

Run directory::

    state.json        finished phases with their results, timings and evaluation counts
    scenario.json     the replayed scenario (the input of every later phase)
    accident.mcap     the replayed accident (recording mode)
    physical.ckpt     physical search checkpoint (while it runs)
    physical.json     the physical search: generations, chosen candidate
    reference.mcap    the accident-free reference execution
    diff.json         rocas diff between accident.mcap and reference.mcap
    cyber.ckpt / cyber.json
    fixed.mcap        the original scenario with the fixed configuration
    validation.ckpt   what the finished slices of the validation found (while it runs)
    validation.json   the regression test and the robust-value sweep
    report.json / report.md
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from rocas import numerics
from rocas._fs import check_writable, is_temporary, write_text_atomic
from rocas.errors import InputError, OutputError, ScenarioError, UsageError
from rocas.pipeline.cyber import cyber_space
from rocas.pipeline.evaluate import (
    VariantResult,
    VariantTask,
    evaluate,
    is_accident,
    params_tuple,
    violation,
)
from rocas.pipeline.physical import (
    apply_physical,
    describe,
    entity_kinds,
    entity_positions,
    mutated_entities,
    physical_space,
)
from rocas.scenarios.model import Scenario
from rocas.search.executor import Executor, make_executor
from rocas.search.ga import Candidate, GenerationStats, SearchConfig, SearchResult, run_search
from rocas.search.minimize import shrink_all_magnitudes, shrink_set, shrink_sets
from rocas.search.objectives import ego_dissimilarity, scenario_dissimilarity, suspiciousness
from rocas.search.space import Mutation, MutationSpace
from rocas.sim.oracles import Outcome

PHASES = ("replay", "physical", "diff", "cyber", "validation")
VERDICTS = ("misconfiguration", "no_configuration_fix", "no_reference", "not_reproduced")


@dataclass(frozen=True)
class AnalyzeConfig:
    """Settings of one analysis.

    Every setting is checked on construction (:class:`~rocas.errors.UsageError` with a hint),
    before a run directory is made or anything is simulated.

    Attributes:
        seed: seed of every search and of the validation variants (zero or more).
        budget: simulations per search phase (the rule: :meth:`search`).
        population: individuals per generation (at least 2).
        scope: "module" (search the deviating module's parameters) or "all" (the paper's
            brute-force baseline: every parameter).
        executor: registered executor name; workers: its worker count (None: all cores).
        batch_size: variants per batch-mode simulation.
        delta_s: Algorithm 1's window, also the h1 horizon cut [s].
        validation_variants: perturbed variants in the regression test.
        k_suspicion: K of f1 [m].
        h1_limit_m2: a fix may change the ego's trajectory before the accident by at most
            this MSE [m^2] (fixes beyond it count only when no other exists).
        shrink_candidates: how many of the search's best fixes (distinct parameter sets or
            directions of change) are shrunk before one is chosen (see _smallest_fix).
        screening: start the cyber search by trying every parameter alone at both ends of its
            range (two simulations per parameter, out of the budget); False runs a plain
            genetic search (the paper has no screening) from a population half single-parameter
            mutants, half random.
    """

    seed: int = 0
    budget: int = 240
    population: int = 24
    scope: str = "module"
    executor: str = "local"
    workers: int | None = None
    batch_size: int = 32
    delta_s: float = 3.0
    validation_variants: int = 200
    k_suspicion: float = 10.0
    h1_limit_m2: float = 1.0
    shrink_candidates: int = 3
    screening: bool = True

    def __post_init__(self) -> None:
        # every setting is checked here, before a run directory is made or a simulation runs
        def whole(value: Any, least: int, option: str, example: int) -> None:
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
                raise UsageError(f"{option} must be a whole number of at least {least}, not {value!r}",
                                 f"e.g. {option} {example}")

        def real(value: Any, option: str, example: float, positive: bool = False) -> None:
            ok = isinstance(value, (int, float, np.number)) and not isinstance(value, bool) \
                and math.isfinite(value) and (value > 0 if positive else value >= 0)
            if not ok:
                raise UsageError(f"{option} must be a {'positive' if positive else 'non-negative'} "
                                 f"finite number, not {value!r}", f"e.g. {option} {example:g}")

        whole(self.seed, 0, "--seed", 0)
        whole(self.population, 2, "--population", 24)
        whole(self.budget, 1, "--budget", 240)
        if self.budget < self.population:
            raise UsageError(f"--budget must be at least the population ({self.population}), "
                             f"not {self.budget}", "raise --budget or lower --population")
        if self.scope not in ("module", "all"):
            raise UsageError(f"--scope must be module or all, not {self.scope!r}",
                             "module searches the deviating module's parameters, all every one")
        from rocas.search.executor import executor_names

        if self.executor not in executor_names():
            raise UsageError(f"unknown executor {self.executor!r}",
                             f"choose one of: {', '.join(executor_names())}")
        if self.workers is not None:
            whole(self.workers, 1, "--workers", 1)
        whole(self.batch_size, 1, "batch_size", 32)
        real(self.delta_s, "--delta", 3.0)
        whole(self.validation_variants, 0, "--validation", 200)
        real(self.k_suspicion, "k_suspicion", 10.0, positive=True)
        real(self.h1_limit_m2, "h1_limit_m2", 1.0)
        whole(self.shrink_candidates, 1, "shrink_candidates", 3)

    def search(self, stage: int, n_vars: int = 0) -> SearchConfig:
        """The search of stage 1 (physical: single-property seeds) or 2 (cyber).

        The budget rule (see :func:`planned_simulations`): stage 1 runs budget // population
        generations. Stage 2 with screening first tries each of its ``n_vars`` parameters
        alone at both ends of its range (two simulations per parameter, out of the budget),
        then runs (budget - 2 n_vars) // population generations, but at least 2: the first
        generation is the best screened mutants, already simulated, so at least one generation
        of new mutants always runs, even when the screening alone uses up the budget."""
        screen = stage == 2 and self.screening
        generations = (max(2, (self.budget - 2 * n_vars) // self.population) if screen
                       else self.budget // self.population)
        return SearchConfig(population=self.population, generations=generations,
                            seed=self.seed * 1000 + stage,
                            single_property_share=1.0 if stage == 1 else 0.5,
                            mutate_prob=0.3, screen=screen)


def planned_simulations(search: SearchConfig, screening: int = 0) -> int:
    """The most simulations a search runs (its progress bar's total): the ``screening``
    simulations, then population new mutants per generation, except that with screening the
    first generation is the best screened mutants (new ones only where fewer were screened
    than the population). Repeated mutants are simulated once, so a search may run fewer."""
    if not search.screen:
        return search.population * search.generations
    return (screening + max(0, search.population - screening)
            + search.population * (search.generations - 1))


def screening_simulations(space: MutationSpace, seed: int) -> int:
    """How many simulations the screening of ``space`` runs: two per parameter, less an end
    of a range that is the parameter's value in force (no change, nothing to simulate)."""
    from rocas.search.ga import screening_genomes

    return len({m for m in (space.decode(g) for g in screening_genomes(space, seed)) if m.values})


@dataclass(frozen=True)
class Accident:
    """The accident of a run: kind ("collision" or "emergency"), time [s], other party."""

    kind: str
    time_s: float
    other: str | None

    @classmethod
    def of(cls, o: Outcome) -> Accident | None:
        if o.collided:
            return cls("collision", float(o.collision_time_s or 0.0), o.collision_with)
        if o.emergency:
            times = [t for t in (o.hard_brake_time_s, o.estop_time_s) if t is not None]
            return cls("emergency", float(min(times)) if times else 0.0, None)
        return None

    def to_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "time_s": round(self.time_s, 3), "other": self.other}


Progress = Callable[[str, dict[str, Any]], None]


def _noop(_: str, __: dict[str, Any]) -> None:
    pass


@dataclass
class _Run:
    """Everything phases share (rebuilt on resume from the run directory)."""

    out: Path
    cfg: AnalyzeConfig
    executor: Executor
    progress: Progress
    state: dict[str, Any]
    scenario: Scenario | None = None
    original: VariantResult | None = None
    accident: Accident | None = None
    accident_tick: int = 0

    @property
    def h1_horizon(self) -> int:
        """Samples of the ego trajectory h1 compares: [0, d - delta] (at least one)."""
        assert self.scenario is not None
        return max(1, self.accident_tick - int(round(self.cfg.delta_s / self.scenario.dt_s)))

    def cyber_space(self, module: str | None) -> MutationSpace:
        """The parameters the cyber phase searches (the module's, or all with --scope all) at
        the values in force in the accident run."""
        from rocas.ads.params import ParamSet

        assert self.scenario is not None
        return cyber_space(module if self.cfg.scope == "module" else None,
                           dict(ParamSet(self.scenario.ego.overrides)))

    def save(self) -> None:
        write_text_atomic(self.out / "state.json", json.dumps(self.state, indent=2, default=_jsonable))

    def done(self, phase: str) -> bool:
        return phase in self.state["done"]

    def finish(self, phase: str, result: dict[str, Any], seconds: float, evaluations: int = 0) -> None:
        self.state["done"][phase] = result
        self.state["timings_s"][phase] = round(seconds, 3)
        self.state["evaluations"][phase] = evaluations
        self.save()


def _jsonable(x: Any) -> Any:
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(type(x).__name__)


#: settings of AnalyzeConfig that do not change the result (where and how simulations run)
_NOT_SETTINGS = ("executor", "workers")
#: ... and those the report lists (batch_size only groups simulations)
REPORT_SETTINGS = ("seed", "budget", "population", "scope", "screening", "delta_s",
                   "validation_variants", "h1_limit_m2", "k_suspicion", "shrink_candidates")


def _config(cfg: AnalyzeConfig) -> dict[str, Any]:
    return {k: getattr(cfg, k) for k in cfg.__dataclass_fields__ if k not in _NOT_SETTINGS}


def source_identity(source: str | os.PathLike[str] | Scenario) -> tuple[str, str]:
    """``(label, sha256)`` of an analysis's input: the recording's resolved path and the
    digest of its bytes, or ``scenario:NAME`` and the digest of the scenario's canonical JSON.
    A run directory is resumed only with an input of the same digest.

    Raises:
        InputError: the recording cannot be read.
    """
    if isinstance(source, Scenario):
        from rocas.scenarios.loader import scenario_to_dict

        text = json.dumps(scenario_to_dict(source), sort_keys=True, separators=(",", ":"))
        return f"scenario:{source.name}", hashlib.sha256(text.encode()).hexdigest()
    path = Path(source)
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            while chunk := f.read(1 << 20):
                digest.update(chunk)
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror or exc}", "check the path") from None
    return str(path.resolve()), digest.hexdigest()


def _damaged(out: Path, name: str, reason: str) -> InputError:
    return InputError(f"run directory {out} is damaged: {name} {reason}",
                      f"delete {out} to start again, or choose another --out")


def _read_state(out: Path) -> dict[str, Any]:
    try:
        state = json.loads((out / "state.json").read_text(encoding="utf-8"))
    except OSError as exc:
        raise _damaged(out, "state.json", f"cannot be read ({exc.strerror or exc})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise _damaged(out, "state.json", f"is not valid JSON ({exc})") from None
    if not (isinstance(state, dict)
            and all(isinstance(state.get(k), dict) for k in ("done", "config", "timings_s", "evaluations"))
            and set(state["done"]) <= set(PHASES)):
        raise _damaged(out, "state.json", "is not a rocas run state")
    return state


def _remove_debris(out: Path) -> None:
    """Remove the temporaries of writes a killed process left (``.NAME.XXXX.part``)."""
    for p in out.iterdir():
        if is_temporary(p) and p.is_file():
            p.unlink(missing_ok=True)


def _fmt_setting(v: Any) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def prepare_run_dir(out: Path, resume: bool, source: str, cfg: AnalyzeConfig,
                    source_sha256: str | None = None) -> dict[str, Any]:
    """Create or reopen a run directory; returns its state.

    A run directory is resumed only with the same settings (those that change the result; not
    the executor or its workers) and the same input: the same ``source_sha256`` (content), or,
    for a run directory written before inputs were identified by content, the same ``source``
    label (path). Temporaries of writes a killed run left behind (``.NAME.XXXX.part``) are
    removed, and are not taken for foreign content.

    Raises:
        UsageError: ``out`` holds an analysis but ``resume`` is False, or one of another input
            or other settings, or other files.
        InputError: ``out/state.json`` is damaged.
        OutputError: ``out`` cannot be made or written.
    """
    state_path = out / "state.json"
    config = _config(cfg)
    if state_path.exists():
        if not resume:
            raise UsageError(f"run directory {out} already holds an analysis",
                             "continue it with --resume, or choose another --out")
        state = _read_state(out)
        if "source_sha256" in state:
            same_input = state["source_sha256"] == source_sha256
        else:  # written before inputs were identified by content: by path, as then
            same_input = state.get("source") == source
        if not same_input:
            raise UsageError(f"run directory {out} holds the analysis of another input: it was "
                             f"started on {state.get('source')}, and {source} has other content",
                             "choose another --out, or resume with the input it was started with")
        # a setting added after the run was started has its default, which is what that run used
        default = _config(AnalyzeConfig())
        stored = {**default, **{k: v for k, v in state["config"].items() if k in default}}
        differ = [f"{k} {_fmt_setting(config[k])} vs {_fmt_setting(stored[k])}"
                  for k in config if config[k] != stored[k]]
        if differ:
            raise UsageError(f"run directory {out} holds an analysis with other settings "
                             f"(given vs stored: {', '.join(differ)})",
                             "choose another --out, or resume with the options it was started with")
        _remove_debris(out)
        return state
    if out.exists() and not out.is_dir():
        raise OutputError(f"cannot make run directory {out}: a file of that name exists",
                          "choose another --out")
    if out.exists():
        if any(not is_temporary(p) for p in out.iterdir()):
            raise UsageError(f"{out} exists and is not a rocas run directory", "choose another --out")
        _remove_debris(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        check_writable(out / "state.json")
    except OSError as exc:
        raise OutputError(f"cannot make run directory {out}: {exc.strerror or exc}",
                          "choose a writable place for --out") from exc
    state = {"version": 1, "source": source, "config": config, "done": {}, "timings_s": {},
             "evaluations": {}}
    if source_sha256 is not None:
        state["source_sha256"] = source_sha256
    return state


# -- phase I: replay -------------------------------------------------------------------------
def _phase_replay(run: _Run, scenario: Scenario | None, recording: Path | None) -> None:
    from rocas.scenarios.loader import scenario_from_dict, scenario_to_dict
    from rocas.sim.engine import simulate

    if run.done("replay"):
        try:
            run.scenario = scenario_from_dict(json.loads((run.out / "scenario.json").read_text()))
        except OSError as exc:
            raise _damaged(run.out, "scenario.json", f"cannot be read ({exc.strerror or exc})") from None
        except (ValueError, ScenarioError) as exc:  # JSONDecodeError and UnicodeDecodeError too
            raise _damaged(run.out, "scenario.json", f"is not a valid scenario ({exc})") from None
    else:
        t0 = time.perf_counter()
        result: dict[str, Any] = {}
        if recording is not None:
            import rocas.replay as replay_mod

            recon = replay_mod.reconstruct(recording)
            report = replay_mod.replay(recon, output=run.out / "accident.mcap")
            scenario = recon.scenario
            # the replay figures of the report: the recorded accident (None: the recording
            # holds none), the replay's, and how closely the ego followed its recorded pose
            result = {"source": "recording", "reproduced": bool(report.reproduced),
                      "recorded_accident": report.original.to_dict() if report.original else None,
                      "accident": report.accident.to_dict() if report.accident else None,
                      "ego_rmse_m": report.ego_rmse_m, "compared_until_s": report.compared_until_s}
        else:
            assert scenario is not None
            res = simulate(scenario, output=run.out / "accident.mcap")
            acc = Accident.of(res.outcome)
            result = {"source": "scenario", "reproduced": is_accident(res.outcome),
                      "recorded_accident": None, "accident": acc.to_json() if acc else None,
                      "ego_rmse_m": 0.0}
        run.scenario = scenario
        write_text_atomic(run.out / "scenario.json", json.dumps(scenario_to_dict(scenario), indent=1))
        write_text_atomic(run.out / "replay.json", json.dumps(result, indent=1))
        run.finish("replay", result, time.perf_counter() - t0, 1)
    # the original run's trajectories are re-simulated (deterministic) rather than stored
    (orig,) = evaluate(run.executor, [VariantTask(run.scenario, (), run.scenario.seed)])
    run.original = orig
    run.accident = Accident.of(orig.outcome)
    dt = run.scenario.dt_s
    run.accident_tick = int(round(run.accident.time_s / dt)) if run.accident else 0


# -- phase II: physical mutation -------------------------------------------------------------
def _phase_physical(run: _Run) -> dict[str, Any]:
    from rocas.sim.engine import simulate

    if run.done("physical"):
        return run.state["done"]["physical"]
    run.progress("physical", {"planned": planned_simulations(run.cfg.search(1))})
    t0 = time.perf_counter()
    scn, orig, tick = run.scenario, run.original, run.accident_tick
    assert scn is not None and orig is not None
    space = physical_space(scn)
    positions = entity_positions(scn, orig.actors_xy[min(tick, len(orig.actors_xy) - 1)])
    ego_xy = tuple(orig.ego_xy[tick])
    prev = orig.ego_xy[max(tick - 1, 0)]
    heading = float(numerics.arctan2(ego_xy[1] - prev[1], ego_xy[0] - prev[0])) if tick else 0.0
    actor_ids = [a.id for a in scn.actors]
    upto = tick + 1

    def objectives(m: Mutation, r: VariantResult) -> tuple[tuple[float, ...], float]:
        ents = mutated_entities(space, m)
        f1 = suspiciousness([positions.get(e) for e in ents], ego_xy, heading, run.cfg.k_suspicion)
        # f2 over every actor and the ego: a reference in which the ego already drives
        # differently long before the accident is a poor reference for the diff
        f2 = scenario_dissimilarity(
            {"ego": orig.ego_xy[:upto], **{a: orig.actors_xy[:upto, i] for i, a in enumerate(actor_ids)}},
            {"ego": r.ego_xy[:upto], **{a: r.actors_xy[:upto, i] for i, a in enumerate(actor_ids)}})
        return (f1, f2, space.distance(m)), violation(r.outcome)

    def batch(ms: list[Mutation]) -> list[tuple[tuple[float, ...], float]]:
        tasks = [VariantTask(apply_physical(scn, m), (), scn.seed) for m in ms]
        return [objectives(m, r) for m, r in zip(ms, evaluate(run.executor, tasks, run.cfg.batch_size),
                                                 strict=True)]

    res = run_search(space, batch, run.cfg.search(1), 3, checkpoint=run.out / "physical.ckpt",
                     on_generation=lambda s: run.progress("physical", _gen_info(s, "f2")))
    chosen = _choose_trigger(res, space)
    result: dict[str, Any] = {"generations": [_gen_json(g, "f2") for g in res.generations],
                              "evaluations": res.evaluations, "feasible": len(res.feasible),
                              "front": [_cand_json(c) for c in res.front[:20]]}
    evaluations = res.evaluations
    if chosen is not None:
        # drop properties the avoidance does not need (a search often carries passengers,
        # e.g. a 0.0001 m move of a bystander), keeping the reference as similar as chosen
        f2_limit = f2_tolerance(chosen.objectives[1])
        scores = _Scores(batch, res.candidates)

        def holds(ms: list[Mutation]) -> list[bool]:
            return [cons <= 0.0 and objs[1] <= f2_limit for objs, cons in scores.of(ms)]

        small, _ = shrink_set(chosen.mutation, holds)
        evaluations += scores.simulated
        result["shrink_evaluations"] = scores.simulated
        result["search_chosen"] = _cand_json(chosen)
        if small != chosen.mutation:  # a trial that held: its objectives are already known
            objs, cons = scores.of([small])[0]
            chosen = replace(chosen, mutation=small, objectives=objs, constraint=cons)
        entity = mutated_entities(space, chosen.mutation)
        result["chosen"] = _cand_json(chosen)
        result["triggering_entity"] = {
            "entity": entity[0] if entity else None,
            "kind": entity_kinds(scn).get(entity[0]) if entity else None,
            "entities": entity,
            "properties": describe(space, chosen.mutation),
        }
        simulate(apply_physical(scn, chosen.mutation), output=run.out / "reference.mcap")
    write_text_atomic(run.out / "physical.json", json.dumps(result, indent=1, default=_jsonable))
    run.finish("physical", result, time.perf_counter() - t0, evaluations)
    (run.out / "physical.ckpt").unlink(missing_ok=True)
    return result


#: f2 [m^2] within which front members count as equally similar to the original ...
F2_TOLERANCE_M2 = 1.0
#: ... or this fraction of the best f2, whichever is larger: f2 is a mean squared distance,
#: so its scale grows with speeds and duration, and a fixed margin that separates two
#: references on a parking lot would call two highway references different
F2_TOLERANCE_REL = 0.25


def f2_tolerance(best_f2: float) -> float:
    """The largest f2 [m^2] that counts as as similar to the original as ``best_f2``."""
    return best_f2 + max(F2_TOLERANCE_M2, F2_TOLERANCE_REL * best_f2)


def _choose_trigger(res: SearchResult, space: MutationSpace) -> Candidate | None:
    """The documented rule, over the feasible Pareto front:

    1. keep the executions most similar to the original (f2 within F2_TOLERANCE_M2 or
       F2_TOLERANCE_REL of the best, whichever is larger; see f2_tolerance): a good
       reference differs from the accident only where it must;
    2. then the fewest mutated entities (the triggering entity, not a coalition);
    3. then the most suspicious (f1: close to and in front of the ego);
    4. then the smallest change (f3);
    5. then changing a property over removing an entity (``enabled`` -> off): a reference that
       keeps every entity differs from the accident only in that property, which is what the
       diff should see;
    6. then the names, for determinism.
    """
    if not res.front:
        return None
    best_f2 = min(c.objectives[1] for c in res.front)
    similar = [c for c in res.front if c.objectives[1] <= f2_tolerance(best_f2)]
    return min(similar, key=lambda c: (len(mutated_entities(space, c.mutation)), c.objectives[0],
                                       c.objectives[2], _removals(c.mutation), c.objectives[1],
                                       c.mutation.names))


def _removals(m: Mutation) -> int:
    """How many entities a mutation removes (an ``enabled`` property switched off)."""
    return sum(1 for n, v in m.values.items() if n.endswith(".enabled") and not v)


# -- phase III: differential analysis --------------------------------------------------------
def _phase_diff(run: _Run) -> dict[str, Any]:
    from rocas.analysis.diff import diff

    if run.done("diff"):
        return run.state["done"]["diff"]
    t0 = time.perf_counter()
    result = diff(run.out / "accident.mcap", run.out / "reference.mcap", delta_s=run.cfg.delta_s)
    data = result.to_json()
    write_text_atomic(run.out / "diff.json", json.dumps(data, indent=1))
    summary = {"deviating_module": data["deviating_module"], "path": data["path"],
               "control_channel": data["control_channel"]}
    run.finish("diff", summary, time.perf_counter() - t0, 0)
    return summary


# -- phase IV: cyber mutation ----------------------------------------------------------------
def _phase_cyber(run: _Run, module: str | None) -> dict[str, Any]:
    from rocas.sim.engine import simulate

    if run.done("cyber"):
        return run.state["done"]["cyber"]
    t0 = time.perf_counter()
    scn, orig = run.scenario, run.original
    assert scn is not None and orig is not None
    space = run.cyber_space(module)
    search = run.cfg.search(2, len(space.variables))
    screening = screening_simulations(space, search.seed) if search.screen else 0
    run.progress("cyber", {"planned": planned_simulations(search, screening)})
    horizon = run.h1_horizon

    def overrides(m: Mutation) -> tuple[tuple[str, float], ...]:
        return params_tuple({k: float(v) for k, v in m.values.items()})

    def run_fixes(ms: list[Mutation]) -> list[VariantResult]:
        tasks = [VariantTask(scn, overrides(m), scn.seed) for m in ms]
        return evaluate(run.executor, tasks, run.cfg.batch_size)

    # each simulated fix's smallest gap to anything [m], for choosing among shrunk fixes
    separation: dict[Mutation, float] = {}

    def batch(ms: list[Mutation]) -> list[tuple[tuple[float, ...], float]]:
        out = []
        for m, r in zip(ms, run_fixes(ms), strict=True):
            separation[m] = r.outcome.min_separation_m
            out.append(((ego_dissimilarity(orig.ego_xy, r.ego_xy, horizon), space.distance(m)),
                        violation(r.outcome)))
        return out

    originals = {v.name: float(v.original) for v in space.variables}
    res = run_search(space, batch, search, 2,
                     checkpoint=run.out / "cyber.ckpt",
                     on_generation=lambda s: run.progress("cyber", _gen_info(s, "h2")))
    result: dict[str, Any] = {"module": module, "scope": run.cfg.scope, "parameters": len(space.variables),
                              "generations": [_gen_json(g, "h2") for g in res.generations],
                              "evaluations": res.evaluations, "feasible": len(res.feasible),
                              "first_fix_evaluation": _first_fix(res, run.cfg.h1_limit_m2),
                              "first_fix_batch_evaluations": _first_fix_batch(res, run.cfg.h1_limit_m2)}
    candidates = _fix_candidates(res, run.cfg.h1_limit_m2, run.cfg.shrink_candidates, originals)
    nearest = _nearest_fix(res, run.cfg.h1_limit_m2)
    if nearest is not None:
        result["nearest_fix"] = _cand_json(nearest)
    evaluations = res.evaluations
    if candidates:
        # the search ranks fixes by the size it happened to try; each of the best few is shrunk
        # (set, then magnitudes) and the smallest shrunk fix wins
        run.progress("minimise", {"parameters": sum(len(c.mutation.values) for c in candidates)})
        # candidates often shrink through the same mutations, and the search has already
        # scored many of them; the candidates shrink in lockstep, one batch per round
        scores = _Scores(batch, res.candidates)
        limits = [max(run.cfg.h1_limit_m2, c.objectives[0]) for c in candidates]

        def holds(trials: list[tuple[int, Mutation]]) -> list[bool]:
            return [cons <= 0.0 and objs[0] <= limits[i]
                    for (i, _), (objs, cons) in zip(trials, scores.of([m for _, m in trials]),
                                                    strict=True)]

        smalls, _ = shrink_sets([c.mutation for c in candidates], holds)
        smalls, _ = shrink_all_magnitudes(smalls, space, holds)
        evaluations += scores.simulated
        # every shrunk fix was simulated by the search or as a trial, and counted there; only a
        # search resumed from its checkpoint lacks the gaps of its earlier generations, and
        # re-running those is the resume's cost, not the analysis's (the report stays the same)
        unseen = [m for m in dict.fromkeys(smalls) if m not in separation]
        if unseen:
            batch(unseen)
        best, near = _smallest_fix([space.distance(m) for m in smalls], smalls,
                                   separation=[separation[m] for m in smalls],
                                   originals=originals)
        small, chosen = smalls[best], candidates[best]
        result["search_best"] = _cand_json(chosen)
        result["minimise_evaluations"] = scores.simulated
        result["shrunk_candidates"] = [
            {"search": _cand_json(c), "shrunk": {k: float(v) for k, v in m.values.items()},
             "h2": round(space.distance(m), 6),
             # None when nothing was ever near (no actor or object): JSON has no infinity
             "min_separation_m": separation[m] if np.isfinite(separation[m]) else None}
            for c, m in zip(candidates, smalls, strict=True)]
        result["fix"] = {k: float(v) for k, v in small.values.items()}

        def described(m: Mutation) -> list[dict[str, Any]]:
            return [{"module": n.split(".", 1)[0], "parameter": n,
                     "original": space.variable(n).original, "mutated": m.values[n]}
                    for n in m.names]

        result["misconfiguration"] = described(small)
        result["alternatives"] = [{"h2": round(space.distance(smalls[i]), 6),
                                   "misconfiguration": described(smalls[i])} for i in near]
        simulate(scn, params=result["fix"], output=run.out / "fixed.mcap")
    write_text_atomic(run.out / "cyber.json", json.dumps(result, indent=1, default=_jsonable))
    run.finish("cyber", result, time.perf_counter() - t0, evaluations)
    (run.out / "cyber.ckpt").unlink(missing_ok=True)
    return result


#: h2 within which another shrunk fix is reported as an alternative (0.05: one parameter
#: moved 5 % of its range farther than the chosen fix)
ALTERNATIVE_H2_TOLERANCE = 0.05


def _smallest_fix(h2: list[float], fixes: list[Mutation],
                  tolerance: float = ALTERNATIVE_H2_TOLERANCE,
                  separation: list[float] | None = None,
                  originals: Mapping[str, float] | None = None) -> tuple[int, list[int]]:
    """Index of the chosen shrunk fix, and the indices of the other fixes (other parameter
    sets, or the same parameters moved the other way) within ``tolerance`` of the smallest
    h2, in order: the same margin expressed in another parameter, or a second suspect.

    The smallest fix (h2, ties by parameter names) is chosen, unless another fix within
    ``tolerance`` of it keeps the ego farther from everything (``separation``: the run's
    smallest gap to any actor or object [m], 0.5 m more or better): such changes are
    equally small, and the one that adds margin is the repair, not the one that avoids the
    accident narrowly (an overtake margin lowered until the ego races ahead of the truck)."""
    order = sorted(range(len(fixes)), key=lambda i: (h2[i], fixes[i].names))
    close = [i for i in order if h2[i] <= h2[order[0]] + tolerance]
    best = order[0]
    if separation is not None:
        widest = max(close, key=lambda i: (separation[i], -h2[i]))
        if separation[widest] >= separation[best] + SEPARATION_MARGIN_M:
            best = widest

    def kind(m: Mutation) -> Any:
        return m.names if originals is None else _direction(m, originals)

    seen = {kind(fixes[best])}
    near = []
    for i in close:
        if kind(fixes[i]) not in seen:
            seen.add(kind(fixes[i]))
            near.append(i)
    return best, near


#: how much wider [m] an equally small fix must keep the ego's smallest gap to be preferred
SEPARATION_MARGIN_M = 0.5


class _Scores:
    """(objectives, constraint) per mutation, each simulated once: seeded with what a search
    already scored, the rest run in one batch per call."""

    def __init__(self, batch: Callable[[list[Mutation]], list[tuple[tuple[float, ...], float]]],
                 known: list[Candidate]) -> None:
        self._batch = batch
        self._scores = {c.mutation: (c.objectives, c.constraint) for c in known}
        self.simulated = 0

    def of(self, ms: list[Mutation]) -> list[tuple[tuple[float, ...], float]]:
        todo = list(dict.fromkeys(m for m in ms if m not in self._scores))
        if todo:
            self._scores.update(zip(todo, self._batch(todo), strict=True))
            self.simulated += len(todo)
        return [self._scores[m] for m in ms]


def _first_fix(res: SearchResult, h1_limit: float) -> int | None:
    """How many simulations the search ran up to its first fix: a candidate that avoids the
    accident and keeps the ego's earlier trajectory (h1 within the limit), i.e. one that
    :func:`_fix_candidates` would accept as it stands."""
    for i, c in enumerate(res.candidates, 1):
        if c.feasible and c.objectives[0] <= h1_limit:
            return i
    return None


def _first_fix_batch(res: SearchResult, h1_limit: float) -> int | None:
    """How many simulations had run when the first fix became known: a generation (the
    screening too) is evaluated as one batch, so its every simulation is paid before any of its
    results is in. Unlike :func:`_first_fix` this does not depend on where in its batch the
    fix happened to sit."""
    i = _first_fix(res, h1_limit)
    if i is None:
        return None
    gen = res.candidates[i - 1].generation
    return next((g.evaluations for g in res.generations if g.generation == gen), i)


def _fix_candidates(res: SearchResult, h1_limit: float, count: int,
                    originals: Mapping[str, float] | None = None) -> list[Candidate]:
    """The best ``count`` feasible fixes with distinct parameter sets or directions (up or
    down from ``originals``): those that keep the ego's earlier trajectory (h1 <= limit), by
    smallest change (h2). None when no fix keeps it: a configuration that avoids the accident
    only by driving differently before it is not a fix (:func:`_nearest_fix` records it)."""
    originals = originals or {}
    keep = [c for c in res.feasible if c.objectives[0] <= h1_limit]
    out: list[Candidate] = []
    seen: set[tuple[tuple[str, int], ...]] = set()
    for c in sorted(keep, key=lambda c: (c.objectives[1], c.objectives[0], c.mutation.names)):
        key = _direction(c.mutation, originals)
        if key not in seen:
            seen.add(key)
            out.append(c)
        if len(out) == count:
            break
    return out


def _nearest_fix(res: SearchResult, h1_limit: float) -> Candidate | None:
    """When every accident-free configuration changes the ego's earlier trajectory beyond
    ``h1_limit``, the one that changes it least; else None."""
    feasible = res.feasible
    if not feasible or any(c.objectives[0] <= h1_limit for c in feasible):
        return None
    return min(feasible, key=lambda c: (c.objectives[0], c.objectives[1], c.mutation.names))


def _direction(m: Mutation, originals: Mapping[str, float]) -> tuple[tuple[str, int], ...]:
    """A fix's parameters with the sign of each change: raising a margin and lowering it are
    different fixes."""
    return tuple((n, int(np.sign(float(m.values[n]) - float(originals[n]))) if n in originals
                  else 0) for n in m.names)


# -- phase V: validation ---------------------------------------------------------------------
def perturbed_variants(scenario: Scenario, count: int, seed: int) -> list[Scenario]:
    """``count`` variants of ``scenario``: actor speeds scaled by U(0.95, 1.05), start
    positions moved by U(-2, 2) m, and a new simulation seed each."""
    import dataclasses

    rng = np.random.default_rng(seed + 7)
    out = []
    for k in range(count):
        actors = []
        for a in scenario.actors:
            scale = float(rng.uniform(0.95, 1.05))
            ds = float(rng.uniform(-2.0, 2.0))
            actors.append(dataclasses.replace(
                a, start_s_m=max(0.0, a.start_s_m + ds),
                speed_profile=tuple((t, v * scale) for t, v in a.speed_profile)))
        out.append(dataclasses.replace(scenario, actors=tuple(actors), seed=scenario.seed + 1 + k))
    return out


#: how far past the minimal fix the validation tries stronger values: fractions of the way from
#: the minimal fix to the end of each parameter's range in the fix's direction
STRONGER_FRACTIONS = (0.125, 0.25, 0.5, 0.75, 1.0)
#: the robust value is the closest to the minimal fix whose success rate over the variants is
#: within this of the best rate seen, and it is reported only when it beats the minimal fix's
#: rate by at least this much (0.05: ten of 200 variants)
ROBUST_TOLERANCE = 0.05


def validation_simulations(variants: int) -> int:
    """Simulations of phase V at most: the variants with the original and the minimal fix, then
    each stronger value on the accident itself and on every variant (none without variants;
    fewer when stronger values coincide, see stronger_fixes)."""
    return 2 * variants + len(STRONGER_FRACTIONS) * (variants + 1) if variants else 0


def stronger_fixes(fix: Mapping[str, float], space: MutationSpace
                   ) -> list[tuple[float, dict[str, float]]]:
    """``(fraction, values)``: the fix moved each of STRONGER_FRACTIONS of the way on to the end
    of each parameter's range in the direction it moved (integer parameters rounded), closest
    first. A value equal to the fix or to a closer one is left out (it would only be simulated
    again): a fix already at the end of its range has no stronger value."""
    out: list[tuple[float, dict[str, float]]] = []
    seen = [dict(fix)]
    for f in STRONGER_FRACTIONS:
        values = {}
        for name, x in fix.items():
            var = space.variable(name)
            lo, hi = float(var.low), float(var.high)  # type: ignore[arg-type]
            end = hi if x > float(var.original) else lo
            # x + f * (end - x) can land a rounding error outside the range, which the ADS refuses
            v = min(max(x + f * (end - x), lo), hi)
            values[name] = float(round(v)) if var.kind == "int" else v
        if values not in seen:
            seen.append(values)
            out.append((f, values))
    return out


#: simulations of phase V per slice, in batches (of AnalyzeConfig.batch_size) per worker: after
#: each slice the progress bar advances and the finished simulations are checkpointed
VALIDATION_SLICE_BATCHES = 4


def _phase_validation(run: _Run, fix: dict[str, float], module: str | None) -> dict[str, Any]:
    """The paper's regression test: K perturbed variants with the original configuration and
    with the minimal fix. Then the robust value: the fix moved further the same way
    (STRONGER_FRACTIONS), each stronger value run on the accident (it must still avoid it and
    keep the ego's earlier trajectory, h1) and on the same variants.

    The simulations run in slices (VALIDATION_SLICE_BATCHES batches per worker); after each, the
    progress callback gets the running count (``evaluations``) and what the finished ones found
    (accident or not, and h1 where the sweep needs it) is written to ``validation.ckpt``, so a
    resumed run goes on after the last finished slice. Results do not depend on the slicing."""
    if run.done("validation"):
        return run.state["done"]["validation"]
    t0 = time.perf_counter()
    assert run.scenario is not None and run.original is not None
    variants = perturbed_variants(run.scenario, run.cfg.validation_variants, run.cfg.seed)
    n = len(variants)
    stronger = stronger_fixes(fix, run.cyber_space(module)) if n else []
    configs = [params_tuple(fix)] + [params_tuple(values) for _, values in stronger]
    tasks = [VariantTask(v, (), v.seed) for v in variants] + \
        [VariantTask(v, configs[0], v.seed) for v in variants]
    for params in configs[1:]:
        tasks.append(VariantTask(run.scenario, params, run.scenario.seed))
        tasks += [VariantTask(v, params, v.seed) for v in variants]
    on_accident = [2 * n + k * (n + 1) for k in range(len(stronger))]  # each stronger value's first
    horizon = run.h1_horizon
    ckpt = run.out / "validation.ckpt"
    found = _validation_checkpoint(ckpt, fix, len(tasks))
    step = run.cfg.batch_size * VALIDATION_SLICE_BATCHES * max(1, getattr(run.executor, "workers", 1))
    while True:
        start = len(found["accident"])
        run.progress("validation", {"variants": n, "simulations": len(tasks), "evaluations": start})
        if start == len(tasks):
            break
        for i, r in enumerate(evaluate(run.executor, tasks[start:start + step], run.cfg.batch_size),
                              start):
            found["accident"].append(is_accident(r.outcome))
            if i in on_accident:
                found["h1_m2"][str(i)] = ego_dissimilarity(run.original.ego_xy, r.ego_xy, horizon)
        write_text_atomic(ckpt, json.dumps(found))
    accident = found["accident"]

    def rate(first: int) -> float:
        return sum(not a for a in accident[first:first + n]) / n

    ok_orig, ok_fixed = (rate(0), rate(n)) if n else (None, None)
    sweep = []
    for (f, values), first in zip(stronger, on_accident, strict=True):
        sweep.append({"fraction": f, "fix": values, "avoids_accident": not accident[first],
                      "h1_m2": round(found["h1_m2"][str(first)], 6), "success_rate": rate(first + 1)})
    result = {"variants": n, "success_rate_original": ok_orig, "success_rate_fixed": ok_fixed,
              "fix_makes_it_worse": bool(n and ok_fixed < ok_orig),  # type: ignore[operator]
              "stronger": sweep, "robust_fix": _robust(ok_fixed, sweep, run.cfg.h1_limit_m2)}
    write_text_atomic(run.out / "validation.json", json.dumps(result, indent=1))
    run.finish("validation", result, time.perf_counter() - t0, len(tasks))
    ckpt.unlink(missing_ok=True)
    return result


def _validation_checkpoint(path: Path, fix: Mapping[str, float], simulations: int) -> dict[str, Any]:
    """What the finished slices of phase V found, in task order (``accident``: one flag per
    simulation; ``h1_m2``: task index -> h1 of the stronger values' runs on the accident); empty
    when there is no checkpoint, or one of another fix or size (then it is started afresh)."""
    fresh = {"fix": dict(fix), "simulations": simulations, "accident": [], "h1_m2": {}}
    if not path.exists():
        return fresh
    try:
        saved = json.loads(path.read_text())
    except (OSError, ValueError):
        return fresh
    if not isinstance(saved, dict) or saved.get("fix") != fresh["fix"] \
            or saved.get("simulations") != simulations:
        return fresh
    return saved


def _robust(fixed_rate: float | None, sweep: list[dict[str, Any]], h1_limit: float
            ) -> dict[str, Any] | None:
    """The value closest to the minimal fix whose success rate is within ROBUST_TOLERANCE of the
    best rate among it and the stronger values that still avoid the accident and keep the ego's
    earlier trajectory; None when that is the minimal fix itself (no stronger value avoids
    clearly more variants)."""
    if fixed_rate is None:
        return None
    valid = [s for s in sweep if s["avoids_accident"] and s["h1_m2"] <= h1_limit]
    best = max([fixed_rate] + [s["success_rate"] for s in valid])
    if best < fixed_rate + ROBUST_TOLERANCE:
        return None
    pick = next(s for s in valid if s["success_rate"] >= best - ROBUST_TOLERANCE)
    return {"fix": pick["fix"], "success_rate": pick["success_rate"], "fraction": pick["fraction"]}


# -- orchestration ---------------------------------------------------------------------------
def _gen_info(s: GenerationStats, second: str) -> dict[str, Any]:
    """A generation for the progress bars and the run directory. ``best_feasible`` is the
    smallest second objective among its accident-free members, and ``best_objective`` names
    that objective (``second``): f2 (how unlike the original the world became) in the physical
    search, h2 (how large the fix) in the cyber one."""
    obj = np.asarray(s.objectives, dtype=float)
    feas = np.asarray(s.constraints) <= 0
    best = (float(np.min(obj[feas, 1])) if obj.ndim == 2 and obj.shape[1] > 1 and len(feas) == len(obj)
            and feas.any() else None)
    return {"generation": s.generation, "evaluations": s.evaluations, "feasible": s.feasible,
            "best_constraint": s.best_constraint, "best_feasible": best, "best_objective": second}


def _gen_json(s: GenerationStats, second: str) -> dict[str, Any]:
    return {**_gen_info(s, second), "objectives": s.objectives.tolist(),
            "constraints": s.constraints.tolist()}


def _cand_json(c: Candidate) -> dict[str, Any]:
    return {"mutation": dict(c.mutation.values), "objectives": list(c.objectives),
            "constraint": c.constraint, "generation": c.generation}


def analyze(
    source: str | os.PathLike[str] | Scenario,
    out: str | os.PathLike[str],
    cfg: AnalyzeConfig = AnalyzeConfig(),
    *,
    resume: bool = False,
    progress: Progress = _noop,
    executor: Executor | None = None,
) -> dict[str, Any]:
    """Run (or resume) the whole analysis; returns the report object (``--json``).

    Args:
        source: an accident recording (replayed) or a Scenario (simulated as the accident).
        out: the run directory.
        cfg: settings.
        resume: continue the analysis already in ``out``.
        progress: ``progress(phase, info)`` called as the phases advance.
        executor: an executor to use instead of ``cfg.executor``/``cfg.workers``.
    """
    out = Path(out)
    scenario = source if isinstance(source, Scenario) else None
    recording = None if scenario is not None else Path(source)  # type: ignore[arg-type]
    label, digest = source_identity(source)
    own = executor is None
    ex = executor if executor is not None else make_executor(cfg.executor, cfg.workers)
    # the folders this call makes: removed again if nothing was finished in them
    made = [d for d in (out, *out.parents) if not d.exists()]
    state: dict[str, Any] = {"done": {}}
    try:
        state = prepare_run_dir(out, resume, label, cfg, digest)
        return _analyze(_Run(out, cfg, ex, progress, state), scenario, recording)
    except BaseException:
        if not state["done"]:  # the run's state, which each finished phase adds to
            _remove_if_empty(made)
        raise
    finally:
        if own:
            ex.close()


def _remove_if_empty(folders: list[Path]) -> None:
    """Remove ``folders`` (deepest first) where they are empty; never anything else."""
    for d in folders:
        try:
            d.rmdir()
        except OSError:
            return


def _analyze(run: _Run, scenario: Scenario | None, recording: Path | None) -> dict[str, Any]:
    from rocas.pipeline.report import build_report, write_report

    run.progress("replay", {})
    _phase_replay(run, scenario, recording)
    replay = run.state["done"]["replay"]
    if not replay["reproduced"] or run.accident is None:
        return write_report(run.out, build_report(run.state, run.accident, "not_reproduced"))
    physical = _phase_physical(run)
    if "chosen" not in physical:
        return write_report(run.out, build_report(run.state, run.accident, "no_reference"))
    run.progress("diff", {})
    diff = _phase_diff(run)
    cyber = _phase_cyber(run, diff["deviating_module"])
    if "fix" not in cyber:
        return write_report(run.out, build_report(run.state, run.accident, "no_configuration_fix"))
    _phase_validation(run, cyber["fix"], diff["deviating_module"])
    return write_report(run.out, build_report(run.state, run.accident, "misconfiguration"))

