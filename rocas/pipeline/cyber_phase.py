"""Phase IV: the cyber search over the deviating module's parameters, then minimisation."""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from rocas._fs import write_text_atomic
from rocas.pipeline.common import Scores, cand_json, gen_info, gen_json
from rocas.pipeline.config import planned_simulations, screening_simulations
from rocas.pipeline.evaluate import (
    VariantResult,
    VariantTask,
    batches_of,
    evaluate,
    params_tuple,
    run_batch,
    violation,
)
from rocas.pipeline.results import (
    AlternativeFix,
    ConfidenceResult,
    CyberResult,
    ModuleRevision,
    OtherFix,
    ParameterChange,
    ShrunkFix,
)
from rocas.pipeline.rundir import Run
from rocas.scenarios.model import Scenario
from rocas.search.executor import submit
from rocas.search.ga import Candidate, SearchResult, run_search, screening_mutations
from rocas.search.minimize import shrink_all_magnitudes, shrink_sets
from rocas.search.objectives import ego_dissimilarity
from rocas.search.space import Mutation, MutationSpace


def phase_cyber(run: Run, module: str | None) -> CyberResult:
    """Search ``module``'s parameters (every module's with ``--scope all``) for the smallest
    fix, then, when none fixes the accident, the parameters of the module module substitution
    names (:func:`second_suspect`). Returns the phase's result (``fix`` and
    ``misconfiguration`` when one was found; ``named_module`` and a revision of the deviating
    module when the fix is the second suspect's)."""
    done = run.get(CyberResult)
    if done is not None:
        return done
    t0 = time.perf_counter()
    result, evaluations = _search_fix(run, module, run.out / "cyber.ckpt")
    suspect = second_suspect(run, module)
    if result.fix is None and suspect is not None:
        assert module is not None
        second, more = _search_fix(run, suspect, run.out / "cyber_suspect.ckpt")
        evaluations += more
        if second.fix is not None:
            result = replace(second, named_module=module, named_module_search=result.summary(),
                             revision=_suspect_revision(run, module, suspect))
        else:
            result = replace(result, second_suspect=second.summary())
    write_text_atomic(run.out / "cyber.json", json.dumps(result.to_json(), indent=1))
    run.finish(result, time.perf_counter() - t0, evaluations)
    return result


def fix_tasks(scenario: Scenario, fixes: list[Mutation]) -> list[VariantTask]:
    """The accident ``scenario`` run once with each fix's parameter values."""
    return [VariantTask(scenario, params_tuple({k: float(v) for k, v in m.values.items()}),
                        scenario.seed) for m in fixes]


def start_screening(run: Run, module: str | None) -> None:
    """Start the cyber search's screening of ``module``'s parameters on the executor's workers
    (``run.ahead["cyber_screening"]``: its tasks and the futures of their batches) while the
    confidence phase runs in this process. The screening's mutants follow from the parameter
    space and the seed alone, so the search takes these results for its first batch when it
    asks for exactly these tasks; when the confidence phase makes another module the deviating
    one, the search asks for other tasks and this work is left unused (it ran on a core that
    would have been idle). Nothing is started with one worker, without screening, or for a
    search already under way (a checkpoint to resume from), nor when the diff names no module
    (the confidence phase then most often adopts another reference's, and the search over
    every module's parameters would be large)."""
    workers = max(1, getattr(run.executor, "workers", 1))
    if (module is None or workers == 1 or getattr(run.executor, "submit", None) is None
            or run.done("cyber") or (run.out / "cyber.ckpt").exists()):
        return
    scn = run.scenario
    assert scn is not None
    space = run.cyber_space(module)
    search = run.cfg.search(2, len(space.variables))
    if not search.screen:
        return
    tasks = fix_tasks(scn, screening_mutations(space, search.seed))
    if tasks:
        run.ahead["cyber_screening"] = (tasks, [submit(run.executor, run_batch, b) for b in
                                                batches_of(tasks, run.cfg.batch_size, workers)])


