"""Confidence in the deviating module: does the answer survive another reference, and does an
independent method agree?

Algorithm 1's answer depends on the reference execution the physical phase chose. The phase
records the accident-free candidates in the order of its rule (``physical["front"]``); this
phase diffs the accident against the best few *other* references (each changing other
properties than the chosen one, so that each is an independent view of the accident) and counts
how many name the same module. It also asks module substitution
(:func:`rocas.pipeline.substitution.second_opinion`), which uses no reference at all, whether
its answer agrees.

The verdict on the answer:

- ``stable``: more than half of the references name the module, and substitution agrees with
  it or is consistent with it (or was not asked);
- ``contested``: one of the two supports it: more than half of the references but substitution
  disagrees, or substitution but not more than half of the references;
- ``unstable``: neither does: do not act on the answer alone.

An answer Algorithm 1 found without a change point on the control channel that times its
departure (none, or one in the first bin after the start: its fallback,
:mod:`rocas.analysis.pinpoint`) is at most ``contested``: it rests on the earliest departure
among the modules the commands depend on, not on a walk back from the commands' own change.
"""

from __future__ import annotations

import json
import shutil
import time
from collections import Counter
from pathlib import Path
from typing import Any

from rocas._fs import atomic_path, write_text_atomic
from rocas.pipeline.evaluate import VariantTask, record
from rocas.pipeline.physical import apply_physical
from rocas.pipeline.rundir import Run
from rocas.scenarios.model import Scenario
from rocas.search.executor import submit
from rocas.search.space import Mutation

#: the report's words for each substitution stance (rocas.pipeline.substitution)
_STANCE_WORDS = {
    "agrees": "module substitution names the same module",
    "consistent": "module substitution clears perception and prediction, consistent with a "
                  "downstream module",
    "disagrees": "module substitution points elsewhere",
    "undetermined": "module substitution found no accident to explain",
}


def alternate_references(front: list[dict[str, Any]], chosen: dict[str, Any], count: int
                         ) -> list[dict[str, Any]]:
    """Up to ``count`` candidates of ``front`` (best first) that change another set of
    properties than ``chosen`` and than each other."""
    seen = {tuple(sorted(chosen["mutation"]))}
    out: list[dict[str, Any]] = []
    if count <= 0:
        return out
    for c in front:
        key = tuple(sorted(c["mutation"]))
        if key in seen:
            continue
        seen.add(key)
        out.append(c)
        if len(out) == count:
            break
    return out


def agreement(modules: list[str | None], reported: int = 0) -> dict[str, Any]:
    """How many of the references' modules name the one reported (``modules[reported]``), the
    majority's module (ties: the earliest, best-ranked answer) and the most frequent other."""
    counts = Counter(modules)
    module = modules[reported]
    best = max(counts.values())
    majority = next(m for m in modules if counts[m] == best)
    others = [(n, m) for m, n in counts.most_common() if m != module]
    return {"module": module, "runs": len(modules), "same": counts[module], "majority": majority,
            "runner_up": {"module": others[0][1], "runs": others[0][0]} if others else None}


_SUPPORTS = ("agrees", "consistent")


def level(agree: dict[str, Any], stance: str | None, fallback: bool = False) -> str:
    """stable / contested / unstable (see the module docstring); ``fallback``: the reported
    answer came from Algorithm 1's fallback."""
    majority = 2 * agree["same"] > agree["runs"]
    supported = stance in _SUPPORTS
    if majority and (supported or stance is None) and not fallback:
        return "stable"
    if majority or supported:
        return "contested"
    return "unstable"


