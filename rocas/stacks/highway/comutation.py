"""Co-mutation in highway-env: physical search, diff, cyber search, validation.

1. **Physical**: a genetic search (:func:`rocas.search.run_search`) over the scene's other
   vehicles (position on the lane, speed, target speed, class) for a near-identical scene in
   which the ego, driven by the same parameters, has no accident: the reference.
2. **Diff**: the accident and the reference are recorded and compared with
   :func:`rocas.analysis.diff`; the walk from the control channel names the initial deviating
   module.
3. **Cyber**: first the counterfactual of each departure from the driver's declared defaults
   (that parameter alone back at its default: one run each, whatever module it belongs to),
   then a search over the named module's parameters (bounded by their ParamSpec ranges) on
   the accident scene, screened one parameter at a time first; the best few fixes are shrunk
   (fewest parameters, then smallest changes) and, among those with the fewest parameters,
   one that undoes a departure ranks first, then the one whose drive departs least from the
   accident's (then the smallest change); a parameter that repairs when moved either way
   ranks last.
4. **Validation**: every shrunk fix on seeded variants of the accident scene that still
   crash; the fix that avoids the accident on the most of them is the answer.

Budgets are counted in simulations; simulations run on ``rocas.search.executor`` workers.
"""

from __future__ import annotations

import math
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from rocas.errors import NotReproducedError
from rocas.search import Mutation, MutationSpace, SearchConfig, Variable, run_search
from rocas.search.executor import Executor, SerialExecutor
from rocas.search.minimize import shrink_all_magnitudes, shrink_sets
from rocas.search.objectives import ego_dissimilarity
from rocas.stacks.highway.params import parameters
from rocas.stacks.highway.scene import KINDS, Scene
from rocas.stacks.highway.substitution import SubstitutionOpinion, SubstitutionRun, judge
from rocas.stacks.highway.world import RunResult, avoids, simulate

SimTask = tuple[Scene, tuple[tuple[str, float], ...], int]
#: fixes with distinct parameter sets and directions shrunk before the smallest is chosen
SHRINK_CANDIDATES = 6
#: other references the confidence diffs the accident against (beside the chosen one)
ALTERNATE_REFERENCES = 2
#: a fix must keep the ego this far from everything [m]: one that shaves the accident into a
#: near miss has repaired nothing (and shrinking would stop at the first miss by millimetres)
FIX_MARGIN_M = 0.5


def run_task(task: SimTask | tuple[Scene, tuple[tuple[str, float], ...], int, str]
             ) -> RunResult:
    """One simulation (module level, so worker processes and Ray can run it); a fourth item
    names the module replaced by its ideal counterpart
    (:func:`rocas.stacks.highway.world.build`)."""
    scene, params, seed, *substitute = task
    return simulate(scene, dict(params), seed, substitute=substitute[0] if substitute else None)


@dataclass(frozen=True)
class Budget:
    """Simulations each phase may spend (a search may stop earlier)."""

    physical_population: int = 12
    physical_generations: int = 3
    cyber_population: int = 12
    cyber_generations: int = 2
    validation_variants: int = 6


