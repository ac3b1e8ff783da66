"""The ``rocas`` command: parse arguments, dispatch to one module per command, map errors.

Each command lives in ``rocas/cli/<name>.py`` and exposes::

    HELP: str                                  # one line for ``rocas --help``
    def add_arguments(parser) -> None          # its options
    def run(args, env: Env) -> int             # does the work, returns an exit status

Only this module turns exceptions into ``rocas: error: ...`` lines and exit codes.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import importlib
import os
import signal
import sys
import threading
import traceback
from collections.abc import Iterator, Sequence
from typing import NoReturn

from rocas import __version__
from rocas.cli.console import Env
from rocas.cli.exit_codes import ExitStatus, exit_status_for
from rocas.errors import OutputError, RocasError, Terminated, UsageError

#: Command name -> module under rocas.cli. Modules that are not present are not offered.
COMMANDS: dict[str, str] = {
    "analyze": "analyze",
    "diff": "diff",
    "cmg": "cmg",
    "simulate": "simulate",
    "replay": "replay",
    "params": "params",
    "annotate": "annotate",
    "view": "view",
    "catalog": "catalog",
    "bench": "bench",
    "triage": "triage",
    "compare": "compare",
}


class _ArgumentError(Exception):
    """A command-line usage error, raised by the parser and reported by :func:`main`."""


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors in rocas's one-line format (exit 2)."""

    def error(self, message: str) -> NoReturn:
        raise _ArgumentError(f"{message} (see '{self.prog} --help')")


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The command-line parser; with ``only``, the parser of that one command (the others'
    modules, and what they import to declare their options, are then not imported)."""
    parser = _Parser(
        prog="rocas",
        description="Root cause analysis of autonomous-driving accidents from MCAP recordings.",
    )
    parser.add_argument("--version", action="version", version=f"rocas {__version__}")
    parser.add_argument(
        "--traceback", action="store_true", help="show the full traceback on errors"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, module_name in COMMANDS.items():
        if only is not None and name != only:
            continue
        try:
            module = importlib.import_module(f"rocas.cli.{module_name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"rocas.cli.{module_name}":
                continue
            raise
        p = sub.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(p)
        _add_traceback(p)
        p.set_defaults(_run=module.run)
    return parser


def _command_named(args: Sequence[str]) -> str | None:
    """The command the arguments name, if they name one before anything else but --traceback."""
    for arg in args:
        if arg != "--traceback":
            return arg if arg in COMMANDS else None
    return None


def _add_traceback(p: argparse.ArgumentParser) -> None:
    """Accept --traceback after the command, and after an action of a command that has them."""
    p.add_argument("--traceback", action="store_true", default=argparse.SUPPRESS,
                   help="show the full traceback on errors")
    for action in p._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                _add_traceback(child)


def main(argv: Sequence[str] | None = None, env: Env | None = None) -> int:
    """Entry point of the console script; returns (and, as a script, exits with) a status."""
    env = env or Env()
    args_list = sys.argv[1:] if argv is None else list(argv)
    if args_list == ["--version"]:  # answered before the commands (and numpy) are imported
        env.stdout.write(f"rocas {__version__}\n")
        return ExitStatus.SUCCESS
    parser = build_parser(_command_named(args_list))
    try:
        args = parser.parse_args(argv)
    except _ArgumentError as exc:
        env.error(str(exc))
        return ExitStatus.USAGE
    except SystemExit as exc:  # --help and --version
        return int(exc.code or 0)
    if not getattr(args, "command", None):
        parser.print_help(env.stderr)
        return ExitStatus.USAGE
    _rearm_sigint()
    try:
        with _sigterm_interrupts():
            status = int(args._run(args, env))
            env.stdout.flush()  # a full disk under stdout is an output error, not a bug
            return status
    except OSError as exc:
        if isinstance(exc, BrokenPipeError) or exc.errno == errno.EPIPE:
            # the reader stopped (``rocas params --json | head``): end quietly, as head expects;
            # stdout goes to /dev/null so the interpreter's own flush at exit says nothing either
            _silence_stdout(env)
            return ExitStatus.SUCCESS
        if exc.errno not in _OUTPUT_ERRNOS:
            return _internal(exc, args, env)
        if args.traceback:
            traceback.print_exc(file=env.stderr)
        where = f" {exc.filename}" if exc.filename else " (standard output)"
        err = OutputError(f"cannot write{where}: {exc.strerror or exc}",
                          "free some space or write elsewhere")
        env.error(str(err))
        _silence_stdout(env)
        return exit_status_for(err)
    except KeyboardInterrupt as exc:
        if args.traceback:
            traceback.print_exc(file=env.stderr)
        kept = getattr(exc, "kept", None) or "no output was written"
        env.error(f"interrupted ({kept})")
        return exit_status_for(exc)
    except RocasError as exc:
        if args.traceback:
            traceback.print_exc(file=env.stderr)
        if isinstance(exc, UsageError) and exc.hint is None:  # an option error: where to look
            env.error(f"{exc} (see 'rocas {args.command} --help')")
        else:
            env.error(str(exc))
        return exit_status_for(exc)
    except Exception as exc:  # a bug: say so in one line, full story with --traceback
        return _internal(exc, args, env)


#: errno values that mean an output could not be written (a full disk, a quota, a file too
#: large, a read-only file system): exit 5 with what to do, never "report a bug".
_OUTPUT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS})


def _internal(exc: BaseException, args: argparse.Namespace, env: Env) -> int:
    if args.traceback:
        traceback.print_exc(file=env.stderr)
    env.error(
        f"internal error: {type(exc).__name__}: {exc} "
        "(this is a bug in rocas; rerun with --traceback and report it)"
    )
    return ExitStatus.INTERNAL


def _silence_stdout(env: Env) -> None:
    """After stdout failed to flush, point it at /dev/null so that the interpreter's own
    flush at exit does not print a second error."""
    if env.stdout is sys.stdout:
        with contextlib.suppress(OSError, ValueError):
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
            os.close(devnull)


def _rearm_sigint() -> None:
    """Make Ctrl-C (SIGINT) stop rocas even when it was started ignoring it.

    A non-interactive shell starts ``cmd &`` with SIGINT ignored, and Python keeps an ignored
    signal ignored; rocas then could not be interrupted. Only the main thread can do this.
    """
    if threading.current_thread() is not threading.main_thread():
        return
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@contextlib.contextmanager
def _sigterm_interrupts() -> Iterator[None]:
    """While a command runs, SIGTERM stops it as Ctrl-C does: it raises :class:`Terminated` (a
    KeyboardInterrupt) in the main thread, so the same cleanup runs and the same line says what
    was kept. Further SIGTERMs while it stops are ignored. Outside the main thread (where no
    handler can be installed) SIGTERM keeps its previous meaning."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "SIGTERM"):
        yield
        return
    raised = False

    def stop(signum: int, frame: object) -> None:
        nonlocal raised
        if not raised:
            raised = True
            raise Terminated

    previous = signal.signal(signal.SIGTERM, stop)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def console_script() -> NoReturn:
    sys.exit(main())


if __name__ == "__main__":
    console_script()
