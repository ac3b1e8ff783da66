"""What each phase of ``rocas analyze`` returns: one frozen dataclass per phase.

A phase's result is written into the run directory (``state.json``, through
:mod:`rocas.pipeline.codec`) and never rewritten by a later phase. A later phase that revises
the deviating module (the confidence phase adopting another reference's answer or walking on
past a departure, the cyber phase reporting a second suspect's fix) returns a
:class:`ModuleRevision` inside its own result; :func:`current_answer` applies the revisions,
in phase order, to the diff phase's answer. JSON keys are the field names, in their order:
the run directory's files and ``report.json`` keep the layout they had as plain dicts.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from rocas.pipeline.codec import Json, ShapeError, from_json, omitted, to_json


class JsonCodec:
    """``to_json``/``from_json`` of a result dataclass (see :mod:`rocas.pipeline.codec`)."""

    def to_json(self) -> dict[str, Any]:
        return to_json(self)

    @classmethod
    def from_json(cls, data: Any, where: str = ""):  # type: ignore[no-untyped-def]
        return from_json(cls, data, where)


# ---- parts shared by several phases -------------------------------------------------------


@dataclass(frozen=True)
class AccidentInfo(JsonCodec):
    """An accident as reports give it: ``kind`` ("collision" or "emergency"), ``time_s`` [s]
    (None: unknown) and the other party's id (None for an emergency)."""

    kind: str
    time_s: float | None
    other: str | None


@dataclass(frozen=True)
class CandidateRecord(JsonCodec):
    """A search candidate: its mutation (name -> value), objectives (physical search:
    f1 [-], f2 [m^2], f3 [-], f4 [s], f5 [-]; cyber search: h1 [m^2], h2 [-]), its constraint
    (<= 0: avoids the accident) and the generation it was found in."""

    mutation: Mapping[str, Any]
    objectives: tuple[float, ...]
    constraint: float
    generation: int


@dataclass(frozen=True)
class GenerationRecord(JsonCodec):
    """One generation of a search: counts, the best constraint, the smallest second objective
    among its accident-free members (``best_objective`` names it: f2 or h2), and every
    member's objectives (shape (N, M)) and constraints (shape (N,))."""

    generation: int
    evaluations: int
    feasible: int
    best_constraint: float
    best_feasible: float | None
    best_objective: str
    objectives: tuple[tuple[float, ...], ...]
    constraints: tuple[float, ...]


@dataclass(frozen=True)
class PropertyChange(JsonCodec):
    """A property of the world a reference changes: its name, value in the accident and in
    the reference (units of the property)."""

    name: str
    original: Any
    mutated: Any


@dataclass(frozen=True)
class TriggeringEntity(JsonCodec):
    """The entity whose change avoids the accident: its id and kind (None: weather or none),
    every entity the change touches, and the properties changed."""

    entity: str | None
    kind: str | None
    entities: tuple[str, ...]
    properties: tuple[PropertyChange, ...]


@dataclass(frozen=True)
class ParameterChange(JsonCodec):
    """A parameter of the stack a fix changes: its module, full name, value in force in the
    accident and the fix's value (units of the parameter)."""

    module: str
    parameter: str
    original: float
    mutated: float


# ---- phase I ------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class ReplayResult(JsonCodec):
    """Phase I: the accident replayed (``source`` "recording") or simulated ("scenario").

    Attributes:
        reproduced: the replay has the accident (the analysis goes on).
        recorded_accident: the accident the recording holds (None: none, or a scenario).
        accident: the replay's accident.
        ego_rmse_m: the replayed ego's position error against the recorded pose [m].
        compared_until_s, only_emergency, warnings, complete: recording mode only: how far
            the poses were compared [s], whether only the emergency before the recorded
            collision was reproduced, the damage the reader found, and whether the whole
            recording was used.
        stack: the stack the searches re-run.
    """

    PHASE: ClassVar[str] = "replay"
    source: str
    reproduced: bool
    recorded_accident: AccidentInfo | None
    accident: AccidentInfo | None
    ego_rmse_m: float | None
    compared_until_s: float | None = omitted()
    only_emergency: bool | None = omitted()
    warnings: tuple[str, ...] | None = omitted()
    complete: bool | None = omitted()
    stack: str


# ---- phase II -----------------------------------------------------------------------------


@dataclass(frozen=True)
class ShrinkStep(JsonCodec):
    """A step of the reference's shrink whose diff was checked: its mutation, the module the
    diff names, and the modules that depart."""

    mutation: Mapping[str, Any]
    module: str | None
    departed: tuple[str, ...]


