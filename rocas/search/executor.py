"""Executors: where a batch of simulations runs.

An executor maps a *pure, picklable* function over a list of picklable tasks and returns
the results in task order. Results therefore depend only on the tasks, never on the number
of workers, the batch size or the executor, which is what makes a search reproducible and
what lets a distributed engine take over later: it only has to implement ``map``.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
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

    Each task goes to a worker on its own and a worker is given its next task only when it
    has returned its last one, so at most one task per worker is under way at any time. An
    interruption (Ctrl-C, SIGTERM) therefore waits for at most one task per worker, not for
    a share of the whole list: callers keep tasks small (:func:`rocas.pipeline.evaluate.evaluate`
    sends batches of at most ``batch_size`` simulations). Results come back in task order.
    With one worker (or one task) it runs in-process, without a pool.

    A worker exits as soon as the process that started it is gone, even killed (SIGKILL),
    instead of running on as an orphan: it waits on the sentinel multiprocessing gives every
    spawned process (a pipe on POSIX, the parent's handle on Windows). Workers ignore SIGINT and
    SIGTERM, from their start: a terminal's Ctrl-C or ``timeout`` signals the whole process
    group, and stopping is the main process's decision (it ends the workers as it closes the
    pool), not a worker's (which would break the pool, or print its own traceback).
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
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx,
                                             initializer=_start_worker)
        return self._pool

    def map(self, fn: Callable[[T], R], tasks: Sequence[T]) -> list[R]:
        tasks = list(tasks)
        if self.workers == 1 or len(tasks) <= 1:
            return [fn(t) for t in tasks]
        pool = self._get_pool()
        out: list[Any] = [None] * len(tasks)
        under_way: dict[Future[R], int] = {}
        following = iter(range(len(tasks)))

        def give_next() -> None:
            i = next(following, None)
            if i is not None:
                under_way[pool.submit(fn, tasks[i])] = i

        try:
            with _stop_signals_held():  # the first submissions start the workers
                for _ in range(self.workers):
                    give_next()
            while under_way:
                finished, _ = wait(under_way, return_when=FIRST_COMPLETED)
                for f in finished:
                    out[under_way.pop(f)] = f.result()
                    give_next()
        except BaseException:
            for f in under_way:  # only what already runs is left to finish (see close)
                f.cancel()
            raise
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


#: the signals that ask rocas to stop; only the main process acts on them
_STOP_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM") if hasattr(signal, n))


@contextlib.contextmanager
def _stop_signals_held() -> Iterator[None]:
    """Block the stop signals in this thread while it starts workers: a new process inherits the
    mask, so a worker never sees them, even while it imports before :func:`_start_worker` can
    ignore them. None is lost: one that comes meanwhile goes to another thread of this process
    or waits for the mask to be lifted, and Python runs its handler in the main thread as usual.
    Nothing is done where there are no signal masks.
    """
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, _STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _start_worker() -> None:
    """Runs first in every worker: ignore the stop signals (see LocalExecutor), and end the
    worker from a watcher thread when its parent is gone."""
    for s in _STOP_SIGNALS:
        signal.signal(s, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _STOP_SIGNALS)
    parent = multiprocessing.parent_process()
    if parent is not None:
        threading.Thread(target=_exit_with, args=(parent,), name="rocas-parent-watch",
                         daemon=True).start()


def _exit_with(parent: Any) -> None:
    parent.join()  # returns once the parent has exited, however it ended
    os._exit(1)


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
