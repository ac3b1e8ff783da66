"""Mutation spaces, objectives, executors, the genetic search and fix minimisation."""

from rocas.search.executor import (
    Executor,
    LocalExecutor,
    SerialExecutor,
    executor_names,
    make_executor,
    register_executor,
)
from rocas.search.ga import Candidate, SearchConfig, SearchResult, pareto_front, run_search
from rocas.search.minimize import (
    shrink_all_magnitudes,
    shrink_magnitudes,
    shrink_set,
    shrink_sets,
)
from rocas.search.objectives import (
    ego_dissimilarity,
    scenario_dissimilarity,
    suspiciousness,
    trajectory_mse,
)
from rocas.search.space import Mutation, MutationSpace, Variable

__all__ = [
    "Candidate",
    "Executor",
    "LocalExecutor",
    "Mutation",
    "MutationSpace",
    "SearchConfig",
    "SearchResult",
    "SerialExecutor",
    "Variable",
    "ego_dissimilarity",
    "executor_names",
    "make_executor",
    "pareto_front",
    "register_executor",
    "run_search",
    "scenario_dissimilarity",
    "shrink_all_magnitudes",
    "shrink_magnitudes",
    "shrink_set",
    "shrink_sets",
    "suspiciousness",
    "trajectory_mse",
]
