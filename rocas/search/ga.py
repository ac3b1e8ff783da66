"""A constrained multi-objective genetic search (NSGA-II from pymoo), driven ask-and-tell.

The caller supplies ``evaluate(mutations) -> [(objectives, constraint)]`` for a whole batch
(where it fans out to an executor). ``constraint <= 0`` means the accident is avoided; a
graded value (e.g. how far the run was from being safe) guides the search towards
feasibility. After each generation the evaluations so far can be checkpointed as JSON (data,
never code: a checkpoint from someone else's run directory cannot run anything). A resumed
search replays the same seeded NSGA-II from the start, answering every evaluation it already
has from the checkpoint, so it reaches the interrupted generation without a simulation and
continues exactly as an uninterrupted search would.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rocas._fs import atomic_path
from rocas.errors import InputError, UsageError
from rocas.search.space import Mutation, MutationSpace

Evaluation = tuple[tuple[float, ...], float]  # (objectives, constraint: <= 0 is feasible)
BatchEvaluate = Callable[[list[Mutation]], list[Evaluation]]


@dataclass(frozen=True)
class SearchConfig:
    """Budget and settings of one search.

    Attributes:
        population: individuals per generation.
        generations: number of generations (a fixed termination: pymoo's default may run
            to 1000).
        seed: random seed.
        single_property_share: fraction of the first population made of single-property
            mutants (the rest mutates each variable with probability ``mutate_prob``).
        mutate_prob: per-variable mutation probability of the random part.
        stop_when_feasible_after: stop early once this many generations have run and a
            feasible candidate exists (0 = never stop early).
        screen: before the first generation, evaluate every variable alone at the two ends
            of its range (in a seeded random order; counted as generation 0) and start the
            search from the best screened individuals: with a graded constraint this shows
            which variables matter at the cost of two simulations per variable.
    """

    population: int = 24
    generations: int = 10
    seed: int = 0
    single_property_share: float = 1.0
    mutate_prob: float = 0.2
    stop_when_feasible_after: int = 0
    screen: bool = False

    def __post_init__(self) -> None:
        if self.population < 2 or self.generations < 1:
            raise UsageError("a search needs a population of at least 2 and >= 1 generation")


@dataclass(frozen=True)
class Candidate:
    """One evaluated individual.

    Attributes:
        mutation: what it changes.
        objectives: its objective values (minimised).
        constraint: <= 0 when the accident is avoided.
        generation: the generation it was evaluated in.
    """

    mutation: Mutation
    objectives: tuple[float, ...]
    constraint: float
    generation: int

    @property
    def feasible(self) -> bool:
        return self.constraint <= 0


@dataclass
class GenerationStats:
    """What one generation produced (for progress bars and the Rerun timeline)."""

    generation: int
    evaluations: int
    feasible: int
    best_constraint: float
    objectives: np.ndarray  # (population, n_obj)
    constraints: np.ndarray  # (population,)


@dataclass
class SearchResult:
    """All evaluated candidates, the feasible Pareto front and per-generation stats."""

    candidates: list[Candidate]
    front: list[Candidate]
    generations: list[GenerationStats] = field(default_factory=list)

    @property
    def evaluations(self) -> int:
        return len(self.candidates)

    @property
    def feasible(self) -> list[Candidate]:
        return [c for c in self.candidates if c.feasible]


@dataclass
class _State:
    algorithm: Any
    problem: Any
    candidates: list[Candidate]
    generations: list[GenerationStats]
    cache: dict[Mutation, Evaluation]
    replayed: int = 0  # generations a resumed search re-runs from its checkpoint (no callback)


CHECKPOINT_FORMAT = "rocas-search-checkpoint"
CHECKPOINT_VERSION = 1


def _initial_population(space: MutationSpace, cfg: SearchConfig) -> np.ndarray:
    rng = np.random.default_rng(cfg.seed)
    n_single = int(round(cfg.population * cfg.single_property_share))
    parts = [space.single_property_seeds(n_single, rng)] if n_single else []
    if cfg.population - n_single:
        parts.append(space.sample(cfg.population - n_single, rng, cfg.mutate_prob))
    return np.vstack(parts)


def run_search(
    space: MutationSpace,
    evaluate: BatchEvaluate,
    cfg: SearchConfig,
    n_objectives: int,
    *,
    checkpoint: str | os.PathLike[str] | None = None,
    on_generation: Callable[[GenerationStats], None] | None = None,
    screening_suffices: Callable[[list[Candidate]], bool] | None = None,
) -> SearchResult:
    """Run NSGA-II over ``space``; resumes from ``checkpoint`` when it exists.

    Identical mutations are evaluated once (results are cached per search). With
    ``cfg.screen``, each variable is first tried alone at both ends of its range and halfway
    from its original to each end (:func:`screening_genomes`), and
    ``screening_suffices(candidates)`` may end the search after the screening:
    what the screening found does not depend on the seed (its order does, its results do not),
    so a caller that chooses among the screened candidates gets the same answer at every seed.
    """
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.termination import get_termination

    from rocas.search._problem import SearchProblem
    from rocas.search._survival import StableRankAndCrowding, quantize

    ckpt = Path(checkpoint) if checkpoint else None
    problem = SearchProblem(space.n_genes, n_objectives)
    state = _State(None, problem, [], [], {})
    if ckpt is not None and ckpt.exists():
        state.candidates, state.replayed = _load_checkpoint(ckpt, space, cfg)
        state.cache = {c.mutation: (c.objectives, c.constraint) for c in state.candidates}
    sampling = _initial_population(space, cfg)
    if cfg.screen:
        sampling = _screen(space, evaluate, cfg, state, on_generation)
        if screening_suffices is not None and screening_suffices(state.candidates):
            return SearchResult(state.candidates, pareto_front(state.candidates), state.generations)
    algorithm = NSGA2(pop_size=cfg.population, sampling=sampling, eliminate_duplicates=True,
                      survival=StableRankAndCrowding())
    algorithm.setup(problem, termination=get_termination("n_gen", cfg.generations),
                    seed=cfg.seed, verbose=False)
    state.algorithm = algorithm

    algo, problem = state.algorithm, state.problem
    while algo.has_next():
        gen = algo.n_gen if algo.n_gen is not None else 1
        pop = algo.ask()
        genomes = quantize(pop.get("X"))
        pop.set("X", genomes)
        mutations = [space.decode(g) for g in genomes]
        todo = list(dict.fromkeys(m for m in mutations if m not in state.cache))
        for m, ev in zip(todo, evaluate(todo), strict=True):
            state.cache[m] = ev
            state.candidates.append(Candidate(m, tuple(ev[0]), float(ev[1]), gen))
        f = np.array([state.cache[m][0] for m in mutations], dtype=float).reshape(len(mutations), -1)
        g = np.array([[state.cache[m][1]] for m in mutations], dtype=float)
        problem.pending = (f, g)
        algo.evaluator.eval(problem, pop)
        problem.pending = None
        algo.tell(infills=pop)
        stats = GenerationStats(gen, len(state.candidates), int((g[:, 0] <= 0).sum()),
                                float(g.min()), f, g[:, 0])
        state.generations.append(stats)
        replaying = len(state.generations) <= state.replayed
        if on_generation is not None and not replaying:
            on_generation(stats)
        if ckpt is not None and not replaying:
            _write_checkpoint(ckpt, space, cfg, state)
        if (cfg.stop_when_feasible_after and gen >= cfg.stop_when_feasible_after
                and any(c.feasible for c in state.candidates)):
            break

    return SearchResult(state.candidates, pareto_front(state.candidates), state.generations)


def _identity(space: MutationSpace, cfg: SearchConfig) -> dict[str, Any]:
    return {"variables": [v.name for v in space.variables],
            "config": {k: getattr(cfg, k) for k in cfg.__dataclass_fields__}}


def _write_checkpoint(ckpt: Path, space: MutationSpace, cfg: SearchConfig, state: _State) -> None:
    doc = {"format": CHECKPOINT_FORMAT, "version": CHECKPOINT_VERSION, **_identity(space, cfg),
           "generations": len(state.generations),
           "candidates": [{"values": dict(c.mutation.values), "objectives": list(c.objectives),
                           "constraint": c.constraint, "generation": c.generation}
                          for c in state.candidates]}
    with atomic_path(ckpt) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        json.dump(doc, fh, allow_nan=True)


def _load_checkpoint(ckpt: Path, space: MutationSpace, cfg: SearchConfig
                     ) -> tuple[list[Candidate], int]:
    """The candidates a checkpoint holds and the number of generations it had completed.

    Raises:
        InputError: the file cannot be read, is not a search checkpoint (truncated,
            overwritten, or written by an incompatible version), or belongs to another search.
    """
    hint = f"delete {ckpt} to restart this search from its first generation"
    from rocas._limits import loads_json, read_bytes_limited

    try:  # bounded in size and depth: a run directory may come from someone else
        data = read_bytes_limited(ckpt, what="search checkpoint")
    except InputError as exc:
        raise InputError(f"cannot read search checkpoint {ckpt}: {exc.message}", hint) from None
    try:
        doc = loads_json(data, origin=str(ckpt))
    except InputError as exc:
        raise InputError(f"search checkpoint {ckpt} is damaged (not JSON: {exc.message})", hint) from None
    if not isinstance(doc, dict) or doc.get("format") != CHECKPOINT_FORMAT:
        raise InputError(f"search checkpoint {ckpt} does not hold a search state", hint)
    if doc.get("version") != CHECKPOINT_VERSION:
        raise InputError(f"search checkpoint {ckpt} has version {doc.get('version')!r}; this rocas "
                         f"reads version {CHECKPOINT_VERSION}", hint)
    if {k: doc.get(k) for k in ("variables", "config")} != _identity(space, cfg):
        raise InputError(f"search checkpoint {ckpt} belongs to another search (other variables "
                         "or settings)", hint)
    names = set(doc["variables"])
    try:
        candidates = [_candidate(c, names) for c in doc["candidates"]]
        generations = int(doc["generations"])
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"search checkpoint {ckpt} is damaged ({type(exc).__name__}: {exc})",
                         hint) from None
    return candidates, generations


def _candidate(c: dict[str, Any], names: set[str]) -> Candidate:
    values = c["values"]
    if not isinstance(values, dict) or not set(values) <= names \
            or not all(isinstance(v, bool | int | float | str) for v in values.values()):
        raise ValueError("a candidate's values are not a mapping of the space's variables")
    objectives = tuple(float(o) for o in c["objectives"])
    constraint = float(c["constraint"])
    if math.isnan(constraint):
        raise ValueError("a candidate's constraint is NaN")
    return Candidate(Mutation(values), objectives, constraint, int(c["generation"]))


def screening_genomes(space: MutationSpace, seed: int) -> np.ndarray:
    """Single-variable genomes, variables in a seeded random order: each variable alone at
    both ends of its range and, for real and integer variables, halfway from its original
    value to each end (a bool's or an enum's ends are all its values); shape (n, n_genes),
    n <= 4 * n_vars. The ends can overshoot a fix that lies inside a range (a buffer that
    repairs at 0.1-0.3 m brakes hard elsewhere at 0 m)."""
    base = space.encode(Mutation())
    order = np.random.default_rng(seed).permutation(len(space.variables))
    out = []
    for i in order:
        var = space.variables[i]
        u0 = var.encode(var.original)
        values = (0.0, 1.0) + (((u0 + 0.0) / 2.0, (u0 + 1.0) / 2.0)
                               if var.kind in ("real", "int") else ())
        for u in values:
            g = base.copy()
            g[2 * i], g[2 * i + 1] = 0.75, u
            out.append(g)
    return np.array(out).reshape(len(out), space.n_genes)


def screening_mutations(space: MutationSpace, seed: int) -> list[Mutation]:
    """The distinct mutations the screening simulates, in its order: the screening genomes
    (:func:`screening_genomes`) decoded, less those that change nothing (a value that is
    already the parameter's)."""
    return list(dict.fromkeys(m for m in (space.decode(g) for g in screening_genomes(space, seed))
                              if m.values))


def _screen(space: MutationSpace, evaluate: BatchEvaluate, cfg: SearchConfig, state: _State,
            on_generation: Callable[[GenerationStats], None] | None) -> np.ndarray:
    """Simulate the screening genomes (:func:`screening_genomes`; candidates of generation 0)
    and return the first population of the genetic search: the best screened."""
    todo = [m for m in screening_mutations(space, cfg.seed) if m not in state.cache]
    for m, ev in zip(todo, evaluate(todo), strict=True):
        state.cache[m] = ev
        state.candidates.append(Candidate(m, tuple(ev[0]), float(ev[1]), 0))
    screened = [c for c in state.candidates if c.generation == 0]
    if screened:
        f = np.array([c.objectives for c in screened], dtype=float)
        g = np.array([c.constraint for c in screened], dtype=float)
        stats = GenerationStats(0, len(screened), int((g <= 0).sum()), float(g.min()), f, g)
        state.generations.append(stats)
        if on_generation is not None and state.replayed == 0:
            on_generation(stats)
    ranked = sorted(screened, key=lambda c: (c.constraint > 0, c.constraint, sum(c.objectives)))
    best = [space.encode(c.mutation) for c in ranked[: cfg.population]]
    if len(best) < cfg.population:
        rng = np.random.default_rng(cfg.seed)
        best += list(space.sample(cfg.population - len(best), rng, cfg.mutate_prob))
    return np.array(best)


def pareto_front(candidates: Sequence[Candidate]) -> list[Candidate]:
    """Feasible candidates not dominated by another feasible one (stable order)."""
    feas = [c for c in candidates if c.feasible]
    front = []
    for c in feas:
        dominated = any(
            all(o <= p for o, p in zip(d.objectives, c.objectives, strict=True))
            and any(o < p for o, p in zip(d.objectives, c.objectives, strict=True))
            for d in feas
        )
        if not dominated:
            front.append(c)
    return front
