"""The one error hierarchy of rocas.

Library code raises these; only the CLI turns them into a message line and an exit code
(see :mod:`rocas.cli.exit_codes`). Each error carries a *what went wrong* message and an
optional *what to do* hint, both built in the constructor so that ``str(err)`` reads well.
"""

from __future__ import annotations


class RocasError(Exception):
    """Base class of every error rocas raises on purpose."""

    def __init__(self, message: str, hint: str | None = None) -> None:
        self.message = message
        self.hint = hint
        super().__init__(f"{message} ({hint})" if hint else message)


class UsageError(RocasError):
    """The command line or an API call asked for something inconsistent."""


class InputError(RocasError):
    """An input file (recording, CMG, scenario) is missing, unreadable or malformed."""


class RecordingError(InputError):
    """An MCAP recording cannot be read, or lacks what the operation needs."""


class TopologyError(InputError):
    """The channel-module graph cannot be built (no topology, no control channel, ...)."""


class ScenarioError(InputError):
    """A scenario file or a parameter override is invalid."""


class NotReproducedError(RocasError):
    """Replay did not reproduce the recorded accident."""


class OutputError(RocasError):
    """An output (file, directory, ``.rrd``) cannot be written where it was asked for."""


class Terminated(KeyboardInterrupt):
    """The process was asked to stop (SIGTERM, e.g. from ``timeout`` or a job scheduler).

    A KeyboardInterrupt, so that whatever cleans up after Ctrl-C and says what it kept does
    the same for it; the CLI raises it from its SIGTERM handler and exits with 143 (128 + 15).
    """


__all__ = [
    "InputError",
    "NotReproducedError",
    "OutputError",
    "RecordingError",
    "RocasError",
    "ScenarioError",
    "Terminated",
    "TopologyError",
    "UsageError",
]
