"""Tasks for the executor tests (importable by spawned workers)."""

import os
import time
from pathlib import Path


def slow_touch(task: tuple[str, int, float]) -> int:
    """Sleep, then leave a file named after the task in the folder: the task has finished."""
    folder, i, seconds = task
    time.sleep(seconds)
    Path(folder, f"task-{i}").touch()
    return i


def note_pid_and_sleep(task: tuple[str, float]) -> int:
    """Leave a file named after this process in the folder, then keep busy."""
    folder, seconds = task
    Path(folder, f"pid-{os.getpid()}").touch()
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pass
    return os.getpid()


def pid_of_worker() -> int:
    """This process's id (which worker ran a task)."""
    return os.getpid()


def fail(message: str) -> None:
    raise ValueError(message)
