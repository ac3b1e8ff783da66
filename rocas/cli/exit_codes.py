"""Exit codes of the rocas command (documented in docs/cli.md)."""

from __future__ import annotations

from enum import IntEnum

from rocas.errors import (
    InputError,
    NotReproducedError,
    OutputError,
    RocasError,
    Terminated,
    UsageError,
)


class ExitStatus(IntEnum):
    """Process exit status."""

    SUCCESS = 0
    INTERNAL = 1  # a bug: an unexpected exception
    USAGE = 2  # bad command line or inconsistent options
    INPUT = 3  # a missing, unreadable or malformed input file
    NOT_REPRODUCED = 4  # replay did not reproduce the accident
    OUTPUT = 5  # an output cannot be written where it was asked for
    INTERRUPTED = 130  # Ctrl-C (SIGINT)
    TERMINATED = 143  # SIGTERM: stopped as by Ctrl-C; 128 + 15, as a shell reports a killed job


def exit_status_for(exc: BaseException) -> ExitStatus:
    """Map an exception to the exit status the CLI returns for it."""
    if isinstance(exc, Terminated):
        return ExitStatus.TERMINATED
    if isinstance(exc, KeyboardInterrupt):
        return ExitStatus.INTERRUPTED
    if isinstance(exc, UsageError):
        return ExitStatus.USAGE
    if isinstance(exc, InputError):
        return ExitStatus.INPUT
    if isinstance(exc, NotReproducedError):
        return ExitStatus.NOT_REPRODUCED
    if isinstance(exc, OutputError):
        return ExitStatus.OUTPUT
    if isinstance(exc, RocasError):
        return ExitStatus.INPUT
    return ExitStatus.INTERNAL
