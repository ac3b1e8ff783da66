"""Inputs the commands read that are not recordings, read with the limits of
:mod:`rocas._limits`, and the options a stack's own analysis takes (kept free of rich and the
other commands' imports: ``diff --json`` loads only what it uses)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import argparse

    from rocas.analysis.cmg import CmgSpec


def refuse_options_not_taken(args: argparse.Namespace,
                             add_arguments: Callable[[argparse.ArgumentParser], None],
                             positionals: Sequence[str], takes: Sequence[str], who: str,
                             unlisted: Sequence[str] = ()) -> None:
    """Refuse the first option given that a stack's own analysis or bench does not take (only
    rocas's pipeline reads it): an option whose value differs from the command's default.

    Args:
        args: the parsed command line; add_arguments: the command's parser builder;
        positionals: a valid positional command line to read the defaults with;
        takes: the destinations the stack's own code takes; who: the message's subject
        ("stack lav benches in its own world"); unlisted: taken but not shown in the hint
        (positionals, the stack).

    Raises:
        UsageError: such an option was given.
    """
    import argparse

    from rocas.errors import UsageError

    defaults = argparse.ArgumentParser()
    add_arguments(defaults)
    given = [k for k, v in vars(defaults.parse_args(list(positionals))).items()
             if k not in takes and getattr(args, k, v) != v]
    if given:
        shown = ", ".join(f"--{k.replace('_', '-')}" for k in takes if k not in unlisted)
        raise UsageError(f"{who}, which does not take --{given[0].replace('_', '-')}",
                         f"options it takes: {shown}")


def load_cmg_file(path: str) -> CmgSpec:
    """A ``--cmg`` file, read with a size and a depth limit (``--cmg /dev/zero`` or a file
    nested thousands deep is refused in one line), then validated."""
    from rocas._limits import loads_json, read_text_limited
    from rocas.analysis.cmg import parse_cmg
    from rocas.errors import InputError

    hint = 'expected {"modules": {"NAME": {"reads": [...], "writes": [...]}}}'
    try:
        data = loads_json(read_text_limited(path, what="CMG file"), origin=str(path))
    except InputError as exc:
        raise InputError(exc.message, exc.hint or hint) from None
    return parse_cmg(data, str(path))
