"""The settings of an analysis (:class:`AnalyzeConfig`), its phases and verdicts, and the
simulation counts the progress bars plan with."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas.errors import UsageError
from rocas.search.ga import SearchConfig
from rocas.search.space import MutationSpace

PHASES = ("replay", "physical", "diff", "confidence", "cyber", "validation")
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
            range and halfway to each (up to four simulations per parameter, out of the
            budget); False runs a plain
            genetic search (the paper has no screening) from a population half single-parameter
            mutants, half random.
        alternate_references: how many other accident-free references (changing other
            properties than the chosen one) the accident is also diffed against, for the
            agreement of the deviating module (:mod:`rocas.pipeline.confidence`).
        stack: the registered stack that drives the accident instead of the one its
            scenario or recording names (``--stack-file``: an external command standing in for
            the stack it simulates, with that stack's parameters); None: the named one.
        second_opinion: also ask module substitution (ground-truth perception, prediction)
            which module's output the accident needs.
    """

    seed: int = 0
    budget: int = 240
    population: int = 24
    scope: str = "module"
    executor: str = "local"
    workers: int | None = None
    batch_size: int = 256
    delta_s: float = 3.0
    validation_variants: int = 200
    k_suspicion: float = 10.0
    h1_limit_m2: float = 1.0
    shrink_candidates: int = 3
    screening: bool = True
    alternate_references: int = 2
    second_opinion: bool = True
    stack: str | None = None

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
        whole(self.batch_size, 1, "batch_size", 256)
        real(self.delta_s, "--delta", 3.0)
        whole(self.validation_variants, 0, "--validation", 200)
        real(self.k_suspicion, "k_suspicion", 10.0, positive=True)
        real(self.h1_limit_m2, "h1_limit_m2", 1.0)
        whole(self.shrink_candidates, 1, "shrink_candidates", 3)
        whole(self.alternate_references, 0, "--references", 2)

    def search(self, stage: int, n_vars: int = 0) -> SearchConfig:
        """The search of stage 1 (physical: single-property seeds) or 2 (cyber).

        The budget rule (see :func:`planned_simulations`): stage 1 runs budget // population
        generations. Stage 2 with screening first tries each of its ``n_vars`` parameters
        alone at both ends of its range and halfway to each (up to four simulations per
        parameter, out of the budget), then runs (budget - 4 n_vars) // population
        generations, but at least 2: the first
        generation is the best screened mutants, already simulated, so at least one generation
        of new mutants always runs, even when the screening alone uses up the budget."""
        screen = stage == 2 and self.screening
        generations = (max(2, (self.budget - 4 * n_vars) // self.population) if screen
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
    """How many simulations the screening of ``space`` runs: up to four per parameter (two for
    a bool or an enum), less a value that is the parameter's value in force (an end of its
    range, or a halfway point of an integer: no change, nothing to simulate)."""
    from rocas.search.ga import screening_mutations

    return len(screening_mutations(space, seed))



#: settings of AnalyzeConfig that do not change the result (where and how simulations run)
_NOT_SETTINGS = ("executor", "workers")
#: ... and those the report lists (batch_size only groups simulations)
REPORT_SETTINGS = ("seed", "budget", "population", "scope", "screening", "delta_s",
                   "validation_variants", "h1_limit_m2", "k_suspicion", "shrink_candidates",
                   "alternate_references", "second_opinion")


def config_dict(cfg: AnalyzeConfig) -> dict[str, Any]:
    return {k: getattr(cfg, k) for k in cfg.__dataclass_fields__ if k not in _NOT_SETTINGS}