@dataclass(frozen=True)
class Analysis:
    """What the co-mutation found for one accident.

    Attributes:
        accident: the accident run; reference: the physical search's reference (None if none).
        reference_change: what the reference changes in the scene.
        deviating_module: the diff's initial deviating module (None without a reference).
        searched_module: whose parameters the cyber search changed ("driver": all of them).
        fix: parameter full name -> value (empty when no fix was found).
        alternatives: the other shrunk fixes, smallest change first.
        fix_run: the accident scene with the fix (None without a fix).
        reference_modules: the diff's module against the chosen reference, then against each
            other reference of the confidence (empty without a reference).
        substitution: module substitution's second opinion (ideal control;
            :mod:`rocas.stacks.highway.substitution`), which needs no reference.
        validated: variants whose accident the fix's claim avoids (:func:`claim`: an undoing
            of departures with them undone; :func:`avoids`), of ``variants`` that crash
            unfixed.
        seconds: wall time per phase (physical, diff, cyber, validation).
        simulations: simulations per phase (physical, with the accident's own run; diff, the
            two recorded runs; cyber; validation).
    """

    accident: RunResult
    reference: RunResult | None
    reference_change: Mapping[str, object]
    deviating_module: str | None
    searched_module: str | None
    fix: Mapping[str, float]
    alternatives: tuple[Mapping[str, float], ...]
    fix_run: RunResult | None
    reference_modules: tuple[str | None, ...]
    substitution: SubstitutionOpinion | None
    validated: int
    variants: int
    seconds: Mapping[str, float]
    simulations: Mapping[str, int]

    @property
    def module(self) -> str | None:
        """The answer's deviating module: the diff's, revised to the fix's module when the fix
        changes one module's parameters and the diff named another (its walk ended at a module
        without parameters, or the named module's own parameters held no fix), as the
        built-in pipeline's cyber phase revises the diff's module for a second suspect's fix."""
        owners = {name.split(".", 1)[0] for name in self.fix}
        if len(owners) == 1 and self.deviating_module not in owners:
            return owners.pop()
        return self.deviating_module

    @property
    def agreement(self) -> Mapping[str, object] | None:
        """How many of the references' diffs name the answer's module (``module``: the
        diff's, or the fix's when it was revised): ``{"module", "runs", "same"}``, None
        without a reference."""
        if not self.reference_modules:
            return None
        return {"module": self.module, "runs": len(self.reference_modules),
                "same": sum(m == self.module for m in self.reference_modules)}

    @property
    def stance(self) -> str | None:
        """Module substitution's stance on the answer's module (agrees, consistent,
        disagrees, undetermined; :meth:`SubstitutionOpinion.stance`), None if not asked."""
        return None if self.substitution is None else self.substitution.stance(self.module)

    @property
    def confidence(self) -> str | None:
        """stable / contested / unstable by the built-in pipeline's rule
        (:func:`rocas.pipeline.confidence.level`): more than half of the references' diffs
        name the answer's module, and module substitution supports it; one of the two; neither.
        None when neither was asked (no reference and no substitution)."""
        from rocas.pipeline.confidence import level

        agree = self.agreement or {"runs": 0, "same": 0}
        if self.agreement is None and self.substitution is None:
            return None
        return level(dict(agree), self.stance)

    def summary(self) -> str:
        s, n = self.seconds, self.simulations
        fix = ", ".join(f"{k}={v:.3g}" for k, v in sorted(self.fix.items())) or "none"
        others = "; ".join(", ".join(f"{k}={v:.3g}" for k, v in sorted(a.items()))
                           for a in self.alternatives) or "none"
        agree = self.agreement
        refs = f", {agree['same']}/{agree['runs']} references name it" if agree else ""
        if self.stance is not None:
            refs += f", substitution {self.stance}"
        if self.confidence is not None:
            refs += f": {self.confidence}"
        return (f"{self.accident.scene.name}: module {self.module}{refs} (diff "
                f"{self.deviating_module}, searched {self.searched_module}); fix {fix} "
                f"(other fixes: {others}); validated "
                f"{self.validated}/{self.variants}\n  time physical {s['physical']:.1f} s, diff "
                f"{s['diff']:.1f} s, cyber {s['cyber']:.1f} s, validation "
                f"{s['validation']:.1f} s; simulations {sum(n.values())} (physical "
                f"{n['physical']}, diff {n['diff']}, cyber {n['cyber']}, validation "
                f"{n['validation']})")


def physical_space(scene: Scene) -> MutationSpace:
    """Each other vehicle's lane position (+-15 m), speed and target speed (+-4 m/s) and
    class."""
    out: list[Variable] = []
    for i, v in enumerate(scene.others, start=1):
        target = v.speed_mps if v.target_speed_mps is None else v.target_speed_mps
        out += [Variable(f"v{i}.s", f"v{i}", "real", v.s_m, v.s_m - 15.0, v.s_m + 15.0, unit="m"),
                Variable(f"v{i}.speed", f"v{i}", "real", v.speed_mps, max(0.0, v.speed_mps - 4),
                         v.speed_mps + 4, unit="m/s"),
                Variable(f"v{i}.target_speed", f"v{i}", "real", target, max(0.0, target - 4),
                         target + 4, unit="m/s"),
                Variable(f"v{i}.kind", f"v{i}", "enum", v.kind, choices=KINDS)]
    return MutationSpace(tuple(out))


