"""Simulations as pure functions of picklable inputs, fanned out over an executor.

A :class:`VariantTask` (scenario, parameter overrides, seed) maps to a :class:`VariantResult`
(outcome and trajectories). Tasks are grouped into batches for the simulator's batch mode and
the batches are mapped over an executor; since a variant's result does not depend on the
batch it runs in, the results depend only on the tasks: the same whatever the batch size,
the number of workers or the executor.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocas.scenarios.model import Scenario
from rocas.search.executor import Executor
from rocas.sim.oracles import Outcome


@dataclass(frozen=True)
class VariantTask:
    """One simulation to run.

    Attributes:
        scenario: the (possibly mutated) scenario.
        params: the stack's parameter overrides on top of the scenario's own.
        seed: the simulation seed.
    """

    scenario: Scenario
    params: tuple[tuple[str, float], ...] = ()
    seed: int = 0


@dataclass(frozen=True)
class VariantResult:
    """What a search needs from one simulation.

    Attributes:
        outcome: the oracles' verdict.
        ego_xy: (T + 1, 2) ego positions [m].
        actors_xy: (T + 1, A, 2) actor positions [m].
    """

    outcome: Outcome
    ego_xy: np.ndarray
    actors_xy: np.ndarray


def run_batch(tasks: Sequence[VariantTask],
              outputs: Mapping[int, str | os.PathLike[str]] | None = None) -> list[VariantResult]:
    """Simulate tasks that share one scenario structure in one batch (picklable entry point),
    with the stack their scenario names; ``outputs`` (task index -> MCAP file) also records
    those tasks, each the very file its run alone records
    (:func:`rocas.rollout.simulate_batch`)."""
    from rocas.rollout import simulate_batch

    res = simulate_batch([t.scenario for t in tasks], params=[dict(t.params) for t in tasks],
                         seeds=[t.seed for t in tasks], outputs=outputs)
    return [
        VariantResult(res.outcomes[i], np.ascontiguousarray(res.ego[i, :, :2]),
                      np.ascontiguousarray(res.actors[i, :, :, :2]))
        for i in range(len(tasks))
    ]


def run_job(job: tuple[Sequence[VariantTask], Sequence[tuple[VariantTask, str]]]
            ) -> list[VariantResult]:
    """``run_batch`` of a batch's tasks with further runs to record appended to it as extra
    rows (``(task, MCAP path)``); the results of the tasks only (picklable entry point)."""
    tasks, recordings = job
    rows = [*tasks, *(t for t, _ in recordings)]
    outputs = {len(tasks) + k: path for k, (_, path) in enumerate(recordings)}
    return run_batch(rows, outputs)[:len(tasks)]


def record(runs: Sequence[tuple[VariantTask, str | os.PathLike[str]]]) -> list[VariantResult]:
    """Record each task to its MCAP file, as ``simulate(..., output=path)`` would, in one batch
    in this process: independent recordings share one batch's fixed cost per tick (about
    2 ms a tick whatever the batch's size), and each file is bit for bit its run alone's.
    The tasks must share one scenario structure."""
    if not runs:
        return []
    return run_batch([t for t, _ in runs], {i: path for i, (_, path) in enumerate(runs)})


#: the smallest batch worth a worker of its own: tasks that fill one batch but give each of
#: several workers at least this many are split among them. On A9 one core runs 100 variants
#: in 0.96 s of CPU and 200 in 1.45 s, so two workers of 100 finish 1.5x sooner than one of
#: 200; below about 64 a batch's fixed cost per tick eats the gain.
PARALLEL_MIN_BATCH = 64


def evaluate(executor: Executor, tasks: Sequence[VariantTask], batch_size: int = 256,
             recordings: Sequence[tuple[VariantTask, str | os.PathLike[str]]] = ()
             ) -> list[VariantResult]:
    """Run ``tasks`` in batches of at most ``batch_size`` on ``executor``; results in task order.

    The simulator's throughput grows with the batch (its cost per tick is mostly fixed), so
    tasks are split only as far as they must be: into as few equal batches as ``batch_size``
    allows, and, when that is more than one or the tasks give every worker at least
    PARALLEL_MIN_BATCH, into a multiple of the executor's workers so none waits idle. Fewer
    tasks run as one batch (a local executor runs a single batch in this process, without
    starting workers).

    ``recordings`` (``(task, MCAP path)``, tasks of the same scenario structure) are recorded
    as extra rows of the first batch, each the file its run alone writes: a recording costs
    the batch a few milliseconds instead of a rollout's fixed cost; their results are not
    returned. Without tasks they run as one batch here."""
    tasks = list(tasks)
    if not tasks:
        record(recordings)
        return []
    batches = batches_of(tasks, batch_size, max(1, getattr(executor, "workers", 1)))
    out: list[VariantResult] = []
    if recordings:
        jobs = [(b, [(t, os.fspath(p)) for t, p in recordings] if i == 0 else [])
                for i, b in enumerate(batches)]
        chunks = executor.map(run_job, jobs)
    else:
        chunks = executor.map(run_batch, batches)
    for chunk in chunks:
        out.extend(chunk)
    return out


def batches_of(tasks: list[VariantTask], batch_size: int, workers: int) -> list[list[VariantTask]]:
    """How :func:`evaluate` groups ``tasks`` (at least one) into batches for ``workers``."""
    count = -(-len(tasks) // max(1, batch_size))
    if count > 1 or (workers > 1 and len(tasks) >= workers * PARALLEL_MIN_BATCH):
        count = min(len(tasks), -(-count // workers) * workers)
    size = -(-len(tasks) // count)
    return [tasks[i:i + size] for i in range(0, len(tasks), size)]


def prepare_worker() -> None:
    """What a worker imports before its first task (see ``warm_up`` of
    :class:`~rocas.search.executor.LocalExecutor`): the simulation with the built-in ADS."""
    import rocas.rollout  # noqa: F401
    import rocas.stacks.ads.run  # noqa: F401


def params_tuple(overrides: Mapping[str, float]) -> tuple[tuple[str, float], ...]:
    return tuple(sorted((k, float(v)) for k, v in overrides.items()))


def is_accident(outcome: Outcome) -> bool:
    """A collision or an emergency (hard brake, estop, unexpected stop)."""
    return bool(outcome.collided or outcome.emergency)


def violation(outcome: Outcome) -> float:
    """The graded constraint: <= 0 when the run is accident-free, > 0 otherwise.

    Accident runs score 1 plus how bad they were (penetration depth [m] for collisions,
    deceleration beyond 4 m/s^2 for emergencies, in units of 4 m/s^2); accident-free runs
    score minus their safety margin (minimum separation, capped at 2 m, halved), so among
    feasible runs the safer ones are preferred.
    """
    if outcome.collided:
        return 1.0 + max(0.0, -outcome.min_separation_m)
    if outcome.emergency:
        return 1.0 + max(0.0, outcome.max_decel_mps2 - 4.0) / 4.0
    return -min(max(outcome.min_separation_m, 0.0), 2.0) / 2.0


@dataclass(frozen=True)
class Accident:
    """The accident of a run: kind ("collision" or "emergency"), time [s], other party."""

    kind: str
    time_s: float
    other: str | None

    @classmethod
    def of(cls, o: Outcome) -> Accident | None:
        if o.collided:
            return cls("collision", float(o.collision_time_s or 0.0), o.collision_with)
        if o.emergency:
            times = [t for t in (o.hard_brake_time_s, o.estop_time_s) if t is not None]
            return cls("emergency", float(min(times)) if times else 0.0, None)
        return None

    def to_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "time_s": round(self.time_s, 3), "other": self.other}
