"""Confidence in the deviating module: does the answer survive another reference, and does an
independent method agree?

Algorithm 1's answer depends on the reference execution the physical phase chose. The phase
records the accident-free candidates in the order of its rule (``PhysicalResult.front``); this
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

import functools
import json
import shutil
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rocas._fs import atomic_path, write_text_atomic
from rocas.pipeline.evaluate import VariantTask, record
from rocas.pipeline.physical import apply_physical
from rocas.pipeline.results import (
    Agreement,
    ConfidenceResult,
    DiffPhaseResult,
    ModuleRevision,
    PhysicalResult,
    PropertyChange,
    ReferenceAnswer,
    SecondOpinionRecord,
    TriggeringEntity,
)
from rocas.pipeline.rundir import Run
from rocas.scenarios.model import Scenario
from rocas.search.executor import submit
from rocas.search.space import Mutation

if TYPE_CHECKING:
    from rocas.analysis.diff import DiffResult

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


def phase_confidence(run: Run) -> ConfidenceResult:
    """Diff the accident against alternate references and ask module substitution. Returns
    the phase's result. When the chosen reference's walk went on past departures
    (:func:`_answer`), or :func:`adopted_answer` picks another reference's answer than the
    chosen one's (that reference then becomes the reference: reference.mcap and diff.json are
    rewritten for it), the result holds the revision of the deviating module; otherwise the
    chosen reference's answer stands."""
    from rocas.analysis.diff import diff

    done = run.get(ConfidenceResult)
    if done is not None:
        return done
    t0 = time.perf_counter()
    scn = run.scenario
    assert scn is not None
    physical = run.result(PhysicalResult)
    chosen_diff = run.result(DiffPhaseResult)
    assert physical.chosen is not None
    alternates = alternate_references([{"mutation": c.mutation} for c in physical.front],
                                      {"mutation": physical.chosen.mutation},
                                      run.cfg.alternate_references)
    opinion = _record_alternates_and_ask(run, scn, alternates)
    found = {"deviating_module": chosen_diff.deviating_module, "path": list(chosen_diff.path),
             "fallback": chosen_diff.fallback, "entries": chosen_diff.entries}
    answers = [{"reference": "reference.mcap", "mutation": physical.chosen.mutation,
                **_answer(found, opinion, lambda: diff(
                    run.out / "accident.mcap", run.out / "reference.mcap", delta_s=run.cfg.delta_s))}]
    diffs: list[dict[str, Any] | None] = [None]
    for i, cand in enumerate(alternates, start=1):
        result = diff(run.out / "accident.mcap", run.out / f"reference_{i}.mcap",
                      delta_s=run.cfg.delta_s)
        diffs.append(result.to_json())
        answers.append({"reference": f"reference_{i}.mcap", "mutation": cand["mutation"],
                        **_answer(diffs[-1], opinion, lambda r=result: r)})
    adopted = adopted_answer(answers, opinion)
    revisions = _revisions(run, chosen_diff, answers, adopted, diffs[adopted])
    agree = agreement([a["module"] for a in answers], adopted)
    stance = None if opinion is None else opinion.stance(agree["module"])
    level_ = level(agree, stance, fallback=bool(answers[adopted].get("fallback")))
    summary: dict[str, Any] = {"answers": answers, "agreement": agree, "adopted": adopted,
                               "level": level_}
    if opinion is not None:
        summary["second_opinion"] = {**opinion.to_dict(), "stance": stance}
    result = ConfidenceResult(
        answers=tuple(ReferenceAnswer.from_json(_plain(a)) for a in answers),
        triggering_entity=triggering_entity(scn, Mutation(dict(answers[adopted]["mutation"])))
        if adopted else None,
        agreement=Agreement.from_json(agree),
        adopted=adopted,
        second_opinion=SecondOpinionRecord.from_json(summary["second_opinion"])
        if opinion is not None else None,
        level=level_, note=note(summary), revisions=tuple(revisions))
    simulations = len(alternates) + (len(opinion.runs) + 1 if opinion is not None else 0)
    run.finish(result, time.perf_counter() - t0, simulations)
    return result


def _plain(answer: dict[str, Any]) -> dict[str, Any]:
    """An answer's JSON with its mutation's values as they are (not copied through JSON)."""
    return {**answer, "path": list(answer["path"])}