def apply_physical(scene: Scene, m: Mutation) -> Scene:
    """The scene with a physical mutation applied."""
    others = list(scene.others)
    fields = {"s": "s_m", "speed": "speed_mps", "target_speed": "target_speed_mps",
              "kind": "kind"}
    for name, value in m.values.items():
        who, prop = name.split(".", 1)
        i = int(who[1:]) - 1
        others[i] = replace(others[i], **{fields[prop]: value})
    return replace(scene, others=tuple(others))


def cyber_space(module: str, current: Mapping[str, float]) -> MutationSpace:
    """The module's parameters (every driver parameter for ``"driver"``) over their ParamSpec
    ranges, from their current values; the stack's braking and margin limits may only rise
    and its comfort limits may only grow in magnitude
    (:class:`rocas.stacks.highway.stack.HighwayStack`)."""
    from rocas.stacks.highway.stack import HighwayStack

    floors = {*HighwayStack.braking_limits, *HighwayStack.margin_limits}
    comfort = set(HighwayStack.comfort_limits)
    out = []
    for p in parameters():
        if module not in (p.module, "driver"):
            continue
        value = float(current.get(p.full_name, p.default))
        low, high = p.low, p.high
        if p.full_name in floors or (p.full_name in comfort and value >= 0):
            low = max(p.low, value)
        elif p.full_name in comfort:
            high = min(p.high, value)  # a deceleration: its magnitude may grow, not shrink
        out.append(Variable(p.full_name, p.module, "real", value, low, high, unit=p.unit))
    return MutationSpace(tuple(out))


class _Runner:
    """Counts simulations and maps them over an executor."""

    def __init__(self, executor: Executor) -> None:
        self.executor = executor
        self.count = 0

    def runs(self, tasks: Sequence[SimTask], substitute: str | None = None
             ) -> list[RunResult]:
        self.count += len(tasks)
        # the substitute rides in the task: an executor maps one module-level function
        return self.executor.map(run_task, [t if substitute is None else (*t, substitute)
                                            for t in tasks])


def _until(accident: RunResult) -> int:
    return max(1, len(accident.times) - 1)


def _physical(accident: RunResult, params: tuple[tuple[str, float], ...], runner: _Runner,
              budget: Budget, seed: int
              ) -> tuple[RunResult | None, Mutation, tuple[Scene, ...]]:
    """The reference (None without one), its change, and up to ALTERNATE_REFERENCES other
    references' scenes for the confidence."""
    scene = accident.scene
    space = physical_space(scene)
    until = _until(accident)

    def evaluate(ms: list[Mutation]) -> list[tuple[tuple[float, ...], float]]:
        runs = runner.runs([(apply_physical(scene, m), params, accident.seed) for m in ms])
        return [((space.distance(m), ego_dissimilarity(accident.ego[:, :2], r.ego[:, :2], until)),
                 r.constraint()) for m, r in zip(ms, runs, strict=True)]

    cfg = SearchConfig(population=budget.physical_population,
                       generations=budget.physical_generations, seed=seed,
                       single_property_share=0.5, stop_when_feasible_after=1)
    result = run_search(space, evaluate, cfg, 2)
    if not result.feasible:
        return None, Mutation(), ()
    ranked = sorted(result.feasible, key=lambda c: (c.objectives[0], c.objectives[1]))
    best = ranked[0]
    # the confidence's other references: the best candidates that change another set of
    # properties than the chosen one and than each other (independent views of the accident)
    seen, others = {best.mutation.names}, []
    for c in ranked[1:]:
        if c.mutation.names not in seen and len(others) < ALTERNATE_REFERENCES:
            seen.add(c.mutation.names)
            others.append(apply_physical(scene, c.mutation))
    ref_scene = apply_physical(scene, best.mutation)
    return runner.runs([(ref_scene, params, accident.seed)])[0], best.mutation, tuple(others)


def _diff_references(scene: Scene, references: Sequence[Scene], params: Mapping[str, float],
                     seed: int) -> tuple[str | None, ...]:
    """The diff's deviating module of the accident against each reference scene (recorded
    into a temporary folder, removed after)."""
    from rocas.analysis.diff import diff
    from rocas.stacks.highway.record import record

    with tempfile.TemporaryDirectory(prefix="rocas-highway-") as tmp:
        a = Path(tmp, "accident.mcap")
        record(scene, a, dict(params), seed)
        modules = []
        for i, ref in enumerate(references):
            b = Path(tmp, f"reference_{i}.mcap")
            record(ref, b, dict(params), seed)
            # both are this world's simulations of one scene by construction: a reference
            # that moved a vehicle differs from the first tick, which the diff's check for
            # unrelated files (made for logs it is handed) would refuse
            modules.append(diff(a, b, allow_unrelated=True).deviating_module)
    return tuple(modules)