@dataclass(frozen=True)
class PhysicalResult(JsonCodec):
    """Phase II: the physical search for an accident-free reference.

    Attributes:
        screening, screening_feasible: single-property mutants simulated, and how many avoid
            the accident.
        search: "screening" (a screened mutant is the reference) or "genetic".
        generations: every generation (the screening is generation 0).
        evaluations, feasible: candidates simulated, and how many avoid the accident.
        front: the best accident-free candidates (at most 20) in the order of the rule.
        avoidance_shares: per property, the estimated share of its values that avoid it.
        shrink_evaluations, search_chosen, shrink_checked: the shrink of the reference (its
            simulations, the candidate before it, the steps whose diff was checked).
        chosen: the reference (None: no accident-free world was found).
        shared_prefix_s: how long the ego drives in the reference as in the accident [s].
        triggering_entity: what the reference changes.
    """

    PHASE: ClassVar[str] = "physical"
    screening: int
    screening_feasible: int
    search: str
    generations: tuple[GenerationRecord, ...]
    evaluations: int
    feasible: int
    front: tuple[CandidateRecord, ...]
    avoidance_shares: Mapping[str, float]
    shrink_evaluations: int | None = omitted()
    search_chosen: CandidateRecord | None = omitted()
    shrink_checked: tuple[ShrinkStep, ...] | None = omitted()
    chosen: CandidateRecord | None = omitted()
    shared_prefix_s: float | None = omitted()
    triggering_entity: TriggeringEntity | None = omitted()


# ---- phase III ----------------------------------------------------------------------------


@dataclass(frozen=True)
class DiffPhaseResult(JsonCodec):
    """Phase III: Algorithm 1 on the accident and the chosen reference (diff.json holds it all).

    Attributes:
        deviating_module: the module the walk names (None: none).
        path: the walk, channels and modules alternating from the control channel.
        control_channel: the channel the walk started from.
        fallback: why the walk did not start at the control channel's change point.
        entries: the walk with the departures where content entered both runs passed over
            (the diff's ``entries`` object), or None.
        warnings: damage the diff met (lines).
    """

    PHASE: ClassVar[str] = "diff"
    deviating_module: str | None
    path: tuple[str, ...]
    control_channel: str | None
    fallback: str | None
    entries: Json | None
    warnings: tuple[str, ...]


# ---- revisions of the deviating module ----------------------------------------------------

#: why a later phase revised the deviating module
REVISION_REASONS = ("walk_passed", "adopted_reference", "second_suspect")


@dataclass(frozen=True)
class ModuleRevision(JsonCodec):
    """A later phase's revision of the deviating module.

    Attributes:
        by: the phase that revised it ("confidence" or "cyber").
        reason: "walk_passed" (the walk went on past departures module substitution speaks
            against), "adopted_reference" (another reference's answer is the analysis's) or
            "second_suspect" (no configuration of the earlier module avoids the accident; the
            fix is in ``after``'s parameters).
        before, after: the deviating module before and after the revision.
        path: the walk that names ``after`` (empty for a second suspect: no walk names it).
        fallback: the walk's fallback (walk_passed, adopted_reference).
        entries_passed: departures where content entered both runs, passed over (topic ->
            time [s]); cleared_passed: modules substitution cleared, walked past;
            window_passed: why the walk went on past Algorithm 1's window.
        reference: the adopted reference's recording (adopted_reference), and that diff's
            ``control_channel``, ``entries`` and ``warnings``.
        reads_named: (second_suspect) ``after`` reads ``before``'s output (substitution named
            ``before`` itself), rather than being the module substitution names.
    """

    by: str
    reason: str
    before: str | None
    after: str | None
    path: tuple[str, ...]
    fallback: str | None = None
    entries_passed: Mapping[str, float] | None = omitted()
    cleared_passed: tuple[str, ...] | None = omitted()
    window_passed: str | None = omitted()
    reference: str | None = omitted()
    control_channel: str | None = omitted()
    entries: Json | None = omitted()
    warnings: tuple[str, ...] | None = omitted()
    reads_named: bool = False

    def __post_init__(self) -> None:
        if self.reason not in REVISION_REASONS:
            raise ShapeError("reason", f"is not one of {', '.join(REVISION_REASONS)}")


@dataclass(frozen=True)
class Answer:
    """The analysis's current answer: the diff phase's, with every revision applied
    (:func:`current_answer`). Fields as in :class:`DiffPhaseResult` and
    :class:`ModuleRevision`; ``adopted_from``: the adopted reference's recording;
    ``walk_named``: the module the walk named before a second suspect's fix was reported."""

    deviating_module: str | None
    path: tuple[str, ...]
    control_channel: str | None
    fallback: str | None
    entries: Json | None
    warnings: tuple[str, ...]
    entries_passed: Mapping[str, float] | None = None
    cleared_passed: tuple[str, ...] | None = None
    window_passed: str | None = None
    adopted_from: str | None = None
    walk_named: str | None = None
    suspect_reads_named: bool = False


