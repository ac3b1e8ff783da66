"""What a worker process of :class:`rocas.search.executor.LocalExecutor` does first.

Kept apart from :mod:`rocas.search` so that a spawned worker imports nothing heavy before it
runs :func:`start_worker`: the worker unpickles (and so imports) its initializer before it
calls it, and only then the tasks' function. A parent killed while its workers start up is
then noticed within the worker's first fraction of a second, not after its imports.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
from typing import Any

#: the signals that ask rocas to stop; only the main process acts on them
STOP_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM") if hasattr(signal, n))


def start_worker() -> None:
    """Ignore the stop signals (the main process decides to stop and ends its workers), and
    end the worker from a watcher thread when its parent is gone, even killed (SIGKILL): it
    waits on the sentinel multiprocessing gives every spawned process (a pipe on POSIX, the
    parent's handle on Windows)."""
    for s in STOP_SIGNALS:
        signal.signal(s, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS)
    parent = multiprocessing.parent_process()
    if parent is not None:
        threading.Thread(target=_exit_with, args=(parent,), name="rocas-parent-watch",
                         daemon=True).start()


def _exit_with(parent: Any) -> None:
    parent.join()  # returns once the parent has exited, however it ended
    os._exit(1)
