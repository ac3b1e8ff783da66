"""Inputs the commands read that are not recordings, read with the limits of
:mod:`rocas._limits` (kept free of rich and the other commands' imports: ``diff --json`` loads
only what it uses)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rocas.analysis.cmg import CmgSpec


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