def second_suspect(run: Run, module: str | None) -> str | None:
    """The module whose parameters are searched when no configuration of ``module`` avoids the
    accident (``--scope module`` only; None when there is none):

    - the module module substitution names (its ground truth alone avoids the accident), when
      that is another module. Algorithm 1's module can be the wrong one in a way only the fix
      search shows: a creeping car whose forecast differs from its first message in the
      reference has no change point, and the walk ends at planning (a T-junction variant of
      A1). No planning parameter avoids the accident; substitution says ground-truth
      prediction does, and prediction's still-obstacle speed is the repair.
    - the module that reads ``module``'s output on the walk's path, when substitution names
      ``module`` itself: its perfect output would avoid the accident, no configuration of it
      does, so the repair is a margin of its consumer for the errors it cannot help (planning's
      margins for the forecast: a right-turning truck whose forecast cut the corner, a layout
      variant of A11).

    Accidents no configuration can avoid (A7's car from behind, A8's hedge) have no second
    suspect: substitution avoids nothing there."""
    conf = run.get(ConfidenceResult)
    opinion = conf.second_opinion if conf is not None else None
    if module is None or run.cfg.scope != "module" or opinion is None or not opinion.accident:
        return None
    suspect = opinion.module
    if suspect is None:
        return None
    if suspect != module:
        return suspect
    path = list(run.answer().path)
    i = path.index(module) if module in path else -1
    return path[i - 2] if i >= 2 else None


def _suspect_revision(run: Run, named: str, suspect: str) -> ModuleRevision:
    """The revision that makes ``suspect`` the analysis's deviating module: the reference's
    walk did not reach it, so the answer is at most contested (substitution supports it, the
    references do not; :func:`rocas.pipeline.confidence.with_suspect`)."""
    conf = run.get(ConfidenceResult)
    opinion = conf.second_opinion if conf is not None else None
    consumer = suspect != (opinion.module if opinion is not None else None)
    return ModuleRevision(by="cyber", reason="second_suspect", before=named, after=suspect,
                          path=(), reads_named=consumer)


class _FixTrials:
    """Runs the accident with candidate fixes and scores each (objectives h1 [m^2] and h2 [-],
    the accident's constraint), keeping each simulated fix's smallest gap to anything [m]
    (``separation``) and path length driven [m] (``driven``), for choosing among shrunk
    fixes."""

    def __init__(self, run: Run, space: MutationSpace) -> None:
        assert run.scenario is not None and run.original is not None
        self.run, self.space = run, space
        self.separation: dict[Mutation, float] = {}
        self.driven: dict[Mutation, float] = {}
        self.blocked = ended_blocked(run.original, run.scenario.dt_s)
        self.accident_driven = driven_m(run.original.ego_xy)

    def _simulate(self, ms: list[Mutation]) -> list[VariantResult]:
        run = self.run
        assert run.scenario is not None
        tasks = fix_tasks(run.scenario, ms)
        ahead = run.ahead.pop("cyber_screening", None)
        if ahead is not None and ahead[0] == tasks:  # the screening, started on a worker
            return [r for f in ahead[1] for r in f.result()]
        return evaluate(run.executor, tasks, run.cfg.batch_size)

    def batch(self, ms: list[Mutation]) -> list[tuple[tuple[float, ...], float]]:
        orig, horizon = self.run.original, self.run.h1_horizon
        assert orig is not None
        out = []
        for m, r in zip(ms, self._simulate(ms), strict=True):
            self.separation[m] = r.outcome.min_separation_m
            self.driven[m] = driven_m(r.ego_xy)
            out.append(((ego_dissimilarity(orig.ego_xy, r.ego_xy, horizon), self.space.distance(m)),
                        violation(r.outcome)))
        return out

    def stalls(self, m: Mutation) -> bool:
        """Whether fix ``m`` leaves the ego standing where the accident did (a search resumed
        from its checkpoint has no path lengths for its earlier generations: those count as
        getting past, as before this rule)."""
        return self.blocked and m in self.driven and self.driven[m] < self.accident_driven + PROGRESS_MARGIN_M

    def gap(self, m: Mutation) -> float | None:
        """The fix's smallest gap [m]; None when nothing was ever near (JSON has no infinity)."""
        return self.separation[m] if np.isfinite(self.separation[m]) else None