def _record_alternates_and_ask(run: Run, scn: Scenario, alternates: list[dict[str, Any]]) -> Any:
    """Record the alternate references (reference_1.mcap, ...) and return module
    substitution's opinion (None when it is not asked).

    Module substitution needs only the accident: it was started on a worker before phase II
    (start_second_opinion); the alternate references are recorded here, all in one batch
    (each file is the one its run alone records, at one rollout's fixed cost per tick instead
    of one each)."""
    from rocas.pipeline.substitution import second_opinion

    started = run.ahead.pop("second_opinion", None)
    record([(VariantTask(s, (), s.seed), run.out / f"reference_{i}.mcap")
            for i, s in enumerate((apply_physical(scn, Mutation(dict(cand["mutation"])))
                                   for cand in alternates), start=1)])
    if not wants_second_opinion(run):
        return None
    return started.result() if started is not None else second_opinion(scn)


def _revisions(run: Run, chosen_diff: DiffPhaseResult, answers: list[dict[str, Any]], adopted: int,
               data: dict[str, Any] | None) -> list[ModuleRevision]:
    """The phase's revisions of the diff's answer: the chosen reference's walk taken on past
    departures (walk_passed), then another reference's answer adopted (adopted_reference, whose
    recording and diff ``data`` become the run's reference.mcap and diff.json)."""
    out = []
    first = answers[0]
    if any(first.get(k) for k in _PASSED):
        out.append(ModuleRevision(by="confidence", reason="walk_passed",
                                  before=chosen_diff.deviating_module, after=first["module"],
                                  path=tuple(first["path"]), fallback=first["fallback"],
                                  **_passed(first)))
    if adopted:
        assert data is not None
        answer = answers[adopted]
        _adopt(run, answer, data)
        out.append(ModuleRevision(by="confidence", reason="adopted_reference",
                                  before=first["module"], after=answer["module"],
                                  path=tuple(answer["path"]), fallback=answer["fallback"],
                                  reference=answer["reference"],
                                  control_channel=data["control_channel"], entries=data["entries"],
                                  warnings=tuple(data["warnings"]), **_passed(answer)))
    return out


def _passed(answer: dict[str, Any]) -> dict[str, Any]:
    """What an answer's walk passed over, as a revision's fields."""
    return {"entries_passed": answer.get("entries_passed") or None,
            "cleared_passed": tuple(answer["cleared_passed"]) if answer.get("cleared_passed") else None,
            "window_passed": answer.get("window_passed") or None}


#: how far before a module's departure, in Algorithm 1 windows, an input's departure may lie
#: for the walk to go on past the window to it (:func:`_past_window`): just past the window is
#: a cause that took longer to reach the commands (A9's slower truck: 3.2 s against a 3 s
#: window); many windows before is a difference the module long ignored (catalog A11's
#: forecast departs 8-17 s before planning, the truck's off-tracking unmodelled all along)
PAST_WINDOW_REACH = 2.0

#: the answer's keys that say which departures its walk passed over
_PASSED = ("entries_passed", "cleared_passed", "window_passed")


def adopted_answer(answers: list[dict[str, Any]], opinion: Any) -> int:
    """The index in ``answers`` (the chosen reference's first, then the alternates' in rank
    order) of the answer the analysis reports; ``opinion``: module substitution's, or None.

    - When the references' majority names another module than the chosen reference, and
      module substitution supports the majority's module but not the chosen one's, the
      majority's best-ranked reference: two independent methods outweigh one reference.
    - When the chosen reference's diff names no module (its commands differ from their first
      messages, or nothing upstream explains them), it abstains: the best-ranked reference
      that names a module substitution does not disagree with (any module, without
      substitution) answers instead (a light switched off lets an ego that waited at red
      drive from the first tick, and the diff has no departure to walk back from).
    - Otherwise the chosen reference's (0).
    """
    majority = agreement([a["module"] for a in answers])["majority"]
    chosen = answers[0]["module"]
    if (opinion is not None and majority != chosen and opinion.stance(majority) in _SUPPORTS
            and opinion.stance(chosen) == "disagrees"):
        return next(i for i, a in enumerate(answers) if a["module"] == majority)
    if chosen is None:
        return next((i for i, a in enumerate(answers) if a["module"] is not None and (
            opinion is None or opinion.stance(a["module"]) in _SUPPORTS)), 0)
    return 0


def wants_second_opinion(run: Run) -> bool:
    """Whether the confidence phase asks module substitution (when the stack declares modules
    it can substitute)."""
    from rocas.stacks.registry import get_stack

    assert run.scenario is not None
    return run.cfg.second_opinion and bool(getattr(get_stack(run.scenario.ego.stack),
                                                   "substitutable", ()))