def quarter_points(space: MutationSpace) -> list[Mutation]:
    """Each variable alone a quarter and three quarters of the way from its original value to
    each end of its range (the screening's halfway points and ends lie between)."""
    out = []
    for var in space.variables:
        u0 = var.encode(var.original)
        for end in (0.0, 1.0):
            for share in (0.25, 0.75):
                m = Mutation({var.name: var.decode(u0 + share * (end - u0))})
                if var.change(m.values[var.name]) > 0:
                    out.append(m)
    return list(dict.fromkeys(out))


def defaults() -> dict[str, float]:
    """The driver's declared parameter values (highway-env's own class constants)."""
    return {p.full_name: p.default for p in parameters()}


def _departs(value: float, default: float) -> bool:
    return not math.isclose(value, default, rel_tol=1e-9, abs_tol=1e-12)


def restores(m: Mutation, current: Mapping[str, float]) -> bool:
    """Every parameter ``m`` changes departs from its declared default and moves back towards
    it (not past it): the fix undoes a departure rather than retuning a default."""
    home = defaults()
    for n, v in m.values.items():
        d, c = home[n], current.get(n, home[n])
        if not _departs(c, d) or not min(c, d) <= float(v) <= max(c, d):
            return False
    return True


def restorations(space: MutationSpace, current: Mapping[str, float]) -> list[Mutation]:
    """Each departure from the declared defaults undone alone: the counterfactual "had this
    parameter kept its default", for every departed parameter whose default the space admits
    (a braking floor forbids restoring a stronger brake downwards)."""
    home = defaults()
    out = []
    for var in space.variables:
        d, c = home[var.name], float(current.get(var.name, home[var.name]))
        if _departs(c, d) and var.low <= d <= var.high:
            out.append(Mutation({var.name: d}))
    return out


def _shrink_candidates(found: Sequence[tuple[Mutation, tuple[float, ...]]],
                       current: Mapping[str, float]) -> list[Mutation]:
    """The fixes worth shrinking: per parameter set and direction the least change that
    repairs, and of those the SHRINK_CANDIDATES with the fewest parameters, those that undo a
    departure from the defaults first, whose drive departs least from the accident's
    (objectives: change, dissimilarity)."""
    least: dict[tuple[tuple[str, bool], ...], tuple[Mutation, tuple[float, ...]]] = {}
    for m, obj in sorted(found, key=lambda f: (f[1][0], f[1][1], f[0].names)):
        key = tuple((n, float(v) > current.get(n, 0.0)) for n, v in sorted(m.values.items()))
        least.setdefault(key, (m, obj))
    ranked = sorted(least.values(), key=lambda f: (len(f[0].values), not restores(f[0], current),
                                                   f[1][1], f[1][0], f[0].names))
    return [m for m, _ in ranked[:SHRINK_CANDIDATES]]