def _search_fix(run: Run, module: str | None, checkpoint: Path) -> tuple[CyberResult, int]:
    """The cyber search over ``module``'s parameters and the minimisation of its fixes:
    the result (``fix`` and ``misconfiguration`` when one was found) and the simulations run.

    A fix among the screened single parameters ends the search there: the fix is then chosen
    from what every seed screens alike (the genetic search runs only when none is a fix). A
    screened fix that leaves the ego standing where the accident left it is no repair: when
    every screened fix stalls, the genetic search runs too."""
    space = run.cyber_space(module)
    search = run.cfg.search(2, len(space.variables))
    screening = screening_simulations(space, search.seed) if search.screen else 0
    run.progress("cyber", {"planned": planned_simulations(search, screening)})
    trials = _FixTrials(run, space)
    limit = run.cfg.h1_limit_m2
    res = run_search(space, trials.batch, search, 2,
                     checkpoint=checkpoint,
                     on_generation=lambda s: run.progress("cyber", gen_info(s, "h2")),
                     screening_suffices=lambda cands: any(
                         c.feasible and c.objectives[0] <= limit and not trials.stalls(c.mutation)
                         for c in cands))
    fields: dict[str, Any] = {
        "module": module, "scope": run.cfg.scope, "parameters": len(space.variables),
        "generations": tuple(gen_json(g, "h2") for g in res.generations),
        "evaluations": res.evaluations, "feasible": len(res.feasible),
        "first_fix_evaluation": _first_fix(res, limit),
        "first_fix_batch_evaluations": _first_fix_batch(res, limit)}
    originals = {v.name: float(v.original) for v in space.variables}  # type: ignore[arg-type]
    candidates = _fix_candidates(res, limit, run.cfg.shrink_candidates, originals,
                                 stalled=trials.stalls)
    if search.screen and all(c.generation == 0 for c in res.candidates):
        # the screening decided: a screened fix sits at an end of its parameter's range or
        # halfway to one, so its size says nothing about which way that parameter gives the
        # smaller fix; the other direction of each candidate's parameter is shrunk too
        # (raising a margin, not only lowering it until the ego races ahead)
        candidates += _other_directions(res, candidates, limit, originals)
    nearest = _nearest_fix(res, limit)
    if nearest is not None:
        fields["nearest_fix"] = cand_json(nearest)
    evaluations = res.evaluations
    if candidates:
        minimised, simulated = _minimise(run, trials, res, candidates, originals)
        fields |= minimised
        evaluations += simulated
        # fixed.mcap (the accident with the fix) is recorded by phase V, as an extra row of its
        # first batch (rocas.pipeline.validation.record_fix)
    checkpoint.unlink(missing_ok=True)
    return CyberResult(**fields), evaluations


def _minimise(run: Run, trials: _FixTrials, res: SearchResult, candidates: list[Candidate],
              originals: Mapping[str, float]) -> tuple[dict[str, Any], int]:
    """Shrink each of the search's best fixes (set, then magnitudes) and choose the smallest
    shrunk fix (:func:`_smallest_fix`): the search ranks fixes by the size it happened to try.
    Returns the result's fields about the fix and the simulations the shrink ran."""
    space = trials.space
    run.progress("minimise", {"parameters": sum(len(c.mutation.values) for c in candidates)})
    # candidates often shrink through the same mutations, and the search has already
    # scored many of them; the candidates shrink in lockstep, one batch per round
    scores = Scores(trials.batch, res.candidates)
    limits = [max(run.cfg.h1_limit_m2, c.objectives[0]) for c in candidates]

    def holds(trial: list[tuple[int, Mutation]]) -> list[bool]:
        return [cons <= 0.0 and objs[0] <= limits[i]
                for (i, _), (objs, cons) in zip(trial, scores.of([m for _, m in trial]),
                                                strict=True)]

    smalls, _ = shrink_sets([c.mutation for c in candidates], holds)
    smalls, _ = shrink_all_magnitudes(smalls, space, holds)
    # every shrunk fix was simulated by the search or as a trial, and counted there; only a
    # search resumed from its checkpoint lacks the gaps of its earlier generations, and
    # re-running those is the resume's cost, not the analysis's (the report stays the same)
    unseen = [m for m in dict.fromkeys(smalls) if m not in trials.separation]
    if unseen:
        trials.batch(unseen)
    # with an accident that left the ego standing, a fix that drives it no farther only
    # softened the stop (ranked after the fixes that get it past)
    stalled = [trials.stalls(m) for m in smalls]
    h2 = [space.distance(m) for m in smalls]
    best, near = _smallest_fix(h2, smalls, separation=[trials.separation[m] for m in smalls],
                               originals=originals, stalled=stalled)

    def described(m: Mutation) -> tuple[ParameterChange, ...]:
        return tuple(ParameterChange(module=n.split(".", 1)[0], parameter=n,
                                     original=space.variable(n).original,  # type: ignore[arg-type]
                                     mutated=m.values[n]) for n in m.names)  # type: ignore[arg-type]

    return {
        "search_best": cand_json(candidates[best]),
        "minimise_evaluations": scores.simulated,
        "shrunk_candidates": tuple(
            ShrunkFix(search=cand_json(c), shrunk={k: float(v) for k, v in m.values.items()},
                      h2=round(d, 6), min_separation_m=trials.gap(m),
                      driven_m=round(trials.driven[m], 3), stalled=st)
            for c, m, d, st in zip(candidates, smalls, h2, stalled, strict=True)),
        "fix": {k: float(v) for k, v in smalls[best].values.items()},
        "misconfiguration": described(smalls[best]),
        "alternatives": tuple(AlternativeFix(h2=round(h2[i], 6), misconfiguration=described(smalls[i]))
                              for i in near),
        # the other shrunk fixes, larger than the tolerance: they avoid the accident too, and a
        # reader weighing the answer should see them (reported, never chosen)
        "other_fixes": tuple(
            OtherFix(h2=round(h2[i], 6), misconfiguration=described(smalls[i]),
                     min_separation_m=trials.gap(smalls[i]), stalled=stalled[i])
            for i in _other_fixes(h2, smalls, [best, *near], originals)),
    }, scores.simulated


