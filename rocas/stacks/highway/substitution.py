"""A second opinion on the highway ego's deviating module, by module substitution.

The co-mutation (:mod:`rocas.stacks.highway.comutation`) names the deviating module from a
diff against an accident-free reference. Module substitution needs no reference: run the
accident again with one module replaced by an idealised one and see whether the accident
disappears (as :mod:`rocas.pipeline.substitution` does for the built-in stack).

For highway-env's IDM/MOBIL ego the three seams substitute differently:

- **Perception** is already ideal: the driver reads its neighbours from highway-env's true
  state (``road.neighbour_vehicles``), so its ground-truth substitute is the run itself. It is
  cleared by construction.
- **Control** has an ideal substitute (:mod:`rocas.stacks.highway.ideal`): planning's
  decision executed exactly, bounded only by physics (one g, a steering lock), none of the
  control parameters read. If the accident disappears under ideal control, control is
  implicated. If it persists, control is cleared, and with perception exact the cause lies
  in planning, or the accident is one no driver could avoid (the scene's own, such as a
  stopped car closer than one g can stop from): substitution cannot tell these apart, so
  its "planning" is a conclusion by elimination.
- **Planning** has no honest ideal substitute. There is no ground-truth plan: an "ideal"
  IDM/MOBIL with the driver's declared default parameters is the restoration of defaults
  (the co-mutation's cyber search, not a second opinion), and any other planner (one that
  knows the others' futures, say) is a different driver whose success says nothing about
  this one's planning: the others react to the ego, so even their futures are not ground
  truth. None is built.

So one substitution run per accident, besides the run as it is: two simulations in all.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from rocas.stacks.highway.scene import Scene
from rocas.stacks.highway.world import RunResult, accident_kind, avoids, simulate

Stance = Literal["agrees", "consistent", "disagrees", "undetermined"]

#: modules whose ideal counterpart equals the run itself (highway-env's exact neighbours)
EXACT = ("perception",)


@dataclass(frozen=True)
class SubstitutionRun:
    """One run of the accident's scene, seed and parameters.

    Attributes:
        substituted: the modules replaced by their ideal counterpart (empty: the ego as it is).
        accident: a collision or leaving the road within the scene's duration.
        collided: the ego crashed (highway-env's collision check).
        off_road: the ego left the road before any crash.
        accident_t_s: when the accident was detected [s] (None without one).
        collided_with: id of the vehicle hit (-1 none, 0 an object on the road).
        ticks: ticks simulated (the last is the accident's, if any).
        min_margin_m: smallest clearance to another vehicle or road object [m].
        digest: SHA-256 of the trajectories (:meth:`RunResult.digest`).
    """

    substituted: tuple[str, ...]
    accident: bool
    collided: bool
    off_road: bool
    accident_t_s: float | None
    collided_with: int
    ticks: int
    min_margin_m: float
    digest: str

    @classmethod
    def of(cls, substituted: tuple[str, ...], r: RunResult) -> SubstitutionRun:
        return cls(substituted, r.accident, r.collided, r.off_road, r.accident_t_s,
                   r.collided_with, len(r.times), r.min_margin_m, r.digest())

    def what(self) -> str:
        """The accident in words: ``"off the road"``, ``"hit vehicle 2"``, ``"hit an object"``
        (``"none"`` without one)."""
        if self.off_road:
            return "off the road"
        if self.collided:
            return f"hit vehicle {self.collided_with}" if self.collided_with > 0 else "hit an object"
        return "none"

    def same_accident(self, other: SubstitutionRun) -> bool:
        """Both runs have an accident of the same kind with the same partner (off the road,
        or a collision with the same vehicle or with a road object), whenever it happens
        (:func:`rocas.stacks.highway.world.accident_kind`)."""
        return self.accident and accident_kind(self) == accident_kind(other)

    def to_dict(self) -> dict[str, Any]:
        return {"substituted": list(self.substituted), "accident": self.accident,
                "collided": self.collided, "off_road": self.off_road,
                "accident_t_s": self.accident_t_s, "collided_with": self.collided_with,
                "ticks": self.ticks, "min_margin_m": self.min_margin_m}


@dataclass(frozen=True)
class SubstitutionOpinion:
    """What module substitution says about a highway accident.

    Attributes:
        accident: whether the run with the ego as it is has an accident to explain.
        baseline: that run.
        ideal_control: the run with ideal control.
        module: ``"control"`` when ideal control avoids the accident, ``"planning"`` when it
            persists (by elimination: perception is exact; the accident may also be
            unavoidable), None without an accident or when ideal control's run meets another
            accident first (:func:`second_opinion`).
        reason: one sentence saying how ``module`` was chosen or why there is none.
        cleared: modules whose ideal counterpart leaves the accident (perception always, as
            it is exact; control when the accident persists under ideal control).
    """

    accident: bool
    baseline: SubstitutionRun
    ideal_control: SubstitutionRun
    module: str | None
    reason: str
    cleared: tuple[str, ...]

    def stance(self, module: str | None) -> Stance:
        """How this opinion relates to ``module``, the deviating module another method named
        (None: it named none).

        - ``agrees``: substitution names the same module.
        - ``consistent``: substitution names planning by elimination and the other method
          named no driver module (None, the world or the vehicle): both allow an accident
          that belongs to the scene; or substitution names none and ``module`` is not one
          it cleared.
        - ``disagrees``: substitution names another module, or cleared ``module``.
        - ``undetermined``: the run has no accident to explain.
        """
        if not self.accident:
            return "undetermined"
        if self.module is None:  # ideal control met another accident first
            return "disagrees" if module in self.cleared else "consistent"
        if module == self.module:
            return "agrees"
        if self.module == "planning" and module not in self.cleared:
            return "consistent"
        return "disagrees"

    @property
    def other_accident(self) -> bool:
        """Whether ideal control's run has an accident other than this one."""
        return self.ideal_control.accident and not self.ideal_control.same_accident(
            self.baseline)

    def to_dict(self) -> dict[str, Any]:
        return {"module": self.module, "reason": self.reason, "accident": self.accident,
                "cleared": list(self.cleared), "baseline": self.baseline.to_dict(),
                "ideal_control": self.ideal_control.to_dict(),
                "other_accident": self.other_accident}


def second_opinion(scene: Scene, params: Mapping[str, float] | None = None,
                   seed: int = 0) -> SubstitutionOpinion:
    """Run the accident as it is and with ideal control (two simulations, serial) and name
    the module substitution implicates (:func:`judge`).

    The accident "disappears" under ideal control when that run has no accident, or has
    another one (:meth:`SubstitutionRun.same_accident`) only after the accident's time: a
    different trajectory can meet a different hazard later, which is not this accident.
    Another accident before it leaves no conclusion (``module`` None).

    Args:
        scene: the accident's scene.
        params: the ego driver's parameter overrides the accident ran with (full names).
        seed: rocas's seed of the accident.
    """
    baseline = SubstitutionRun.of((), simulate(scene, params, seed))
    ideal = SubstitutionRun.of(("control",), simulate(scene, params, seed,
                                                      substitute="control"))
    return judge(baseline, ideal)


def judge(baseline: SubstitutionRun, ideal: SubstitutionRun) -> SubstitutionOpinion:
    """The opinion from the run as it is and the run with ideal control
    (:func:`second_opinion`'s rule)."""
    if not baseline.accident:
        return SubstitutionOpinion(False, baseline, ideal, None,
                                   "the run has no accident with the ego as it is", EXACT)
    if ideal.same_accident(baseline):
        return SubstitutionOpinion(
            True, baseline, ideal, "planning",
            "ideal control leaves the accident and perception is exact: the cause is "
            "planning, or no driver could avoid it", (*EXACT, "control"))
    if not ideal.accident:
        return SubstitutionOpinion(True, baseline, ideal, "control",
                                   "ideal control avoids the accident (perception is exact)",
                                   EXACT)
    t_ideal = ideal.accident_t_s or 0.0
    if avoids(ideal, baseline):  # another accident, no earlier than this one
        return SubstitutionOpinion(
            True, baseline, ideal, "control",
            f"ideal control avoids the accident (perception is exact); its run meets another "
            f"one ({ideal.what()}) at {t_ideal:.2f} s", EXACT)
    return SubstitutionOpinion(
        True, baseline, ideal, None,
        f"ideal control meets another accident ({ideal.what()}) at {t_ideal:.2f} s, before "
        f"this one's time: substitution cannot tell", EXACT)


__all__ = ["EXACT", "Stance", "SubstitutionOpinion", "SubstitutionRun", "judge", "second_opinion"]
