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
        """A rich console on stdout.

        When stdout is not a terminal: plain text, tables 160 columns wide, and lines of prose
        never broken (a pipe or a file has no width to wrap to, and grep needs whole lines).
        """
        tty = _isatty(self.stdout)
        return Console(file=self.stdout, highlight=False, width=None if tty else 160,
                       soft_wrap=not tty)

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