#: h2 within which another shrunk fix is reported as an alternative (0.05: one parameter
#: moved 5 % of its range farther than the chosen fix)
ALTERNATIVE_H2_TOLERANCE = 0.05


def _smallest_fix(h2: list[float], fixes: list[Mutation],
                  tolerance: float = ALTERNATIVE_H2_TOLERANCE,
                  separation: list[float] | None = None,
                  originals: Mapping[str, float] | None = None,
                  stalled: list[bool] | None = None) -> tuple[int, list[int]]:
    """Index of the chosen shrunk fix, and the indices of the other fixes (other parameter
    sets, or the same parameters moved the other way) within ``tolerance`` of the smallest
    h2, in order: the same margin expressed in another parameter, or a second suspect.

    The smallest fix (h2, ties by parameter names) is chosen, unless another fix within
    ``tolerance`` of it keeps the ego clearly farther from everything (``separation``: the
    run's smallest gap to any actor or object [m]; SEPARATION_MARGIN_M more and
    SEPARATION_RATIO times as much): such changes are equally small, and the one that adds
    margin is the repair, not the one that avoids the accident narrowly (an overtake margin
    lowered until the ego races ahead of the truck: 3.9 m against 6.9 m). Two fixes that
    both pass at several metres (an A11 speed variant: the moving-obstacle check 0.5 -> 1.83 m
    keeps 6.0 m, the lateral buffer 0.3 -> 1.69 m 6.8 m) both add margin; the smaller stays.
    A fix that leaves the ego less than SCRAPE_M from anything ranks after every fix that
    does not, whatever its h2: the collision became a scrape, nothing was repaired (an A11
    variant: `idm_exponent` 4 -> 6.4, h2 1.34, passes the truck at 6 cm; the collision
    check, h2 1.42, keeps 6.1 m).

    A fix marked ``stalled`` (the accident left the ego standing, and this fix drives it no
    farther: :func:`ended_blocked`, PROGRESS_MARGIN_M) ranks after every fix that is not, and
    its gap never makes it the repair: it kept its distance by not driving. An A2 variant: the
    nudge look-ahead 40 -> 50 m (h2 1.11) turns the hard brake in front of the parked pair into
    a gentle stop there (5.8 m from both cars, 110 m driven like the accident run), while the
    static buffer 0.6 -> 0.33 m (h2 1.09, 0.42 m) takes the ego through the gap (154 m)."""
    def scrape(i: int) -> bool:
        return separation is not None and separation[i] < SCRAPE_M

    def stall(i: int) -> bool:
        return stalled is not None and stalled[i]

    order = sorted(range(len(fixes)), key=lambda i: (scrape(i), stall(i), h2[i], fixes[i].names))
    close = [i for i in order if h2[i] <= h2[order[0]] + tolerance]
    best = order[0]
    if separation is not None:
        widest = max((i for i in close if stall(i) <= stall(best)),
                     key=lambda i: (separation[i], -h2[i]))
        if separation[widest] >= max(separation[best] + SEPARATION_MARGIN_M,
                                     separation[best] * SEPARATION_RATIO):
            best = widest

    def kind(m: Mutation) -> Any:
        return m.names if originals is None else _direction(m, originals)

    return best, _new_kinds(close, fixes, [best], kind)


def _other_fixes(h2: list[float], fixes: list[Mutation], shown: list[int],
                 originals: Mapping[str, float]) -> list[int]:
    """Indices of the fixes not ``shown`` (the chosen one and its near alternatives), one per
    parameter set and direction not shown, smallest h2 first (ties by parameter names)."""
    order = sorted(range(len(fixes)), key=lambda i: (h2[i], fixes[i].names))
    return _new_kinds(order, fixes, shown, lambda m: _direction(m, originals))