def _cyber(accident: RunResult, module: str, runner: _Runner, budget: Budget, seed: int,
           undo: bool = True) -> list[dict[str, float]]:
    """The shrunk fixes, smallest change first (empty when none avoids the accident);
    ``undo``: try the undoing of each departure first (a search of the whole driver after a
    module's search found nothing need not: its undoings were tried and none repaired)."""
    current = dict(accident.params)
    searched = cyber_space(module, current)
    # the driver's whole space measures and shrinks every fix: the counterfactual restorations
    # reach parameters of every module, the search only the named module's
    space = cyber_space("driver", current)
    until = _until(accident)

    def tasks(ms: list[Mutation]) -> list[SimTask]:
        return [(accident.scene, tuple(sorted({**current, **m.values}.items())), accident.seed)
                for m in ms]

    def evaluate(ms: list[Mutation]) -> list[tuple[tuple[float, ...], float]]:
        runs = runner.runs(tasks(ms))
        return [((space.distance(m), ego_dissimilarity(accident.ego[:, :2], r.ego[:, :2], until)),
                 r.constraint()) for m, r in zip(ms, runs, strict=True)]

    # the counterfactual of each departure from the defaults first (one run each): an
    # accident that a departure's undoing avoids is explained by that departure
    back = restorations(space, current) if undo else []
    found = [(m, objectives) for m, (objectives, constraint)
             in zip(back, evaluate(back), strict=True) if constraint <= 0]
    if searched.variables:
        cfg = SearchConfig(population=budget.cyber_population,
                           generations=budget.cyber_generations, seed=seed, screen=True,
                           stop_when_feasible_after=1)
        result = run_search(searched, evaluate, cfg, 2,
                            screening_suffices=lambda cs: any(c.feasible for c in cs))
        # the screening tries each parameter at its range's ends and halfway to them; a fix
        # that lies between (a heading gain that repairs from 20 /s only below 7 /s, and
        # overshoots at 0.5 /s) is found by the quarter points, one parameter at a time
        scan = quarter_points(searched)
        found += [(c.mutation, c.objectives) for c in result.feasible]
        found += [(m, objectives) for m, (objectives, constraint)
                  in zip(scan, evaluate(scan), strict=True) if constraint <= 0]
    if not found:
        return []
    candidates = _shrink_candidates(found, current)

    def repairs(r: RunResult) -> bool:
        return not r.accident and r.min_margin_m >= FIX_MARGIN_M

    def holds(trials: list[tuple[int, Mutation]]) -> list[bool]:
        return [repairs(r) for r in runner.runs(tasks([m for _, m in trials]))]

    smalls, _ = shrink_sets(candidates, holds)
    smalls, _ = shrink_all_magnitudes(smalls, space, holds)
    runs = {id(m): r for m, r in zip(smalls, runner.runs(tasks(smalls)), strict=True)}
    # the ranking of the repairing fixes, fewest parameters first:
    # 1. one that undoes a departure from the declared defaults, before one that retunes a
    #    parameter the configuration left at its default: both avoid the accident, but only
    #    the first names something the configuration changed (a stiffer lateral gain also
    #    damps the oscillation an over-tuned heading gain causes; the heading gain is what
    #    was changed), whatever else of the parameter's range happens to repair too;
    # 2. a parameter that repairs when moved either way after the rest: the accident hangs on
    #    its exact value (MOBIL's decision phase at the ramp's end), not on it being too high
    #    or too low, so no direction of it is the cause;
    # 3. the counterfactual closest to the accident: the drive that departs least from the
    #    accident's (the paper's second objective), then the smallest change. A change that is
    #    small in its parameter's range may still remake the drive; the shrunk fixes all lie at
    #    their repair's edge, so their sizes say less than what they do to the drive
    fixed = [m for m in dict.fromkeys(smalls) if repairs(runs[id(m)])]
    ways = {(n, float(v) > current.get(n, 0.0)) for m in fixed for n, v in m.values.items()}

    def two_way(m: Mutation) -> bool:
        return any((n, float(v) <= current.get(n, 0.0)) in ways for n, v in m.values.items())

    ranked = sorted(dict.fromkeys(smalls), key=lambda m: (
        not repairs(runs[id(m)]), len(m.values), not restores(m, current), two_way(m),
        ego_dissimilarity(accident.ego[:, :2], runs[id(m)].ego[:, :2], until),
        space.distance(m), m.names))
    return [{k: float(v) for k, v in m.values.items()} for m in ranked]


def claim(fix: Mapping[str, float], current: Mapping[str, float]) -> dict[str, float]:
    """What validation tries of a fix: a fix that undoes departures from the defaults
    (:func:`restores`) claims the departures caused the accident, so its parameters go back to
    their defaults; any other fix claims its values avoid it, and is tried as it is. (The
    shrunk undoing lies at the edge of what repairs this one scene; the variants ask whether
    the departure, not that edge, is the cause.)"""
    if not restores(Mutation(dict(fix)), current):
        return dict(fix)
    home = defaults()
    return {n: home[n] for n in fix}