def revised(answer: Answer, revision: ModuleRevision) -> Answer:
    """``answer`` with one revision applied."""
    passed = {"entries_passed": revision.entries_passed, "cleared_passed": revision.cleared_passed,
              "window_passed": revision.window_passed}
    if revision.reason == "walk_passed":
        return dataclasses.replace(answer, deviating_module=revision.after, path=revision.path,
                                   fallback=revision.fallback, **passed)
    if revision.reason == "adopted_reference":  # another reference's diff: nothing else stays
        return Answer(revision.after, revision.path, revision.control_channel, revision.fallback,
                      revision.entries, revision.warnings or (), adopted_from=revision.reference,
                      **passed)
    if revision.reason == "second_suspect":
        return dataclasses.replace(answer, deviating_module=revision.after, path=(),
                                   walk_named=revision.before,
                                   suspect_reads_named=revision.reads_named)
    raise AssertionError(revision.reason)  # refused on construction


def current_answer(diff: DiffPhaseResult, revisions: Sequence[ModuleRevision] = ()) -> Answer:
    """The diff phase's answer with ``revisions`` applied in order (the one place the current
    deviating module is computed)."""
    answer = Answer(diff.deviating_module, diff.path, diff.control_channel, diff.fallback,
                    diff.entries, diff.warnings)
    for revision in revisions:
        answer = revised(answer, revision)
    return answer


# ---- the confidence phase -----------------------------------------------------------------


@dataclass(frozen=True)
class ReferenceAnswer(JsonCodec):
    """What one reference's diff names: its recording (in the run directory), its mutation,
    and the answer (module, walk, fallback, and what the walk passed over, as in
    :class:`ModuleRevision`)."""

    reference: str
    mutation: Mapping[str, Any]
    module: str | None
    path: tuple[str, ...]
    fallback: str | None
    entries_passed: Mapping[str, float] | None = omitted()
    cleared_passed: tuple[str, ...] | None = omitted()
    window_passed: str | None = omitted()


@dataclass(frozen=True)
class RunnerUp(JsonCodec):
    """The most frequent other module among the references, and how many name it."""

    module: str | None
    runs: int


@dataclass(frozen=True)
class Agreement(JsonCodec):
    """How many of ``runs`` references name ``module`` (``same``), the majority's module and
    the runner-up."""

    module: str | None
    runs: int
    same: int
    majority: str | None
    runner_up: RunnerUp | None


@dataclass(frozen=True)
class SecondOpinionRecord(JsonCodec):
    """Module substitution's answer (:mod:`rocas.pipeline.substitution`): the module whose
    ground truth alone avoids the accident (None: none), why, whether there was an accident to
    explain, the modules it cleared, the baseline run and each substituted run (one-line
    outcomes), and its stance on the reported module."""

    module: str | None
    reason: str
    accident: bool
    cleared: tuple[str, ...]
    baseline: str
    runs: tuple[Json, ...]
    stance: str


@dataclass(frozen=True, kw_only=True)
class ConfidenceResult(JsonCodec):
    """The confidence phase: the references' answers (the chosen reference's first), the
    adopted one's triggering entity (when another reference was adopted), their agreement,
    the index of the adopted answer, module substitution's answer, the level (stable,
    contested or unstable), the note in words, and the revisions of the deviating module
    this phase made (walk_passed, adopted_reference; in that order)."""

    PHASE: ClassVar[str] = "confidence"
    answers: tuple[ReferenceAnswer, ...]
    triggering_entity: TriggeringEntity | None = omitted()
    agreement: Agreement
    adopted: int
    second_opinion: SecondOpinionRecord | None = omitted()
    level: str
    note: str
    revisions: tuple[ModuleRevision, ...] = ()


# ---- phase IV -----------------------------------------------------------------------------


@dataclass(frozen=True)
class ShrunkFix(JsonCodec):
    """A search fix shrunk: the candidate, its shrunk values, h2 [-], the smallest gap to
    anything it kept [m] (None: nothing was near), the path driven [m], and whether it left
    the ego standing where the accident did."""

    search: CandidateRecord
    shrunk: Mapping[str, float]
    h2: float
    min_separation_m: float | None
    driven_m: float
    stalled: bool


@dataclass(frozen=True)
class AlternativeFix(JsonCodec):
    """A fix nearly as small as the chosen one (h2 within the tolerance)."""

    h2: float
    misconfiguration: tuple[ParameterChange, ...]


@dataclass(frozen=True)
class OtherFix(JsonCodec):
    """A larger fix that also avoids the accident: h2, its changes, the smallest gap [m] and
    whether it stalled."""

    h2: float
    misconfiguration: tuple[ParameterChange, ...]
    min_separation_m: float | None
    stalled: bool


@dataclass(frozen=True)
class SearchSummary(JsonCodec):
    """A cyber search in short: its module, parameters, simulations and fixes found."""

    module: str | None
    parameters: int
    evaluations: int
    feasible: int


