"""An exclusive lock on a directory rocas writes (a run directory, a campaign directory).

Two ``rocas analyze --out RUN`` at once would mix their files; the second is refused in one
line that names the process holding the directory. The lock is ``flock`` on the directory
itself (no lock file to leave behind or to clean up); the kernel releases it when the holder
ends, however it ends. Where ``fcntl`` is missing (Windows) nothing is locked.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

from rocas.errors import OutputError, UsageError

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]


def _holder(path: Path) -> int | None:
    """The process id holding a flock on ``path`` (from ``/proc/locks``), if it can be told."""
    try:
        st = path.stat()
        with open("/proc/locks", encoding="ascii") as f:
            lines = f.read().splitlines()
    except OSError:
        return None
    inode = f":{st.st_ino}"
    for line in lines:
        fields = line.split()
        # "1: FLOCK  ADVISORY  WRITE 1234 08:01:5678 0 EOF"
        if len(fields) >= 6 and fields[1] == "FLOCK" and fields[5].endswith(inode):
            with contextlib.suppress(ValueError):
                return int(fields[4])
    return None


@contextlib.contextmanager
def locked_directory(path: str | os.PathLike[str], what: str = "run directory") -> Iterator[None]:
    """Hold an exclusive lock on the existing directory ``path`` while the block runs.

    Raises:
        UsageError: another process holds it (exit 2; the message names its pid when known).
        OutputError: it cannot be opened (not a directory, no permission).
    """
    p = Path(path)
    if fcntl is None:
        yield
        return
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError as exc:
        raise OutputError(f"cannot lock {what} {p}: {exc.strerror or exc}",
                          "choose a place you can read and write") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            pid = _holder(p)
            who = f"process {pid}" if pid is not None else "another rocas process"
            raise UsageError(f"{what} {p} is in use by {who}",
                             "wait for it to finish, or choose another --out") from None
        yield
    finally:
        os.close(fd)  # releases the lock
