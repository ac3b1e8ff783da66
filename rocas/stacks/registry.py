"""Stacks by name: ``--stack NAME`` and a recording's ``rocas.stack`` metadata resolve here.

Built-in stacks are imported on first use; :func:`register` adds others (a Python stack, an
external command from ``--stack-file``) and refuses a name that is taken. Worker processes
start with the stacks registered in the process that started them: executors hand each task
through :class:`Carrying`, which registers :func:`portable`'s stacks in the worker first.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

from rocas.errors import UsageError
from rocas.stacks.base import Stack

#: built-in stacks: name -> "module:factory" (imported lazily)
_BUILTIN = {
    "ads": "rocas.stacks.ads.adapter:ads_stack",
    "lav": "rocas.stacks.lav.stack:lav_stack",
    "highway": "rocas.stacks.highway.stack:highway_stack",
}
_registered: dict[str, Stack] = {}
#: registered at run time (not built-in), in registration order: what workers must also know
_added: dict[str, Stack] = {}


def register(stack: Stack, *, replace: bool = False) -> None:
    """Make ``stack`` selectable by its name; ``replace`` replaces an earlier run-time
    registration of that name (a stack file given again).

    Raises:
        UsageError: the name is taken (by a built-in or an earlier registration).
    """
    if replace and stack.name in _added:
        del _registered[stack.name], _added[stack.name]
    if stack.name in _registered or stack.name in _BUILTIN:
        if _added.get(stack.name) == stack:  # the same declaration again (a worker, a resume)
            return
        raise UsageError(f"a stack named {stack.name!r} is already registered",
                         "give your stack another name")
    _registered[stack.name] = stack
    _added[stack.name] = stack


def portable() -> tuple[Stack, ...]:
    """The stacks registered at run time, which a worker process must register too (they
    travel pickled: an external stack's declaration, a Python stack's object)."""
    return tuple(_added.values())


class Carrying:
    """``fn`` run in a worker after the parent's run-time stacks are registered there
    (:func:`portable`); equal for equal ``fn`` and stacks, so executors can cache it."""

    def __init__(self, fn: Callable[..., object], stacks: tuple[Stack, ...]) -> None:
        self.fn, self.stacks = fn, stacks

    def __call__(self, *args: object) -> object:
        for stack in self.stacks:
            register(stack)
        return self.fn(*args)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Carrying) and (other.fn, other.stacks) == (self.fn, self.stacks)

    def __hash__(self) -> int:
        return hash((self.fn, tuple(s.name for s in self.stacks)))


def carrying(fn: Callable[..., object]) -> Callable[..., object]:
    """``fn`` as a worker should run it: itself when nothing was registered at run time."""
    stacks = portable()
    return Carrying(fn, stacks) if stacks else fn


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