@dataclass(frozen=True)
class CyberResult(JsonCodec):
    """Phase IV: the cyber search over a module's parameters and the minimisation of its fixes.

    Attributes:
        module, scope, parameters: the module searched ("all": None), the scope, the count.
        generations, evaluations, feasible: the search's generations, simulations, fixes.
        first_fix_evaluation, first_fix_batch_evaluations: simulations up to the first fix.
        nearest_fix: when no fix keeps the ego's earlier trajectory, the one closest to it.
        search_best, minimise_evaluations, shrunk_candidates: the minimisation.
        fix: the chosen fix (parameter -> value), and ``misconfiguration`` its changes.
        alternatives, other_fixes: nearly as small fixes, and larger ones.
        second_suspect: the second suspect's search that found no fix either.
        named_module, named_module_search: when the fix is the second suspect's, the module
            the walk named and its search; ``revision`` then makes the suspect's module the
            deviating one.
    """

    PHASE: ClassVar[str] = "cyber"
    module: str | None
    scope: str
    parameters: int
    generations: tuple[GenerationRecord, ...]
    evaluations: int
    feasible: int
    first_fix_evaluation: int | None
    first_fix_batch_evaluations: int | None
    nearest_fix: CandidateRecord | None = omitted()
    search_best: CandidateRecord | None = omitted()
    minimise_evaluations: int | None = omitted()
    shrunk_candidates: tuple[ShrunkFix, ...] | None = omitted()
    fix: Mapping[str, float] | None = omitted()
    misconfiguration: tuple[ParameterChange, ...] | None = omitted()
    alternatives: tuple[AlternativeFix, ...] | None = omitted()
    other_fixes: tuple[OtherFix, ...] | None = omitted()
    second_suspect: SearchSummary | None = omitted()
    named_module: str | None = omitted()
    named_module_search: SearchSummary | None = omitted()
    revision: ModuleRevision | None = omitted()

    def summary(self) -> SearchSummary:
        return SearchSummary(self.module, self.parameters, self.evaluations, self.feasible)


# ---- phase V ------------------------------------------------------------------------------


@dataclass(frozen=True)
class RegressionTest(JsonCodec):
    """The sequential sign test (:func:`rocas.pipeline.sequential.regression_test`): variants
    compared, those only the fix / only the original avoids, p value, level per look, the
    decision ("fix_better", "fix_worse" or None) and whether it stopped before the last."""

    variants: int
    fix_only: int
    original_only: int
    p_value: float
    alpha_per_look: float
    decision: str | None
    stopped_early: bool


@dataclass(frozen=True)
class StrongerValue(JsonCodec):
    """A value past the minimal fix: the fraction of the way to the range's end, its values,
    whether it avoids the accident, its h1 [m^2], its success rate over the variants (None:
    not run) and why it was skipped."""

    fraction: float
    fix: Mapping[str, float]
    avoids_accident: bool
    h1_m2: float
    success_rate: float | None
    skipped: str | None = omitted()


@dataclass(frozen=True)
class RobustFix(JsonCodec):
    """The robust value: its values, success rate over the variants and fraction."""

    fix: Mapping[str, float]
    success_rate: float
    fraction: float


@dataclass(frozen=True)
class ValidationResult(JsonCodec):
    """Phase V: the regression test over ``variants`` perturbed variants (success rates are
    shares in [0, 1] of accident-free runs; None without variants) and the sweep of stronger
    values; ``simulations`` run, of ``simulations_without_stopping`` at most."""

    PHASE: ClassVar[str] = "validation"
    variants: int
    success_rate_original: float | None
    original_variants: int
    success_rate_fixed: float | None
    fix_makes_it_worse: bool
    regression_test: RegressionTest | None
    stronger: tuple[StrongerValue, ...]
    robust_fix: RobustFix | None
    simulations: int
    simulations_without_stopping: int


#: a phase's result
PhaseResult = (ReplayResult | PhysicalResult | DiffPhaseResult | ConfidenceResult | CyberResult
               | ValidationResult)

#: the result type of each phase, in phase order
RESULT_TYPES: dict[str, type] = {t.PHASE: t for t in (  # type: ignore[attr-defined]
    ReplayResult, PhysicalResult, DiffPhaseResult, ConfidenceResult, CyberResult,
    ValidationResult)}


def revisions_of(results: Mapping[str, Any]) -> list[ModuleRevision]:
    """Every revision of the deviating module among the phase ``results`` (phase -> result),
    in phase order."""
    out: list[ModuleRevision] = []
    conf = results.get("confidence")
    if conf is not None:
        out += conf.revisions
    cyber = results.get("cyber")
    if cyber is not None and cyber.revision is not None:
        out.append(cyber.revision)
    return out