def phase_confidence(run: Run) -> dict[str, Any]:
    """Diff the accident against alternate references and ask module substitution. Returns
    the phase's result. When the references' majority names another module than the chosen
    reference, and module substitution supports the majority's module but not the chosen
    one's, the majority's best-ranked reference becomes the reference (reference.mcap,
    diff.json and the diff phase's summary are rewritten for it): two independent methods
    outweigh one reference. Otherwise the chosen reference's answer stands."""
    from rocas.analysis.diff import diff
    from rocas.pipeline.substitution import second_opinion

    if run.done("confidence"):
        return run.state["done"]["confidence"]
    t0 = time.perf_counter()
    scn = run.scenario
    assert scn is not None
    physical = run.state["done"]["physical"]
    chosen_diff = run.state["done"]["diff"]
    alternates = alternate_references(physical.get("front", []), physical["chosen"],
                                      run.cfg.alternate_references)
    # module substitution needs only the accident: it was started on a worker before phase II
    # (start_second_opinion); the alternate references are recorded here, all in one batch
    # (each file is the one its run alone records, at one rollout's fixed cost per tick
    # instead of one each)
    started = run.ahead.pop("second_opinion", None)
    record([(VariantTask(s, (), s.seed), run.out / f"reference_{i}.mcap")
            for i, s in enumerate((apply_physical(scn, Mutation(dict(cand["mutation"])))
                                   for cand in alternates), start=1)])
    opinion = None
    if wants_second_opinion(run):
        opinion = started.result() if started is not None else second_opinion(scn)
    answers = [{"reference": "reference.mcap", "mutation": physical["chosen"]["mutation"],
                **_answer(chosen_diff, opinion)}]
    if answers[0].get("entries_passed"):  # the walk past the entries: the diff's answer now
        run.state["done"]["diff"] = {
            **chosen_diff, "deviating_module": answers[0]["module"], "path": answers[0]["path"],
            "fallback": answers[0]["fallback"], "entries_passed": answers[0]["entries_passed"]}
    diffs: list[dict[str, Any] | None] = [None]
    for i, cand in enumerate(alternates, start=1):
        found = diff(run.out / "accident.mcap", run.out / f"reference_{i}.mcap",
                     delta_s=run.cfg.delta_s).to_json()
        diffs.append(found)
        answers.append({"reference": f"reference_{i}.mcap", "mutation": cand["mutation"],
                        **_answer(found, opinion)})
    simulations = len(alternates)
    result: dict[str, Any] = {"answers": answers}
    if opinion is not None:
        simulations += len(opinion.runs) + 1
    majority = agreement([a["module"] for a in answers])["majority"]
    adopted = 0
    chosen_module = answers[0]["module"]
    if (opinion is not None and majority != chosen_module and opinion.stance(majority) in _SUPPORTS
            and opinion.stance(chosen_module) == "disagrees"):
        adopted = next(i for i, a in enumerate(answers) if a["module"] == majority)
        result["triggering_entity"] = triggering_entity(scn, Mutation(dict(answers[adopted]["mutation"])))
        _adopt(run, answers[adopted], diffs[adopted])
    agree = agreement([a["module"] for a in answers], adopted)
    result |= {"agreement": agree, "adopted": adopted}
    stance = None
    if opinion is not None:
        stance = opinion.stance(agree["module"])
        result["second_opinion"] = {**opinion.to_dict(), "stance": stance}
    result["level"] = level(agree, stance, fallback=bool(answers[adopted].get("fallback")))
    result["note"] = note(result)
    run.finish("confidence", result, time.perf_counter() - t0, simulations)
    return result


def wants_second_opinion(run: Run) -> bool:
    """Whether the confidence phase asks module substitution (the built-in ADS's oracles)."""
    assert run.scenario is not None
    return run.cfg.second_opinion and run.scenario.ego.stack == "ads"


def start_second_opinion(run: Run) -> None:
    """Start module substitution's batch on a worker (``run.ahead["second_opinion"]``) when the
    confidence phase will ask for it: it needs only the accident scenario, so it runs while
    phase II searches in this process (with one worker, here and now)."""
    from rocas.pipeline.substitution import second_opinion

    if not run.done("confidence") and wants_second_opinion(run):
        run.ahead["second_opinion"] = submit(run.executor, second_opinion, run.scenario)


