"""Console helpers: where output goes, and the one format for errors and warnings."""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import TextIO

from rich.console import Console


@dataclass
class Env:
    """The streams a command writes to; tests inject StringIO objects.

    Attributes:
        stdout: results (tables, JSON).
        stderr: progress, warnings and errors.
    """

    stdout: TextIO = field(default_factory=lambda: sys.stdout)
    stderr: TextIO = field(default_factory=lambda: sys.stderr)

    def out(self) -> Console:
        """A rich console on stdout (plain text, 160 columns, when stdout is not a terminal).

        Lines of prose are printed with :func:`prose`, which never breaks them: a pipe or a
        file has no width to wrap to, and grep needs whole lines.
        """
        return Console(file=self.stdout, highlight=False, width=None if _isatty(self.stdout) else 160)

    def err(self) -> Console:
        """A rich console on stderr (for progress bars)."""
        return Console(file=self.stderr, highlight=False, width=None if _isatty(self.stderr) else 160)

    def warn(self, message: str) -> None:
        """One ``rocas: warning: ...`` line on stderr."""
        print(f"rocas: warning: {message}", file=self.stderr, flush=True)

    def error(self, message: str) -> None:
        """One ``rocas: error: ...`` line on stderr."""
        print(f"rocas: error: {message}", file=self.stderr, flush=True)


def _isatty(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


def prose(console: Console, *parts: object) -> None:
    """Print one line of prose unbroken (the terminal, if any, wraps it)."""
    console.print(*parts, soft_wrap=True)
