"""Executors: where a batch of simulations runs.

An executor maps a *pure, picklable* function over a list of picklable tasks and returns
the results in task order. Results therefore depend only on the tasks, never on the number
of workers, the batch size or the executor, which is what makes a search reproducible and
what lets a distributed engine take over later: it only has to implement ``map``.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from types import TracebackType
from typing import Any, Protocol, TypeVar

from rocas.errors import UsageError

T = TypeVar("T")
R = TypeVar("R")


class Executor(Protocol):
    """What the searches need from a compute backend."""

    name: str

    def map(self, fn: Callable[[T], R], tasks: Sequence[T]) -> list[R]:
        """``[fn(t) for t in tasks]``, in order, possibly in parallel."""
        ...

    def close(self) -> None:
        """Release workers."""
        ...


class SerialExecutor:
    """Runs every task in this process, one after the other."""

    name = "serial"

    def __init__(self, workers: int = 1) -> None:
        self.workers = 1

    def map(self, fn: Callable[[T], R], tasks: Sequence[T]) -> list[R]:
        return [fn(t) for t in tasks]

    def close(self) -> None:
        pass


class LocalExecutor:
    """A process pool over this machine's cores (spawned workers, kept for reuse).

    Tasks are split into contiguous chunks, one list of results per chunk, reassembled in
    order. With one worker (or one task) it runs in-process, without a pool.
    """

    name = "local"

    def __init__(self, workers: int | None = None) -> None:
        n = workers if workers is not None else (os.cpu_count() or 1)
        if n < 1:
            raise UsageError(f"--workers must be at least 1, got {n}")
        self.workers = n
        self._pool: ProcessPoolExecutor | None = None

    def _get_pool(self) -> ProcessPoolExecutor:
        if self._pool is None:
            ctx = multiprocessing.get_context("spawn")
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx)
        return self._pool

    def map(self, fn: Callable[[T], R], tasks: Sequence[T]) -> list[R]:
        tasks = list(tasks)
        if self.workers == 1 or len(tasks) <= 1:
            return [fn(t) for t in tasks]
        n_chunks = min(self.workers, len(tasks))
        bounds = [round(i * len(tasks) / n_chunks) for i in range(n_chunks + 1)]
        chunks = [tasks[bounds[i]:bounds[i + 1]] for i in range(n_chunks)]
        pool = self._get_pool()
        futures = [pool.submit(_run_chunk, fn, c) for c in chunks]
        out: list[R] = []
        for f in futures:
            out.extend(f.result())
        return out

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __enter__(self) -> LocalExecutor:
        return self

    def __exit__(self, et: type[BaseException] | None, e: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


def _run_chunk(fn: Callable[[Any], Any], chunk: list[Any]) -> list[Any]:
    return [fn(t) for t in chunk]


_REGISTRY: dict[str, Callable[[int | None], Executor]] = {}


def register_executor(name: str, factory: Callable[[int | None], Executor]) -> None:
    """Make an executor available as ``--executor NAME``; a name is registered once."""
    if name in _REGISTRY:
        raise UsageError(f"executor {name!r} is already registered")
    _REGISTRY[name] = factory


def make_executor(name: str, workers: int | None = None) -> Executor:
    """Build a registered executor."""
    try:
        factory = _REGISTRY[name]
    except KeyError:
        raise UsageError(
            f"unknown executor {name!r}", f"choose one of: {', '.join(sorted(_REGISTRY))}"
        ) from None
    return factory(workers)


def executor_names() -> list[str]:
    return sorted(_REGISTRY)


register_executor("serial", SerialExecutor)
register_executor("local", LocalExecutor)