def start_second_opinion(run: Run) -> None:
    """Start module substitution's batch on a worker (``run.ahead["second_opinion"]``) when the
    confidence phase will ask for it: it needs only the accident scenario, so it runs while
    phase II searches in this process (with one worker, here and now)."""
    from rocas.pipeline.substitution import second_opinion

    if not run.done("confidence") and wants_second_opinion(run):
        run.ahead["second_opinion"] = submit(run.executor, second_opinion, run.scenario)


def _answer(found: dict[str, Any], opinion: Any, result: Callable[[], DiffResult] | None = None
            ) -> dict[str, Any]:
    """A reference's answer from its diff (``found``: the diff's JSON or the diff phase's
    summary; ``result``: gives the diff itself, called only when a walk must be taken again):
    Algorithm 1's walk, or the walk with the departures where content entered both runs passed
    over (``found["entries"]``, :func:`rocas.analysis.entries.entries_to_pass`) when the two
    name different modules and module substitution (``opinion``) supports the second and not
    the first; then past a module substitution cleared (:func:`_past_cleared`) or past the
    window toward the module substitution names (:func:`_past_window`).

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
    if any(found.get(k) for k in _PASSED):  # a summary this phase already resolved
        return {**answer, **{k: found[k] for k in _PASSED if found.get(k)}}
    entries = found.get("entries")
    if not (opinion is None or not entries or entries["deviating_module"] == answer["module"]
            or not entries.get("named_at_entry")
            or opinion.stance(answer["module"]) != "disagrees"
            or opinion.stance(entries["deviating_module"]) not in _SUPPORTS):
        answer = {"module": entries["deviating_module"], "path": entries["path"],
                  "fallback": entries["fallback"], "entries_passed": entries["channels"]}
    result = None if result is None else functools.cache(result)  # one diff, read at most once
    return _past_cleared(answer, opinion, result) if "entries_passed" in answer else \
        _past_window(_past_cleared(answer, opinion, result), opinion, result)


def _past_window(answer: dict[str, Any], opinion: Any, result: Callable[[], DiffResult] | None
                 ) -> dict[str, Any]:
    """``answer`` with Algorithm 1's walk continued past its window toward the module that
    module substitution (``opinion``) names, when that module writes an input of the module
    the walk named that departed before the window, and the walk from that input names it.

    The window (``--delta``) passes over departures upstream that came too long before a
    module's own to have caused it. How long a cause takes to reach the commands depends on
    the accident, though: the red truck of A9 met at a lower speed is in view 3.2 s before the
    brake classifier's output crosses its threshold, the brake signal departs when the truck
    comes into view, and the walk ends at planning, one bin outside the window. When the
    module whose ground truth alone avoids the accident is the one whose early departure the
    window cut off, the two methods agree on it, and it is the answer; the report says the
    walk went on past the window (``window_passed``). Only Algorithm 1's own answer is
    continued so (not one already taken past entries or cleared modules, nor its fallback's),
    and only to an input that departed at most PAST_WINDOW_REACH windows before the module."""
    target = None if opinion is None or not opinion.accident else opinion.module
    if (result is None or target is None or answer["module"] in (None, target)
            or answer.get("fallback") or answer.get("cleared_passed")):
        return answer
    found = result()
    pin = found.walk_past_window([target], reach_s=PAST_WINDOW_REACH * found.delta_s)
    if pin.deviating_module != target:
        return answer
    return {**answer, "module": target, "path": list(pin.path),
            "window_passed": f"{pin.fallback}; module substitution names {target}"}


def _past_cleared(answer: dict[str, Any], opinion: Any, result: Callable[[], DiffResult] | None
                  ) -> dict[str, Any]:
    """``answer`` with the walk taken again past its module when module substitution
    (``opinion``) cleared that module while another module's ground truth alone avoids the
    accident.

    A module whose ground truth leaves the accident in place did not cause it: no
    configuration of it could do better than ground truth. Its departure before the commands'
    is then a difference the rest of the stack did not act on (a drifting truck placed 0.8 m
    aside changes the brake classifier's probabilities 1.8 s before planning departs, and the
    walk, taking the earliest input, ends at perception). The walk is taken again with that
    module's channels counted as not departed (:meth:`DiffResult.walk_without`), repeatedly
    while it names a cleared module. The rule needs substitution to be informative: when no
    module's ground truth alone avoids the accident (one the ego could not avoid, A7's car
    from behind, or one only both substitutes together avoid) clearing says nothing, and the
    answer stands; it stands too when the walk past names no module."""
    if (opinion is None or result is None or not opinion.accident or opinion.module is None
            or answer["module"] not in opinion.cleared):
        return answer
    found = result()
    passed: list[str] = []
    pin = None
    module = answer["module"]
    while module in opinion.cleared and module not in passed:
        passed.append(module)
        pin = found.walk_without(passed, past_entries=bool(answer.get("entries_passed")))
        module = pin.deviating_module
    if pin is None or module is None:
        return answer
    return {**answer, "module": module, "path": list(pin.path), "fallback": pin.fallback,
            "cleared_passed": passed}


def record_reference(scenario: Scenario, reference: Path) -> None:
    """Simulate ``scenario`` into the recording ``reference`` (a picklable task: it may run in
    a worker)."""
    from rocas.rollout import simulate

    simulate(scenario, output=reference)


def triggering_entity(scn: Any, mutation: Mutation) -> TriggeringEntity:
    """The triggering entity of a reference, as the physical phase words it."""
    from rocas.pipeline.physical import describe, entity_kinds, mutated_entities, physical_space

    space = physical_space(scn)
    entity = mutated_entities(space, mutation)
    return TriggeringEntity(entity=entity[0] if entity else None,
                            kind=entity_kinds(scn).get(entity[0]) if entity else None,
                            entities=tuple(entity),
                            properties=tuple(PropertyChange(**p) for p in describe(space, mutation)))


def _adopt(run: Run, answer: dict[str, Any], data: dict[str, Any]) -> None:
    """Make ``answer``'s reference the analysis's reference (the files later phases, the
    report and the Rerun view read): its recording, already written, is copied over
    reference.mcap, and its diff (``data``) over diff.json."""
    with atomic_path(run.out / "reference.mcap") as tmp:
        shutil.copyfile(run.out / answer["reference"], tmp)
    write_text_atomic(run.out / "diff.json", json.dumps(data, indent=1))


def note(result: dict[str, Any]) -> str:
    """The confidence in one sentence."""
    agree = result["agreement"]
    module = agree["module"]
    text = f"{agree['same']} of {agree['runs']} references name {module or 'no module'}"
    if agree["runner_up"]:
        r = agree["runner_up"]
        text += f" ({r['runs']} name{'s' if r['runs'] == 1 else ''} {r['module'] or 'no module'})"
    first = result["answers"][0]["module"] or "no module"
    adopted_ref = result["answers"][result.get("adopted", 0)]["reference"]
    if result.get("adopted") and result["answers"][0]["module"] is None:
        text += (f"; the chosen reference's diff named no module, so the best-ranked reference "
                 f"that names one ({adopted_ref}) is used")
    elif result.get("adopted"):
        text += (f"; the chosen reference named {first}, but the majority and module substitution "
                 f"name {module or 'no module'}, so the majority's best-ranked reference "
                 f"({adopted_ref}) is used")
    elif agree.get("majority", module) != module:
        text += (f"; the majority names {agree['majority'] or 'no module'}, which module substitution "
                 f"does not support, so the chosen reference's answer stands")
    second = result.get("second_opinion")
    if second:
        text += f"; {_STANCE_WORDS[second['stance']]}"
        if second["stance"] == "disagrees" and second.get("module"):
            text += f" ({second['module']})"
    cleared = result["answers"][result.get("adopted", 0)].get("cleared_passed")
    if cleared:
        text += (f"; the walk went on past {' and '.join(cleared)}, whose ground truth leaves the "
                 "accident in place")
    if result["answers"][result.get("adopted", 0)].get("window_passed"):
        text += "; the walk went on past its window to the module substitution names"
    if result["answers"][result.get("adopted", 0)].get("fallback"):
        text += ("; found without a change point on the control channel that times its "
                 "departure (Algorithm 1's fallback), so at most contested")
    if result["level"] == "unstable":
        text += (". Unstable: neither most references nor module substitution support it; "
                 "do not act on it alone")
    return text + "."


def with_suspect(level_: str, note_: str, revision: ModuleRevision) -> tuple[str, str]:
    """The confidence (level, note) once the cyber phase reported a second suspect's fix
    (``revision``): the reference's walk did not reach the suspect, so the answer is at most
    contested, and the note says whose parameters were searched and why."""
    named, suspect = revision.before, revision.after
    why = (f"{suspect}, which reads its output (substitution names {named} itself)"
           if revision.reads_named else f"{suspect}, the module substitution names")
    return "contested", (note_.rstrip(".") + f"; no configuration of {named} avoids the "
                         f"accident, so the parameters of {why}, were searched and its fix is "
                         f"reported (at most contested).")
