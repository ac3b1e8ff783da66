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
import sys
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from types import TracebackType
from typing import Any, Protocol, TypeVar

from rocas._worker import STOP_SIGNALS, start_worker
from rocas.errors import UsageError
from rocas.stacks.registry import carrying

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
    has returned its last one, so at most one task per worker is under way at any time.
    Results come back in task order. With one worker (or one task) it runs in-process, without
    a pool.

    Stopping: an interruption (Ctrl-C, SIGTERM) or any other exception in :meth:`map` ends the
    workers at once (SIGKILL) instead of waiting for the tasks under way: tasks are pure, so
    nothing is lost but their results, which :meth:`map` would not return anyway. Workers
    ignore SIGINT and SIGTERM from their start (a terminal's Ctrl-C or ``timeout`` signals
    the whole process group, and stopping is the main process's decision, not a worker's,
    which would break the pool or print its own traceback), and exit as soon as the process
    that started them is gone, even killed (:mod:`rocas._worker`). The pool's resource tracker
    is started without its warning about "leaked semaphore objects": it has that to say only
    when the main process was killed, and it removes them itself.
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
            _start_resource_tracker_quietly()
            ctx = multiprocessing.get_context("spawn")
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx,
                                             initializer=start_worker)
        return self._pool

    def map(self, fn: Callable[[T], R], tasks: Sequence[T]) -> list[R]:
        tasks = list(tasks)
        if self.workers == 1 or len(tasks) <= 1:
            return [fn(t) for t in tasks]
        pool = self._get_pool()
        fn = carrying(fn)  # type: ignore[assignment]  # the parent's run-time stacks come along
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
            self._stop_workers()
            raise
        return out

    def submit(self, fn: Callable[..., R], *args: Any) -> Future[R]:
        """Start ``fn(*args)`` in a worker and return at once (the pool starts if it has not);
        with one worker it runs here before this returns. An exception is raised by the
        future's ``result()``."""
        if self.workers == 1:
            return done_future(fn, *args)
        pool = self._get_pool()
        with _stop_signals_held():  # a submission may start a worker
            return pool.submit(carrying(fn), *args)

    def warm_up(self, fn: Callable[[], Any]) -> None:
        """Start the workers now and have each run ``fn`` (its imports, say) without waiting
        for them, so that the first :meth:`map` or :meth:`submit` that needs them does not
        wait for their start-up. Nothing with one worker."""
        if self.workers == 1:
            return
        pool = self._get_pool()
        with _stop_signals_held():
            for _ in range(self.workers):
                pool.submit(fn)

    def abort(self) -> None:
        """End the workers at once, without waiting for the tasks under way or queued (those
        :meth:`submit` or :meth:`warm_up` started): after an interruption or an error."""
        self._stop_workers()

    def _stop_workers(self) -> None:
        """End the pool without waiting for the tasks under way (see the class docstring)."""
        pool, self._pool = self._pool, None
        if pool is None:
            return
        # ProcessPoolExecutor has no public way to end its workers; _processes (pid -> Process)
        # has been its map of live workers since Python 3.2
        for proc in list((getattr(pool, "_processes", None) or {}).values()):
            with contextlib.suppress(OSError, ValueError, AttributeError):
                proc.kill()
        pool.shutdown(wait=True, cancel_futures=True)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __enter__(self) -> LocalExecutor:
        return self

    def __exit__(self, et: type[BaseException] | None, e: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


def done_future(fn: Callable[..., R], *args: Any) -> Future[R]:
    """``fn(*args)`` run here, as a finished future (its result or its exception)."""
    f: Future[R] = Future()
    try:
        f.set_result(fn(*args))
    except Exception as exc:  # noqa: BLE001  (handed to whoever asks for the result)
        f.set_exception(exc)
    return f


def submit(executor: Executor, fn: Callable[..., R], *args: Any) -> Future[R]:
    """``fn(*args)`` started on ``executor`` when it can run one task apart from the others
    (``submit``, as :class:`LocalExecutor`), else run here at once; as a future."""
    start = getattr(executor, "submit", None)
    return start(fn, *args) if start is not None else done_future(fn, *args)


def _start_resource_tracker_quietly() -> None:
    """Start multiprocessing's resource tracker (if not yet running) with its "leaked
    objects" warning filtered: the tracker is a child interpreter started with this process's
    ``-W`` options. Without a resource tracker (Windows) nothing is done."""
    try:
        from multiprocessing import resource_tracker
    except ImportError:
        return
    quiet = "ignore:resource_tracker:UserWarning"
    sys.warnoptions.append(quiet)
    try:
        resource_tracker.ensure_running()
    finally:
        sys.warnoptions.remove(quiet)


@contextlib.contextmanager
def _stop_signals_held() -> Iterator[None]:
    """Block the stop signals in this thread while it starts workers: a new process inherits the
    mask, so a worker never sees them, even while it imports before
    :func:`rocas._worker.start_worker` can ignore them. None is lost: one that comes meanwhile
    goes to another thread of this process or waits for the mask to be lifted, and Python runs
    its handler in the main thread as usual.
    Nothing is done where there are no signal masks.
    """
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


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


def _ray_executor(workers: int | None) -> Executor:
    """The Ray executor (:mod:`rocas.search.ray_executor`), imported only when asked for: Ray
    is an optional dependency. It joins the cluster named by ``RAY_ADDRESS``, if set."""
    from rocas.search.ray_executor import RayExecutor

    return RayExecutor(workers)


register_executor("serial", SerialExecutor)
register_executor("local", LocalExecutor)
register_executor("ray", _ray_executor)
