"""Bounded reads of the inputs that are not recordings: a size limit and a depth limit.

A CMG file, a scenario, a stack file, a campaign index or a run directory's JSON may come from
someone else. Read whole and parsed as they are, ``--cmg /dev/zero`` would fill the memory and
``[[[[...]]]]`` nested a few thousand deep would end rocas with a RecursionError; here both are
refused in one line (:class:`~rocas.errors.InputError`, exit 3).
"""

from __future__ import annotations

import json
import os
import tomllib
from pathlib import Path
from typing import Any

from rocas.errors import InputError

#: the largest non-recording input rocas reads [bytes]; rocas's own are a few hundred KB
MAX_INPUT_BYTES = 32 * 1024 * 1024
#: the deepest nesting of arrays and objects (tables) accepted in JSON or TOML; rocas's own
#: files nest fewer than ten levels
MAX_DEPTH = 64


def read_bytes_limited(path: str | os.PathLike[str], *, what: str,
                       limit: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of ``path``, refused when it holds more than ``limit`` (a device such as
    ``/dev/zero`` included: at most ``limit + 1`` bytes are read).

    Raises:
        InputError: missing, unreadable, a directory, or larger than ``limit``.
    """
    p = Path(path)
    try:
        with open(p, "rb") as f:
            data = f.read(limit + 1)
    except FileNotFoundError:
        raise InputError(f"cannot read {what} {p}: no such {what}", "check the path") from None
    except IsADirectoryError:
        raise InputError(f"{p}: is a directory, not a {what}", "name the file") from None
    except OSError as exc:
        raise InputError(f"cannot read {what} {p}: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise InputError(f"{p}: larger than {limit // (1024 * 1024)} MB, too large for a {what}",
                         f"check that {p} is the {what} you meant")
    return data


def read_text_limited(path: str | os.PathLike[str], *, what: str,
                      limit: int = MAX_INPUT_BYTES) -> str:
    """:func:`read_bytes_limited`, decoded as UTF-8 (else an :class:`InputError`)."""
    data = read_bytes_limited(path, what=what, limit=limit)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a text {what} (not UTF-8 at byte {exc.start})",
                         f"check that {path} is the {what} you meant") from None


def nesting_depth(value: Any) -> int:
    """How deeply lists and dicts nest in ``value`` (a scalar: 0), without recursion."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, dict):
            children = v.values()
        elif isinstance(v, list | tuple):
            children = v
        else:
            continue
        deepest = max(deepest, d)
        if d <= MAX_DEPTH:  # deeper than the limit is refused anyway: no need to walk on
            stack.extend((c, d + 1) for c in children)
    return deepest


def check_depth(value: Any, *, origin: str, max_depth: int = MAX_DEPTH) -> Any:
    """``value`` if it nests at most ``max_depth`` levels, else an :class:`InputError`."""
    if nesting_depth(value) > max_depth:
        raise InputError(f"{origin}: nested more than {max_depth} levels deep",
                         "this is not a file rocas wrote or documents; check where it came from")
    return value


def loads_json(text: str | bytes, *, origin: str, max_depth: int = MAX_DEPTH) -> Any:
    """``json.loads`` that refuses, in one line, invalid JSON and JSON nested too deep.

    Raises:
        InputError: not JSON (with the line and column), or deeper than ``max_depth``.
    """
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{origin}: not valid JSON (line {exc.lineno}, column {exc.colno}: "
                         f"{exc.msg})") from None
    except RecursionError:
        raise InputError(f"{origin}: nested more than {max_depth} levels deep",
                         "this is not a file rocas wrote or documents; check where it came from") from None
    except (UnicodeDecodeError, ValueError) as exc:
        raise InputError(f"{origin}: not valid JSON ({exc})") from None
    return check_depth(value, origin=origin, max_depth=max_depth)


def load_json_file(path: str | os.PathLike[str], *, what: str, limit: int = MAX_INPUT_BYTES,
                   max_depth: int = MAX_DEPTH) -> Any:
    """A JSON file read with :func:`read_bytes_limited` and parsed with :func:`loads_json`."""
    return loads_json(read_text_limited(path, what=what, limit=limit), origin=str(path),
                      max_depth=max_depth)


def loads_toml(text: str, *, origin: str, max_depth: int = MAX_DEPTH) -> dict[str, Any]:
    """``tomllib.loads`` that refuses, in one line, invalid TOML and TOML nested too deep."""
    try:
        value = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{origin}: not valid TOML ({exc})") from None
    except RecursionError:
        raise InputError(f"{origin}: nested more than {max_depth} levels deep",
                         "this is not a file rocas wrote or documents; check where it came from") from None
    return check_depth(value, origin=origin, max_depth=max_depth)


def load_toml_file(path: str | os.PathLike[str], *, what: str, limit: int = MAX_INPUT_BYTES,
                   max_depth: int = MAX_DEPTH) -> dict[str, Any]:
    """A TOML file read with :func:`read_text_limited` and parsed with :func:`loads_toml`."""
    return loads_toml(read_text_limited(path, what=what, limit=limit), origin=str(path),
                      max_depth=max_depth)