def _new_kinds(order: list[int], fixes: list[Mutation], shown: list[int],
               kind: Callable[[Mutation], Any]) -> list[int]:
    """The indices in ``order`` whose fix is of a kind (``kind``) that neither the ``shown``
    fixes nor an earlier index has: the first fix of each other kind."""
    seen = {kind(fixes[i]) for i in shown}
    out = []
    for i in order:
        if kind(fixes[i]) not in seen:
            seen.add(kind(fixes[i]))
            out.append(i)
    return out


#: how much wider [m] an equally small fix must keep the ego's smallest gap to be preferred
SEPARATION_MARGIN_M = 0.5
#: and how many times as wide: a race won narrowly against a repair keeps a clearly smaller gap
#: (catalog A3 and its variants: 3.9 against 6.9 m, 4.5 against 7.0 m, ratios 1.56-1.77), two
#: margins raised alike keep similar gaps (an A11 variant: 6.0 and 6.8 m, ratio 1.14)
SEPARATION_RATIO = 1.25
#: a fix that leaves the ego closer than this [m] to any actor or object is a scrape (the
#: catalog's chosen fixes keep 0.43 m or more: A2's passes a parked car at 0.43 m)
SCRAPE_M = 0.25


#: a fix must drive the ego this much farther [m] than an accident run that left it standing
#: (A2's variants: a gentle stop in front of the parked pair drives 0-0.3 m less than the
#: accident, the repair 36-44 m more)
PROGRESS_MARGIN_M = 5.0
#: an accident run whose ego covered less than this [m] in its last second ended standing
STANDING_M = 2.0


def driven_m(ego_xy: np.ndarray) -> float:
    """Path length [m] of ego positions ``ego_xy`` (shape (T + 1, 2))."""
    steps = np.diff(np.asarray(ego_xy, dtype=float), axis=0)
    return float(np.sqrt(steps[:, 0] * steps[:, 0] + steps[:, 1] * steps[:, 1]).sum())


def ended_blocked(accident: VariantResult, dt_s: float) -> bool:
    """Whether the accident run left the ego standing: no collision, and its ego covered less
    than STANDING_M in the run's last second (an emergency stop it never drove on from). A
    collision run is excluded: there, waiting for the other actor can be the repair."""
    if accident.outcome.collided:
        return False
    k = max(1, int(round(1.0 / dt_s)))
    return driven_m(accident.ego_xy[-(k + 1):]) < STANDING_M


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
                    originals: Mapping[str, float] | None = None,
                    stalled: Callable[[Mutation], bool] | None = None) -> list[Candidate]:
    """The best ``count`` feasible fixes with distinct parameter sets or directions (up or
    down from ``originals``): those that keep the ego's earlier trajectory (h1 <= limit), by
    smallest change (h2). None when no fix keeps it: a configuration that avoids the accident
    only by driving differently before it is not a fix (:func:`_nearest_fix` records it).

    Fixes ``stalled`` marks (the ego stays standing where the accident left it) come after
    every other: :func:`_smallest_fix` ranks them last, so they would only take the places of
    fixes that get the ego past (an A2 actors variant: the headway, the nudge's largest offset
    and its look-ahead, all three a gentle stop in front of the parked pair, took the three
    places and the static buffer that takes the ego through the gap was never shrunk)."""
    originals = originals or {}
    keep = [c for c in res.feasible if c.objectives[0] <= h1_limit]
    out: list[Candidate] = []
    seen: set[tuple[tuple[str, int], ...]] = set()

    def stall(c: Candidate) -> bool:
        return stalled is not None and stalled(c.mutation)

    for c in sorted(keep, key=lambda c: (stall(c), c.objectives[1], c.objectives[0],
                                         c.mutation.names)):
        key = _direction(c.mutation, originals)
        if key not in seen:
            seen.add(key)
            out.append(c)
        if len(out) == count:
            break
    return out


def _other_directions(res: SearchResult, chosen: list[Candidate], h1_limit: float,
                      originals: Mapping[str, float]) -> list[Candidate]:
    """For each single-parameter fix in ``chosen``, the smallest fix (h1 within the limit) that
    moves the same parameter the other way, when the search found one."""
    taken = {_direction(c.mutation, originals) for c in chosen}
    out = []
    for c in chosen:
        if len(c.mutation.values) != 1:
            continue
        ((name, sign),) = _direction(c.mutation, originals)
        other = ((name, -sign),)
        found = sorted((f for f in res.feasible if f.objectives[0] <= h1_limit
                        and _direction(f.mutation, originals) == other),
                       key=lambda f: (f.objectives[1], f.objectives[0]))
        if found and other not in taken:
            taken.add(other)
            out.append(found[0])
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
