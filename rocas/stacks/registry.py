"""Stacks by name: ``--stack NAME`` and a recording's ``rocas.stack`` metadata resolve here.

Built-in stacks are imported on first use; :func:`register` adds others and refuses a name
that is taken.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

from rocas.errors import UsageError
from rocas.stacks.base import Stack

#: built-in stacks: name -> "module:factory" (imported lazily)
_BUILTIN = {
    "ads": "rocas.stacks.builtin:ads_stack",
    "lav": "rocas.stacks.lav.stack:lav_stack",
    "highway": "rocas.stacks.highway.stack:highway_stack",
}
_registered: dict[str, Stack] = {}
DEFAULT_STACK = "ads"


def register(stack: Stack) -> None:
    """Make ``stack`` selectable by its name.

    Raises:
        UsageError: the name is taken (by a built-in or an earlier registration).
    """
    if stack.name in _registered or stack.name in _BUILTIN:
        raise UsageError(f"a stack named {stack.name!r} is already registered",
                         "give your stack another name")
    _registered[stack.name] = stack


def names() -> list[str]:
    """Every selectable stack name, sorted."""
    return sorted({*_BUILTIN, *_registered})


def get_stack(name: str) -> Stack:
    """The stack registered as ``name``.

    Raises:
        UsageError: no such stack.
    """
    if name in _registered:
        return _registered[name]
    target = _BUILTIN.get(name)
    if target is None:
        raise UsageError(f"unknown stack {name!r}", f"known stacks: {', '.join(names())}")
    module, _, attr = target.partition(":")
    factory: Callable[[], Stack] = getattr(importlib.import_module(module), attr)
    stack = factory()
    _registered[name] = stack
    return stack
