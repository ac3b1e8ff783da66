"""A second opinion on the deviating module, by module substitution.

Algorithm 1 names the deviating module from the difference between the accident and an
accident-free reference. Module substitution asks the question the other way round, without
any reference: replay the accident scenario with one module's output replaced by ground truth
(:mod:`rocas.stacks.ads.oracle`) and see whether the accident disappears. The most upstream module, in
data-flow order, whose substitution alone removes the accident is the substitution's answer.
All runs (the ADS as it is, each substitutable module alone, all of them together) are one
batch of simulations.

Planning has no ground-truth substitute (there is no true plan), so substitution can only
point at perception or prediction, or clear them: when their ground truth leaves the accident
in place, the cause is downstream of them (planning, control) or the accident is unavoidable
for the ego. :meth:`SubstitutionOpinion.stance` turns that into agreement with a module named
by another method.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from rocas.rollout import ParamsLike, simulate_batch
from rocas.scenarios.model import Scenario
from rocas.sim.oracles import Outcome
from rocas.stacks.registry import get_stack

Stance = Literal["agrees", "consistent", "disagrees", "undetermined"]


@dataclass(frozen=True)
class SubstitutionRun:
    """One run of the accident scenario with ``modules`` publishing ground truth.

    Attributes:
        modules: the substituted modules, in data-flow order (empty: the ADS as it is).
        outcome: the run's outcome.
        avoided: the run has neither a collision nor an emergency (hard brake, estop,
            unexpected stop).
    """

    modules: tuple[str, ...]
    outcome: Outcome
    avoided: bool


@dataclass(frozen=True)
class SubstitutionOpinion:
    """What module substitution says about an accident.

    Attributes:
        accident: whether the scenario, with the ADS as it is, has an accident to explain.
        baseline: the outcome with the ADS as it is.
        runs: one run per substitution tried: each substitutable module alone, in data-flow
            order, then all of them together.
        module: the most upstream module whose substitution alone avoids the accident, or
            None (see ``reason``).
        reason: one sentence saying how ``module`` was chosen or why there is none.
        cleared: substitutable modules whose ground truth alone leaves the accident.
    """

    accident: bool
    baseline: Outcome
    runs: tuple[SubstitutionRun, ...]
    module: str | None
    reason: str
    cleared: tuple[str, ...]

    def run(self, *modules: str) -> SubstitutionRun:
        """The run with exactly ``modules`` substituted."""
        want = set(modules)
        for r in self.runs:
            if set(r.modules) == want:
                return r
        raise KeyError(f"no run substitutes {sorted(want)}")

    @property
    def jointly_avoided(self) -> bool:
        """Whether substituting every substitutable module together avoids the accident."""
        return self.runs[-1].avoided  # the last run substitutes them all

    def stance(self, module: str | None) -> Stance:
        """How this opinion relates to ``module``, the deviating module another method named
        (None: it named none).

        - ``agrees``: substitution names the same module.
        - ``consistent``: substitution names none, and ``module`` is not one it cleared (a
          module without a substitute, such as planning, or None when nothing avoided the
          accident; or one of the modules that only together avoid it).
        - ``disagrees``: substitution names another module, or cleared ``module``.
        - ``undetermined``: the scenario has no accident to explain.
        """
        if not self.accident:
            return "undetermined"
        if self.module is not None:
            return "agrees" if module == self.module else "disagrees"
        if self.jointly_avoided:
            return "consistent" if module in self.runs[-1].modules else "disagrees"
        return "disagrees" if module in self.cleared else "consistent"

    def to_dict(self) -> dict[str, Any]:
        return {
            "module": self.module, "reason": self.reason, "accident": self.accident,
            "cleared": list(self.cleared),
            "baseline": self.baseline.summary(),
            "runs": [{"substituted": list(r.modules), "avoided": r.avoided,
                      "outcome": r.outcome.summary()} for r in self.runs],
        }


def _clean(outcome: Outcome) -> bool:
    return not (outcome.collided or outcome.emergency)


def second_opinion(scenario: Scenario, params: ParamsLike = None, *,
                   seed: int | None = None) -> SubstitutionOpinion:
    """Run the accident with each substitutable module replaced by ground truth (one batch of
    the stack's substitutable modules + 2 simulations) and name the module whose substitution avoids it.

    Args:
        scenario: the accident scenario.
        params: the ADS parameter overrides the accident ran with.
        seed: the simulation seed (default: the scenario's).
    """
    substitutable = tuple(getattr(get_stack(scenario.ego.stack), "substitutable", ()))
    singles = [(m,) for m in substitutable]
    plans: list[tuple[str, ...]] = [(), *singles, substitutable]
    n = len(plans)
    res = simulate_batch([scenario] * n, params=[params] * n,
                         seeds=[scenario.seed if seed is None else seed] * n,
                         oracle_modules=[frozenset(p) for p in plans])
    outcomes = res.outcomes
    baseline = outcomes[0]
    runs = tuple(SubstitutionRun(p, o, _clean(o)) for p, o in zip(plans[1:], outcomes[1:],
                                                                   strict=True))
    single_runs = runs[:len(singles)]
    cleared = tuple(r.modules[0] for r in single_runs if not r.avoided)
    if _clean(baseline):
        return SubstitutionOpinion(False, baseline, runs, None,
                                   "the scenario has no accident with the ADS as it is",
                                   cleared)
    named = next((r.modules[0] for r in single_runs if r.avoided), None)
    if named is not None:
        upstream = substitutable[:substitutable.index(named)]
        reason = f"ground-truth {named} avoids the accident" + (
            f" ({', '.join(upstream)} ground truth does not)" if upstream else "")
    elif runs[-1].avoided:
        reason = (f"no module's ground truth alone avoids the accident; "
                  f"{' and '.join(substitutable)} together do")
    else:
        reason = (f"ground truth from {' and '.join(substitutable)} leaves the accident: its "
                  f"cause is downstream (planning or control, which have no ground truth) or "
                  f"the ego could not avoid it")
    return SubstitutionOpinion(True, baseline, runs, named, reason, cleared)


__all__ = ["Stance", "SubstitutionOpinion", "SubstitutionRun", "second_opinion"]