def scene_variants(scene: Scene, count: int, seed: int) -> list[Scene]:
    """Seeded small perturbations of the other vehicles (+-2 m, +-0.5 m/s)."""
    rng = np.random.default_rng([seed, 3939])
    out = []
    for _ in range(count):
        others = tuple(replace(o, s_m=o.s_m + float(rng.uniform(-2, 2)),
                               speed_mps=max(0.0, o.speed_mps + float(rng.uniform(-0.5, 0.5))))
                       for o in scene.others)
        out.append(replace(scene, others=others))
    return out


def analyze(scene: Scene, params: Mapping[str, float] | None = None, seed: int = 0, *,
            executor: Executor | None = None, budget: Budget = Budget(),
            search_seed: int | None = None) -> Analysis:
    """The co-mutation on one accident (``scene`` with the ego parameters ``params``, simulated
    at ``seed``); ``search_seed`` seeds the searches and the validation variants (default
    ``seed``), so one recorded accident can be analysed at several seeds.

    Raises:
        NotReproducedError: the scene has no accident with these parameters.
    """
    runner = _Runner(executor or SerialExecutor())
    p = tuple(sorted((params or {}).items()))
    t0 = time.perf_counter()
    accident = runner.runs([(scene, p, seed)])[0]
    if not accident.accident:
        raise NotReproducedError(f"{scene.name}: no accident at seed {seed} with these "
                                 "parameters", "check the scene and the parameters")
    secs: dict[str, float] = {}
    sims: dict[str, int] = {}
    sseed = seed if search_seed is None else search_seed
    reference, change, others = _physical(accident, p, runner, budget, sseed)
    secs["physical"], sims["physical"] = time.perf_counter() - t0, runner.count
    t0 = time.perf_counter()
    modules: tuple[str | None, ...] = ()
    if reference is not None:
        modules = _diff_references(scene, (reference.scene, *others), dict(p), seed)
    module = modules[0] if modules else None
    # module substitution's second opinion needs no reference: the accident with ideal control
    ideal = runner.runs([(scene, p, seed)], substitute="control")[0]
    opinion = judge(SubstitutionRun.of((), accident), SubstitutionRun.of(("control",), ideal))
    secs["diff"] = time.perf_counter() - t0
    sims["diff"] = len(modules) + bool(modules) + 1
    # perception, the vehicle and the world have no parameters: a walk that ends there (the
    # reference changed the traffic, which the driver perceives exactly) leaves the search to
    # every driver parameter; so does a named module whose own parameters hold no fix
    searched = module if module in ("planning", "control") else "driver"
    t0, before = time.perf_counter(), runner.count
    fixes = _cyber(accident, searched, runner, budget, sseed)
    if searched != "driver" and not fixes:
        searched = "driver"
        fixes = _cyber(accident, searched, runner, budget, sseed, undo=False)
    fix: dict[str, float] = {}
    secs["cyber"], sims["cyber"] = time.perf_counter() - t0, runner.count - before
    t0, before = time.perf_counter(), runner.count
    fix_run, validated, variants = None, 0, 0
    if fixes:
        # the variants that still crash unfixed; each shrunk fix's claim is tried on them and
        # the one that avoids the most wins (ties: the ranking): a fix that only shifted a
        # decision's timing in this one scene rarely survives them
        vs = scene_variants(scene, budget.validation_variants, sseed)
        unfixed = runner.runs([(v, p, seed) for v in vs])
        crashing = [v for v, r in zip(vs, unfixed, strict=True) if r.accident]
        crashed = [r for r in unfixed if r.accident]
        variants = len(crashing)
        tried = runner.runs([(v, tuple(sorted({**dict(p), **claim(f, dict(p))}.items())), seed)
                             for f in fixes for v in crashing])
        n = len(crashing)
        scores = [sum(avoids(r, u) for r, u in zip(tried[i * n:(i + 1) * n], crashed,
                                                    strict=True))
                  for i in range(len(fixes))]
        best = max(range(len(fixes)), key=lambda i: (scores[i], -i))
        fixes = [fixes[best], *fixes[:best], *fixes[best + 1:]]
        fix, validated = fixes[0], scores[best]
        fix_run = runner.runs([(scene, tuple(sorted({**dict(p), **fix}.items())), seed)])[0]
    secs["validation"], sims["validation"] = time.perf_counter() - t0, runner.count - before
    return Analysis(accident, reference, dict(change.values), module, searched, fix,
                    tuple(fixes[1:]), fix_run, modules, opinion,
                    validated, variants, secs, sims)
