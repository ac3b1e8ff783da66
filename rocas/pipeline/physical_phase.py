"""Phase II: the physical search for the triggering entity and the accident-free reference.

The search is made to give the same answer at every seed. It starts with a screening: every
single-property mutant of the world (:func:`~rocas.pipeline.physical.screening_mutants`: each
enum choice, the flipped bool, reals at four points of their range) is simulated once. When one of them
avoids the accident, the reference is chosen among them by a fixed rule
(:func:`choose_reference`) and the genetic search does not run: the answer does not depend on
the seed. Only when none does, the genetic search (seeded) looks for combinations. The chosen
reference is then shrunk towards the original world while it still avoids the accident and
ranks as well under the rule.

The objectives of every simulated world (minimised): f1 suspiciousness of the mutated
entities, f2 dissimilarity of the *other* actors' trajectories up to the accident (the
paper's definition: the ego is not one of them), f3 size of the change, and f4 = minus the
shared prefix [s]: how long the ego drives in the reference exactly as in the accident, and f5
= 1 when the reference takes the accident's other party away from the encounter (it never gets
to where it met the ego, :func:`encounter_kept`), else 0. The constraint: no accident (an
emergency the accident's execution had at the same tick, before Algorithm 1's window, is not
one: :func:`without_prior_emergencies`), and the ego gets as far as it had at the accident
(:func:`reference_violation`).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from rocas import numerics
from rocas._fs import write_text_atomic
from rocas.pipeline.common import Scores, cand_json, gen_info, gen_json
from rocas.pipeline.config import planned_simulations
from rocas.pipeline.evaluate import VariantResult, VariantTask, evaluate, violation
from rocas.pipeline.physical import (
    apply_physical,
    describe,
    entity_kinds,
    entity_positions,
    is_weather,
    mutated_entities,
    physical_space,
    screening_mutants,
)
from rocas.pipeline.results import PhysicalResult, PropertyChange, ShrinkStep, TriggeringEntity
from rocas.pipeline.rundir import Run
from rocas.search.ga import Candidate, GenerationStats, run_search
from rocas.search.minimize import shrink_magnitudes, shrink_set
from rocas.search.objectives import scenario_dissimilarity, suspiciousness
from rocas.search.space import Mutation, MutationSpace
from rocas.sim.oracles import Outcome

#: a world counts as accident-free only when the ego also gets within this of as far as it
#: had driven at the accident [m]: a light that stays red avoids the accident by keeping the
#: ego from driving, which says nothing about the accident
PROGRESS_TOLERANCE_M = 1.0
#: two positions closer than this are the same [m]: a batch of simulations that mixes paths of
#: other lengths moves an actor by up to ~1e-4 m (the simulator resamples every path of a batch
#: to one point count), which is no departure
SAME_POSITION_M = 0.01
#: a reference whose ego departs from the accident's earlier than this [s] is an early one
#: (:func:`choose_reference` prefers the others): its planning and control differ from their
#: first messages, so they have no change point and Algorithm 1 ends at /control
EARLY_S = 0.5
#: the accident's other party keeps its encounter with the ego when it gets within this of the
#: place (along its path) where it met the ego, by the time it met it [m]
ENCOUNTER_TOLERANCE_M = 1.0


def shared_prefix_s(original: VariantResult, mutated: VariantResult, dt_s: float, upto: int) -> float:
    """How long [s] the ego drives in ``mutated`` exactly as in ``original`` (to within
    SAME_POSITION_M), up to tick ``upto``. A reference whose ego departs from the first frames
    (a visible actor's whole path shifted, so the ego reacts at once) makes /control change at
    the start and Algorithm 1 end there; one whose ego departs later (an entity changed before
    the ego reacts to it, a speed changed from some time on) leaves the diff the accident's
    own departure to find. Actors are not compared: an actor that moves differently from the
    start while the ego waits (it cannot react yet) is a good reference."""
    n = min(upto, len(original.ego_xy), len(mutated.ego_xy))
    departed = np.hypot(*(mutated.ego_xy[:n] - original.ego_xy[:n]).T) > SAME_POSITION_M
    first = int(np.argmax(departed)) if departed.any() else n
    return first * dt_s


def arc_positions(path_xy: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Where points lie along a path [m]: each point of ``xy`` (shape (N, 2)) projected onto
    the nearest segment of ``path_xy`` (shape (P, 2), P >= 2 distinct points), the first
    segment extended backwards and the last one forwards, so a point before the path's start
    or past its end gets a position below 0 or above its length. Returns shape (N,)."""
    a, b = path_xy[:-1], path_xy[1:]
    seg = b - a
    length = np.hypot(seg[:, 0], seg[:, 1])
    keep = length > 1e-9
    a, seg, length = a[keep], seg[keep], length[keep]
    start = np.concatenate(([0.0], np.cumsum(length)[:-1]))
    rel = xy[:, None, :] - a[None, :, :]
    t = (rel[..., 0] * seg[:, 0] + rel[..., 1] * seg[:, 1]) / (length * length)
    low = np.zeros_like(length)
    high = np.ones_like(length)
    low[0], high[-1] = -np.inf, np.inf
    t = np.clip(t, low, high)
    dx = rel[..., 0] - t * seg[:, 0]
    dy = rel[..., 1] - t * seg[:, 1]
    nearest = np.argmin(dx * dx + dy * dy, axis=1)
    rows = np.arange(len(xy))
    return start[nearest] + t[rows, nearest] * length[nearest]


def encounter_kept(original_xy: np.ndarray, mutated_xy: np.ndarray,
                   tolerance_m: float = ENCOUNTER_TOLERANCE_M) -> bool:
    """Whether the accident's other party, in a reference, still comes to the place where it
    met the ego: it starts short of that place along its path at the accident and gets within
    ``tolerance_m`` of it by the accident. Both arrays have shape (T, 2), up to the accident.

    A reference that stops the other party, holds it back or starts it beyond the place avoids
    the accident by taking away the encounter: the ego never faces the situation the accident
    came from, so the diff compares two systems that saw different things (A1: a creeping car
    stopped is one the ego drives past, and prediction, whose fault the accident is, treats it
    as it did). One that keeps it (the other party still gets there, on another line, at
    another speed or in another colour) leaves the avoidance to the ego's system, whose
    departure the diff is there to find. A party that did not move (less than the tolerance)
    keeps it trivially."""
    pts = original_xy[np.concatenate(([True], np.hypot(*np.diff(original_xy, axis=0).T) > 1e-9))]
    if len(pts) < 2 or path_length_m(pts) < tolerance_m:
        return True
    s = arc_positions(pts, mutated_xy)
    place = path_length_m(pts)
    return bool(s[0] < place and s.max() >= place - tolerance_m)


def path_length_m(xy: np.ndarray) -> float:
    """Length [m] of a path of shape (T, 2)."""
    return float(np.hypot(*np.diff(xy, axis=0).T).sum()) if len(xy) > 1 else 0.0


def without_prior_emergencies(outcome: Outcome, original: Outcome, before_s: float,
                              tolerance_s: float) -> Outcome:
    """``outcome`` without the emergencies (an estop, a hard brake) that the accident's own
    execution (``original``) also had, at the same time (within ``tolerance_s`` [s]) and
    before ``before_s`` [s] (the accident's time less Algorithm 1's reaction window).

    Such an event is not the accident under analysis but part of the prefix the two
    executions share (A7 laid out with the ego stopping close behind a long truck: its control
    raises an estop at 0.25 s in every world, long before the car behind hits it at 7.35 s);
    counted as an accident it would leave no world accident-free, and the analysis would end
    without a reference. An emergency within the window before the accident belongs to it
    (A3: the ego brakes hard 2.6 s before it is hit), as does one at another time or one the
    accident's execution did not have: those stay."""
    if outcome.collided or not outcome.emergency:
        return outcome

    def prior(t: float | None, t0: float | None) -> bool:
        return t is not None and t0 is not None and t0 < before_s and abs(t - t0) <= tolerance_s

    hard = outcome.hard_brake and not prior(outcome.hard_brake_time_s, original.hard_brake_time_s)
    estop = outcome.estop and not prior(outcome.estop_time_s, original.estop_time_s)
    if hard == outcome.hard_brake and estop == outcome.estop:
        return outcome
    return replace(outcome, hard_brake=hard, estop=estop,
                   hard_brake_time_s=outcome.hard_brake_time_s if hard else None,
                   estop_time_s=outcome.estop_time_s if estop else None,
                   emergency=hard or estop or outcome.unexpected_stop)


def reference_violation(r: VariantResult, needed_m: float, original: Outcome | None = None,
                        before_s: float = 0.0, dt_s: float = 0.05) -> float:
    """The physical search's constraint (<= 0: a usable reference): the accident's
    (:func:`~rocas.pipeline.evaluate.violation`; given ``original``, the outcome of the
    accident's execution, the emergencies it shares with it before ``before_s`` [s] do not
    count, :func:`without_prior_emergencies`, to within half a tick ``dt_s`` [s]), and for an
    accident-free world in which the ego drives less than ``needed_m`` over the whole run, a
    value in (0.5, 1] graded by how far short it stops (below any accident's, which is above 1)."""
    outcome = r.outcome if original is None else without_prior_emergencies(
        r.outcome, original, before_s, 0.5 * dt_s)
    v = violation(outcome)
    if v > 0 or needed_m <= 0:
        return v
    travel = path_length_m(r.ego_xy)
    return v if travel >= needed_m else 0.5 + 0.5 * (needed_m - travel) / needed_m


def phase_physical(run: Run) -> PhysicalResult:
    """Phase II: screen single-property mutants of the world, search combinations when none
    avoids the accident, choose the reference by the rule (:func:`choose_reference`) and
    shrink it towards the original world; records reference.mcap. Returns the phase's result
    (without ``chosen`` when no world avoids the accident)."""
    done = run.get(PhysicalResult)
    if done is not None:
        return done
    t0 = time.perf_counter()
    assert run.scenario is not None
    space = physical_space(run.scenario)
    batch = _batch(run, space, _objectives(run, space))
    screened, candidates, generations = _explore(run, space, batch)
    feasible = [c for c in candidates if c.feasible]
    shares = avoidance_shares(screened)
    chosen = choose_reference(feasible, space, shares)
    fields: dict[str, Any] = {
        "screening": len(screened), "screening_feasible": sum(c.feasible for c in screened),
        "search": "screening" if len(candidates) == len(screened) else "genetic",
        "generations": tuple(gen_json(g, "f2") for g in generations),
        "evaluations": len(candidates), "feasible": len(feasible),
        "front": tuple(cand_json(c) for c in _ranked(feasible, space, shares)[:20]),
        "avoidance_shares": {n: round(v, 3) for n, v in shares.items() if v > 0}}
    evaluations = len(candidates)
    if chosen is not None:
        shrunk, more = _shrunk_reference(run, space, batch, candidates, chosen)
        fields |= shrunk
        evaluations += more
    result = PhysicalResult(**fields)
    write_text_atomic(run.out / "physical.json", json.dumps(result.to_json(), indent=1))
    run.finish(result, time.perf_counter() - t0, evaluations)
    (run.out / "physical.ckpt").unlink(missing_ok=True)
    return result


Objectives = Callable[[Mutation, VariantResult], tuple[tuple[float, ...], float]]
Batch = Callable[[list[Mutation]], list[tuple[tuple[float, ...], float]]]


def _objectives(run: Run, space: MutationSpace) -> Objectives:
    """The objectives (f1-f5) and the constraint of one simulated world, measured against the
    accident's execution up to the accident (see the module docstring)."""
    scn, orig, tick, accident = run.scenario, run.original, run.accident_tick, run.accident
    assert scn is not None and orig is not None and accident is not None
    positions = entity_positions(scn, orig.actors_xy[min(tick, len(orig.actors_xy) - 1)])
    ego_xy = tuple(orig.ego_xy[tick])
    prev = orig.ego_xy[max(tick - 1, 0)]
    heading = float(numerics.arctan2(ego_xy[1] - prev[1], ego_xy[0] - prev[0])) if tick else 0.0
    actor_ids = [a.id for a in scn.actors]
    upto = tick + 1
    partner = actor_ids.index(accident.other) if accident.other in actor_ids else None
    needed_m = path_length_m(orig.ego_xy[:upto]) - PROGRESS_TOLERANCE_M
    prior_before_s = accident.time_s - run.cfg.delta_s

    def objectives(m: Mutation, r: VariantResult) -> tuple[tuple[float, ...], float]:
        ents = mutated_entities(space, m)
        f1 = suspiciousness([positions.get(e) for e in ents], ego_xy, heading, run.cfg.k_suspicion)
        f2 = scenario_dissimilarity({a: orig.actors_xy[:upto, i] for i, a in enumerate(actor_ids)},
                                    {a: r.actors_xy[:upto, i] for i, a in enumerate(actor_ids)})
        f4 = -shared_prefix_s(orig, r, scn.dt_s, upto)
        f5 = 0.0 if partner is None or encounter_kept(orig.actors_xy[:upto, partner],
                                                      r.actors_xy[:upto, partner]) else 1.0
        return (f1, f2, space.distance(m), f4, f5), reference_violation(
            r, needed_m, orig.outcome, prior_before_s, scn.dt_s)

    return objectives


def _batch(run: Run, space: MutationSpace, objectives: Objectives) -> Batch:
    """Simulate mutated worlds in batches and score each."""
    scn = run.scenario
    assert scn is not None

    def batch(ms: list[Mutation]) -> list[tuple[tuple[float, ...], float]]:
        tasks = [VariantTask(apply_physical(scn, m), (), scn.seed) for m in ms]
        return [objectives(m, r) for m, r in zip(ms, evaluate(run.executor, tasks, run.cfg.batch_size),
                                                 strict=True)]

    return batch


def _explore(run: Run, space: MutationSpace, batch: Batch
             ) -> tuple[list[Candidate], list[Candidate], list[GenerationStats]]:
    """The screening (generation 0: every single-property mutant, simulated once) and, when no
    single property avoids the accident, the genetic search for combinations. Returns the
    screened candidates, every candidate, and the generations."""
    screening = screening_mutants(space)
    run.progress("physical", {"planned": len(screening)})
    screened = [Candidate(m, tuple(o), float(c), 0) for m, (o, c) in zip(screening, batch(screening),
                                                                        strict=True)]
    stats = _stats(0, screened)
    run.progress("physical", gen_info(stats, "f2"))
    candidates, generations = list(screened), [stats]
    if not any(c.feasible for c in screened):
        search = run.cfg.search(1)
        run.progress("physical", {"planned": len(screened) + planned_simulations(search)})

        def on_generation(s: GenerationStats) -> None:
            run.progress("physical", gen_info(replace(s, evaluations=s.evaluations + len(screened)), "f2"))

        res = run_search(space, batch, search, 5, checkpoint=run.out / "physical.ckpt",
                         on_generation=on_generation)
        candidates += res.candidates
        generations += res.generations
    return screened, candidates, generations


def _shrunk_reference(run: Run, space: MutationSpace, batch: Batch, candidates: list[Candidate],
                      chosen: Candidate) -> tuple[dict[str, Any], int]:
    """Shrink the chosen reference towards the original and record it (reference.mcap).
    Returns the result's fields about the reference and the simulations it took.

    The shrink drops properties the avoidance does not need, then moves each real change back
    while it still avoids the accident and ranks in the same class of the rule (never a
    weather change, more entities, an encounter taken away or an early one), along the
    interval on which it does: a value past one that fails is an accident-free pocket between
    accidents (A6: the truck 0.375 m aside avoids it, 0.5-0.66 m brake hard, 0.69-1 m avoid
    it), whose reference differs from the accident only by a race won, and whose diff ends on
    a perception change 3.0 s before planning's, at the edge of Algorithm 1's window.

    The shrink must not change how the reference avoids the accident: shrunk to the edge of
    avoiding it, it can avoid it another way (A1: the creeping car lifted just below
    prediction's still-obstacle speed is forecast as static again, prediction no longer
    departs, and the ego waits for the car as for a parked one); the most shrunk step in whose
    diff the same modules depart as in the unshrunk one's is kept (:func:`_settle`)."""
    from rocas.rollout import simulate

    scn = run.scenario
    assert scn is not None
    scores = Scores(batch, candidates)
    want = _klass(chosen, space)

    def holds(ms: list[Mutation]) -> list[bool]:
        return [cons <= 0.0 and _klass(Candidate(m, objs, cons, 0), space) <= want
                for m, (objs, cons) in zip(ms, scores.of(ms), strict=True)]

    small, _ = shrink_set(chosen.mutation, holds)
    trail = [chosen.mutation, small]
    small, _ = shrink_magnitudes(small, space, holds, contiguous=True, on_round=trail.append)
    simulated = scores.simulated
    fields: dict[str, Any] = {"shrink_evaluations": simulated, "search_chosen": cand_json(chosen)}
    small, checked, recorded = _settle(run, list(dict.fromkeys(trail)))
    fields["shrink_checked"] = tuple(checked)
    if small != chosen.mutation:  # a trial that held: its objectives are already known
        objs, cons = scores.of([small])[0]
        chosen = replace(chosen, mutation=small, objectives=objs, constraint=cons)
    entity = mutated_entities(space, chosen.mutation)
    fields |= {"chosen": cand_json(chosen), "shared_prefix_s": round(-chosen.objectives[3], 3),
               "triggering_entity": TriggeringEntity(
                   entity=entity[0] if entity else None,
                   kind=entity_kinds(scn).get(entity[0]) if entity else None,
                   entities=tuple(entity),
                   properties=tuple(PropertyChange(**p) for p in describe(space, chosen.mutation)))}
    if recorded is not None:
        recorded.replace(run.out / "reference.mcap")
    else:
        simulate(apply_physical(scn, chosen.mutation), output=run.out / "reference.mcap")
    for stale in run.out.glob("shrink_*.mcap"):
        stale.unlink()
    return fields, simulated + len(checked)


def _settle(run: Run, trail: list[Mutation]
            ) -> tuple[Mutation, list[ShrinkStep], Path | None]:
    """The most shrunk reference of ``trail`` (the chosen reference, then each accepted shrink
    step) in whose diff against the accident the same modules depart (have a change point) as
    in the unshrunk reference's: shrinking moves the reference closer to the accident, and may
    move change points, but a step after which a module no longer departs at all (or another
    one starts to, or one that led the commands falls behind them) avoids the accident by
    another mechanism (:func:`same_mechanism`). Returns it, the
    steps diffed (in the order tried) and its recording
    (None when the trail has one step and nothing was recorded)."""
    from rocas.analysis.diff import diff
    from rocas.pipeline.confidence import record_reference
    from rocas.rollout import simulate
    from rocas.search.executor import done_future, submit

    scn = run.scenario
    assert scn is not None
    if len(trail) < 2:
        return trail[0], [], None
    checked: list[ShrinkStep] = []

    def departed(k: int) -> tuple[dict[str, float], float | None, float]:
        """Each departing module's change point [s], the control channel's (or None), and the
        diff's bin width [s]."""
        path = run.out / f"shrink_{k}.mcap"
        if k not in early:
            simulate(apply_physical(scn, trail[k]), output=path)
        else:
            early.pop(k).result()
        found = diff(run.out / "accident.mcap", path, delta_s=run.cfg.delta_s).to_json()
        modules = {m["name"]: m["change_point_s"] for m in found["modules"]
                   if m["change_point_s"] is not None}
        checked.append(ShrinkStep(mutation=dict(trail[k].values), module=found["deviating_module"],
                              departed=tuple(sorted(modules))))
        control = [c["change_point_s"] for c in found["channels"]
                   if c["topic"] == found["control_channel"]]
        return modules, control[0] if control else None, found["bin_s"]


    # the unshrunk reference and the most shrunk step are both recorded whatever the diffs
    # say: the first is recorded on a worker (when there is one) while this process records
    # the second; the recordings are the same wherever they are made
    last = len(trail) - 1
    early = {0: submit(run.executor, record_reference, apply_physical(scn, trail[0]),
                       run.out / "shrink_0.mcap")}
    early[last] = done_future(record_reference, apply_physical(scn, trail[last]),
                              run.out / f"shrink_{last}.mcap")
    want, want_control, _ = departed(0)
    for k in range(last, 0, -1):
        step, t_control, bin_s = departed(k)
        if same_mechanism(want, want_control, step, t_control, bin_s):
            return trail[k], checked, run.out / f"shrink_{k}.mcap"
    return trail[0], checked, run.out / "shrink_0.mcap"


#: bins by which a module's first departure must precede the commands' to count as leading
#: them: within one bin the pipeline reacts to a changed world at once (perception to control
#: in a tick or two at 10 Hz), so the order inside it says nothing about the mechanism
LEAD_BINS = 2


def same_mechanism(want: Mapping[str, float], want_control: float | None,
                   step: Mapping[str, float], t_control: float | None,
                   bin_s: float = 0.1) -> bool:
    """Whether a shrink step avoids the accident as the unshrunk reference did (see
    :func:`_settle`). ``want`` and ``step``: each departing module's change point [s] in the
    unshrunk reference's diff and in the step's; ``want_control`` and ``t_control``: the
    control channel's (None: none); ``bin_s``: the diffs' bin width [s].

    Every module departs in both, except one whose departure comes only after the commands'
    in the diff where it departs: that is their consequence (the ego's pose once it drives
    otherwise), not a mechanism. And a module that departed LEAD_BINS bins or more before the
    commands in the unshrunk reference's diff changed the stack's state while the commands
    stayed alike, which is how that reference avoided the accident: in the step it must still
    depart no later than the commands (the campaign's and generated A1 variants: prediction
    forecasts the lifted creeping car from 0.4-0.5 s, 2.5 s before the commands depart; shrunk
    to just under the still-obstacle speed, it departs only after them, at 3.2-3.8 s, and the
    reference avoids the accident by timing)."""
    def consequence(m: str, times: Mapping[str, float], tc: float | None) -> bool:
        return tc is not None and times[m] > tc

    def leads(m: str) -> bool:
        return want_control is not None and want_control - want[m] >= (LEAD_BINS - 0.5) * bin_s

    return (all(consequence(m, want, want_control) for m in set(want) - set(step))
            and all(consequence(m, step, t_control) for m in set(step) - set(want))
            and all(m in step and not consequence(m, step, t_control)
                    for m in want if leads(m)))


def _stats(generation: int, cands: Sequence[Candidate]) -> GenerationStats:
    f = np.array([c.objectives for c in cands], dtype=float).reshape(len(cands), -1)
    g = np.array([c.constraint for c in cands], dtype=float)
    return GenerationStats(generation, len(cands), int((g <= 0).sum()),
                           float(g.min()) if len(g) else float("inf"), f, g)


#: f2 [m^2] within which references count as equally similar to the original ...
F2_TOLERANCE_M2 = 1.0
#: ... or this fraction of the best f2, whichever is larger: f2 is a mean squared distance,
#: so its scale grows with speeds and duration, and a fixed margin that separates two
#: references on a parking lot would call two highway references different
F2_TOLERANCE_REL = 0.25


def f2_tolerance(best_f2: float) -> float:
    """The largest f2 [m^2] that counts as as similar to the original as ``best_f2``."""
    return best_f2 + max(F2_TOLERANCE_M2, F2_TOLERANCE_REL * best_f2)


def _klass(c: Candidate, space: MutationSpace) -> tuple[int, int, int, int]:
    """The coarse rank of a reference (smaller is better): a weather change last (fog or rain
    changes every channel at once), then the number of mutated entities, then whether it takes
    the accident's other party away from the encounter (f5), then whether it departs from the
    accident early (before EARLY_S; f4 = minus the shared prefix)."""
    return (int(is_weather(c.mutation)), len(mutated_entities(space, c.mutation)),
            int(c.objectives[4]) if len(c.objectives) > 4 else 0,
            int(-c.objectives[3] < EARLY_S) if len(c.objectives) > 3 else 0)


def avoidance_shares(screened: Sequence[Candidate]) -> dict[str, float]:
    """For each property the screening mutated, the estimated share (in (0, 1)) of its
    values that avoid the accident, from its screened values: ``(k + 1) / (n + 2)`` when
    ``k`` of its ``n`` screened single-property candidates in ``screened`` avoid it (others
    are ignored). This is Laplace's rule of succession (the mean under a uniform prior): a
    property screened at one value (a bool) that avoids it counts as 2/3, not as certain, so
    it does not outrank one that avoids it at 3 of 4 values (also 2/3), while 9 colours of 9
    (10/11) outrank 7 of 9 (8/11). A property none of whose screened values avoids it gets 0:
    it avoids the accident only together with others (the genetic search's candidates), and
    the estimate would rank those by how many values each kind of property was screened at."""
    tried: dict[str, list[bool]] = {}
    for c in screened:
        if len(c.mutation.values) == 1:
            tried.setdefault(c.mutation.names[0], []).append(c.feasible)
    return {name: (sum(ok) + 1) / (len(ok) + 2) if any(ok) else 0.0 for name, ok in tried.items()}


def robustness(c: Candidate, shares: Mapping[str, float]) -> float:
    """How robustly a reference's change avoids the accident: the smallest estimated
    avoidance share (:func:`avoidance_shares`) among the properties it changes (0 for one not
    screened)."""
    return min((shares.get(n, 0.0) for n in c.mutation.values), default=0.0)


def _ranked(feasible: Sequence[Candidate], space: MutationSpace,
            shares: Mapping[str, float] | None = None) -> list[Candidate]:
    """Accident-free candidates in the order of :func:`choose_reference`."""
    if not feasible:
        return []
    shares = shares or {}
    classes = {id(c): _klass(c, space) for c in feasible}
    out: list[Candidate] = []
    for k in sorted(set(classes.values())):
        group = [c for c in feasible if classes[id(c)] == k]
        limit = f2_tolerance(min(c.objectives[1] for c in group))
        out += sorted(group, key=lambda c: (c.objectives[1] > limit, -robustness(c, shares),
                                            c.objectives[0], c.objectives[2],
                                            _removals(c.mutation), c.objectives[1], c.mutation.names,
                                            _values(c.mutation)))
    return out


def _values(m: Mutation) -> tuple[str, ...]:
    return tuple(str(m.values[n]) for n in m.names)


def choose_reference(feasible: Sequence[Candidate], space: MutationSpace,
                     shares: Mapping[str, float] | None = None) -> Candidate | None:
    """The documented rule over the accident-free candidates (None when there are none):

    1. an entity change over a weather change (fog or rain changes every channel at once, so
       the diff could not tell one module's departure from another's);
    2. then the fewest mutated entities (the triggering entity, not a coalition);
    3. then one that keeps the accident's encounter (f5, :func:`encounter_kept`): the other
       party still gets to where it met the ego, so the ego's system is what avoids it;
    4. then a reference whose ego drives as in the accident for at least EARLY_S (f4): one whose
       ego departs from the first frames (a visible actor's whole path shifted, and the ego
       reacts at once) makes planning and control differ from their first messages;
    5. then the executions most similar to the original (f2 within F2_TOLERANCE_M2 or
       F2_TOLERANCE_REL of the best, whichever is larger; see f2_tolerance);
    6. then the most robust change (:func:`robustness` over ``shares``, the screening's
       :func:`avoidance_shares`): a property most of whose screened values avoid the accident
       is one the accident depends on (A9: every other colour of the red truck avoids it); one
       that avoids it at one value of four has hit an accident-free pocket (a cone moved 3 m
       that happens to shift the ego's line), whose diff shows how the pocket was reached;
    7. then the most suspicious (f1: close to and in front of the ego);
    8. then the smallest change (f3);
    9. then changing a property over removing an entity (``enabled`` -> off);
    10. then f2, the names and the values, so that the choice never depends on the order in
        which candidates were found.
    """
    ranked = _ranked(feasible, space, shares)
    return ranked[0] if ranked else None


def _removals(m: Mutation) -> int:
    """How many entities a mutation removes (an ``enabled`` property switched off)."""
    return sum(1 for n, v in m.values.items() if n.endswith(".enabled") and not v)