def _answer(found: dict[str, Any], opinion: Any) -> dict[str, Any]:
    """A reference's answer from its diff (``found``: the diff's JSON or the diff phase's
    summary): Algorithm 1's walk, or the walk with the departures where content entered both
    runs passed over (``found["entries"]``, :func:`rocas.analysis.entries.entries_to_pass`)
    when the two name different modules and module substitution (``opinion``) supports the
    second and not the first.

    Content that enters both runs at once and differs from its first message (a bus in one
    run, a truck in the other, coming into view at the same tick) makes its channel depart
    there, and Algorithm 1 names the module that wrote it. That can be right (a perception
    that cannot see a car approaching from behind, whatever its configuration) or wrong (a
    planner that misjudges the car once it is seen). The diff alone cannot tell; module
    substitution can: when Algorithm 1's module was named at such an entry (its first
    departure is one, ``named_at_entry``), and substitution disagrees with it but supports
    the module the walk reaches past the entries, the second is the answer (a weaker rule,
    substitution finding the accident avoidable somewhere, would take a module substitution
    points away from: docs/algorithms.md). An answer Algorithm 1 reached otherwise stands:
    passing entries over can also expose another channel of a module (an A2 variant's brake
    signal) that the walk did not need.
    """
    answer = {"module": found["deviating_module"], "path": found["path"],
              "fallback": found.get("fallback")}
    if found.get("entries_passed"):  # a summary this phase already resolved
        return {**answer, "entries_passed": found["entries_passed"]}
    entries = found.get("entries")
    if (opinion is None or not entries or entries["deviating_module"] == answer["module"]
            or not entries.get("named_at_entry")
            or opinion.stance(answer["module"]) != "disagrees"
            or opinion.stance(entries["deviating_module"]) not in _SUPPORTS):
        return answer
    return {"module": entries["deviating_module"], "path": entries["path"],
            "fallback": entries["fallback"], "entries_passed": entries["channels"]}


def record_reference(scenario: Scenario, reference: Path) -> None:
    """Simulate ``scenario`` into the recording ``reference`` (a picklable task: it may run in
    a worker)."""
    from rocas.stacks.rollout import simulate

    simulate(scenario, output=reference)


def triggering_entity(scn: Any, mutation: Mutation) -> dict[str, Any]:
    """The triggering entity of a reference, as the physical phase words it."""
    from rocas.pipeline.physical import describe, entity_kinds, mutated_entities, physical_space

    space = physical_space(scn)
    entity = mutated_entities(space, mutation)
    return {"entity": entity[0] if entity else None,
            "kind": entity_kinds(scn).get(entity[0]) if entity else None,
            "entities": entity, "properties": describe(space, mutation)}


def _adopt(run: Run, answer: dict[str, Any], data: dict[str, Any]) -> None:
    """Make ``answer``'s reference the analysis's reference (the files later phases, the
    report and the Rerun view read): its recording, already written, is copied over
    reference.mcap."""
    with atomic_path(run.out / "reference.mcap") as tmp:
        shutil.copyfile(run.out / answer["reference"], tmp)
    write_text_atomic(run.out / "diff.json", json.dumps(data, indent=1))
    run.state["done"]["diff"] = {"deviating_module": answer["module"], "path": answer["path"],
                                 "control_channel": data["control_channel"],
                                 "fallback": answer["fallback"],
                                 "entries": data["entries"],
                                 "adopted_from": answer["reference"]}
    if answer.get("entries_passed"):
        run.state["done"]["diff"]["entries_passed"] = answer["entries_passed"]


def note(result: dict[str, Any]) -> str:
    """The confidence in one sentence."""
    agree = result["agreement"]
    module = agree["module"]
    text = f"{agree['same']} of {agree['runs']} references name {module or 'no module'}"
    if agree["runner_up"]:
        r = agree["runner_up"]
        text += f" ({r['runs']} name{'s' if r['runs'] == 1 else ''} {r['module'] or 'no module'})"
    first = result["answers"][0]["module"] or "no module"
    if result.get("adopted"):
        text += (f"; the chosen reference named {first}, but the majority and module substitution "
                 f"name {module or 'no module'}, so the majority's best-ranked reference "
                 f"({result['answers'][result['adopted']]['reference']}) is used")
    elif agree.get("majority", module) != module:
        text += (f"; the majority names {agree['majority'] or 'no module'}, which module substitution "
                 f"does not support, so the chosen reference's answer stands")
    second = result.get("second_opinion")
    if second:
        text += f"; {_STANCE_WORDS[second['stance']]}"
        if second["stance"] == "disagrees" and second.get("module"):
            text += f" ({second['module']})"
    if result["answers"][result.get("adopted", 0)].get("fallback"):
        text += ("; found without a change point on the control channel that times its "
                 "departure (Algorithm 1's fallback), so at most contested")
    if result["level"] == "unstable":
        text += (". Unstable: neither most references nor module substitution support it; "
                 "do not act on it alone")
    return text + "."
