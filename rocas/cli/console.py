"""Console helpers: where output goes, the one format for errors and warnings, and progress."""

from __future__ import annotations

import sys
import threading
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TextIO

from rocas._text import printable

if TYPE_CHECKING:
    from rich.console import Console

#: How long a step runs before its progress appears [s]: a short command prints none.
PROGRESS_DELAY_S = 1.0


@dataclass
class Env:
    """The streams a command writes to; tests inject StringIO objects.

    Attributes:
        stdout: results (tables, JSON).
        stderr: progress, warnings and errors.
        progress_delay_s: how long a step runs before its progress appears [s].
    """

    stdout: TextIO = field(default_factory=lambda: sys.stdout)
    stderr: TextIO = field(default_factory=lambda: sys.stderr)
    progress_delay_s: float = PROGRESS_DELAY_S

    def out(self) -> Console:
        """A rich console on stdout (plain text, 160 columns, when stdout is not a terminal).

        Lines of prose are printed with :func:`prose`, which never breaks them: a pipe or a
        file has no width to wrap to, and grep needs whole lines.
        """
        from rich.console import Console

        return Console(file=self.stdout, highlight=False, width=None if _isatty(self.stdout) else 160)

    def err(self) -> Console:
        """A rich console on stderr (for progress bars)."""
        from rich.console import Console

        return Console(file=self.stderr, highlight=False, width=None if _isatty(self.stderr) else 160)

    def warn(self, message: str) -> None:
        """One ``rocas: warning: ...`` line on stderr (control characters shown escaped)."""
        print(f"rocas: warning: {printable(message)}", file=self.stderr, flush=True)

    def error(self, message: str) -> None:
        """One ``rocas: error: ...`` line on stderr (control characters shown escaped)."""
        print(f"rocas: error: {printable(message)}", file=self.stderr, flush=True)

    def progress(self, description: str, *, enabled: bool = True) -> Progress:
        """A progress display on stderr for one step (a context manager).

        It shows only when ``enabled``, stderr is a terminal, and the step outlasts
        :attr:`progress_delay_s`; it is erased when the step ends. Otherwise its methods
        do nothing (a pipe, a log file, ``--json``: nothing progress-like is written).
        """
        return Progress(self, description,
                        enabled=enabled and _isatty(self.stderr), delay_s=self.progress_delay_s)


class Progress:
    """Progress of one step on stderr (see :meth:`Env.progress`).

    ``update(done, total)`` reports a fraction (bytes read, say); a step that never calls it
    shows a spinner with the elapsed time.
    """

    def __init__(self, env: Env, description: str, *, enabled: bool, delay_s: float) -> None:
        self.enabled = enabled
        self._env = env
        self._description = description
        self._delay_s = delay_s
        self._lock = threading.Lock()
        self._bar: Any = None
        self._task: Any = None
        self._state: tuple[float, float | None] = (0.0, None)
        self._timer: threading.Timer | None = None
        self._closed = False

    def __enter__(self) -> Progress:
        if self.enabled and self._delay_s <= 0:
            self._show()
        elif self.enabled:
            self._timer = threading.Timer(self._delay_s, self._show)
            self._timer.daemon = True
            self._timer.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def update(self, done: float, total: float | None) -> None:
        """Report ``done`` of ``total`` units (None: not known)."""
        if not self.enabled:
            return
        with self._lock:
            self._state = (done, total)
            if self._bar is not None:
                self._bar.update(self._task, completed=done, total=total)

    def close(self) -> None:
        """Stop and erase the display (idempotent)."""
        if self._timer is not None:
            self._timer.cancel()
        with self._lock:
            self._closed = True
            if self._bar is not None:
                self._bar.stop()
                self._bar = None

    def _show(self) -> None:
        from rich.progress import (
            BarColumn,
            DownloadColumn,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )
        from rich.progress import Progress as RichProgress

        with self._lock:
            if self._closed:
                return
            done, total = self._state
            columns = [SpinnerColumn(), TextColumn("{task.description}"), BarColumn()]
            if total is not None:
                columns += [DownloadColumn(), TimeRemainingColumn()]
            columns.append(TimeElapsedColumn())
            self._bar = RichProgress(*columns, console=self._env.err(), transient=True)
            self._task = self._bar.add_task(self._description, total=total, completed=done)
            self._bar.start()


def _isatty(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


def safe(text: object) -> str:
    """``text`` (a name from data: a topic, a module, an entity, a file) ready for a rich
    console: control characters and escape sequences shown escaped (:func:`rocas._text.printable`)
    and rich markup escaped, so that ``[/`` or ``[bold]`` in a name print as themselves.

    Every name from a recording, a scenario, a campaign or a run directory that reaches a rich
    ``print`` or a table cell goes through here; plain ``print`` lines use ``printable``."""
    from rich.markup import escape

    return escape(printable(text))


def prose(console: Console, *parts: object) -> None:
    """Print one line of prose unbroken (the terminal, if any, wraps it).

    Text parts are printed as they read (through :func:`safe`: no markup, control characters
    shown escaped), since prose carries names from data; rich objects are printed as they are."""
    console.print(*(safe(p) if isinstance(p, str) else p for p in parts), soft_wrap=True)
