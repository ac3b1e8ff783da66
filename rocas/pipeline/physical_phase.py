"""Phase II: the physical search for the triggering entity and the accident-free reference."""

from __future__ import annotations

import json
import time
from dataclasses import replace
from typing import Any

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
    mutated_entities,
    physical_space,
)
from rocas.pipeline.rundir import Run, jsonable
from rocas.search.ga import Candidate, SearchResult, run_search
from rocas.search.minimize import shrink_set
from rocas.search.objectives import scenario_dissimilarity, suspiciousness
from rocas.search.space import Mutation, MutationSpace


def phase_physical(run: Run) -> dict[str, Any]:
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
                     on_generation=lambda s: run.progress("physical", gen_info(s, "f2")))
    chosen = _choose_trigger(res, space)
    result: dict[str, Any] = {"generations": [gen_json(g, "f2") for g in res.generations],
                              "evaluations": res.evaluations, "feasible": len(res.feasible),
                              "front": [cand_json(c) for c in res.front[:20]]}
    evaluations = res.evaluations
    if chosen is not None:
        # drop properties the avoidance does not need (a search often carries passengers,
        # e.g. a 0.0001 m move of a bystander), keeping the reference as similar as chosen
        f2_limit = f2_tolerance(chosen.objectives[1])
        scores = Scores(batch, res.candidates)

        def holds(ms: list[Mutation]) -> list[bool]:
            return [cons <= 0.0 and objs[1] <= f2_limit for objs, cons in scores.of(ms)]

        small, _ = shrink_set(chosen.mutation, holds)
        evaluations += scores.simulated
        result["shrink_evaluations"] = scores.simulated
        result["search_chosen"] = cand_json(chosen)
        if small != chosen.mutation:  # a trial that held: its objectives are already known
            objs, cons = scores.of([small])[0]
            chosen = replace(chosen, mutation=small, objectives=objs, constraint=cons)
        entity = mutated_entities(space, chosen.mutation)
        result["chosen"] = cand_json(chosen)
        result["triggering_entity"] = {
            "entity": entity[0] if entity else None,
            "kind": entity_kinds(scn).get(entity[0]) if entity else None,
            "entities": entity,
            "properties": describe(space, chosen.mutation),
        }
        simulate(apply_physical(scn, chosen.mutation), output=run.out / "reference.mcap")
    write_text_atomic(run.out / "physical.json", json.dumps(result, indent=1, default=jsonable))
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
