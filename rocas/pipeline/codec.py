"""One JSON codec for the pipeline's frozen result dataclasses.

A result type is a frozen dataclass whose fields are JSON scalars (``bool``, ``int``,
``float``, ``str``, ``None``), ``tuple[X, ...]``, ``Mapping[str, X]``, ``X | None``, other
such dataclasses, or :data:`Json` (a value kept as the JSON it was read from: a payload rocas
reports but never reads). :func:`to_json` writes a value's fields in their declared order;
a field declared with :func:`omitted` is left out while it is None (a key the JSON has only
sometimes). :func:`from_json` reads one back and checks every field's shape on the way, so a
run directory's files are typed before anything uses them (:class:`ShapeError` says where
the shape is wrong).
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from collections.abc import Mapping
from typing import Any, TypeVar

import numpy as np

#: a JSON value rocas passes on without reading (a report's payload)
Json = typing.NewType("Json", object)

T = TypeVar("T")

_OMIT = "rocas.omit_none"


def omitted(default: Any = None) -> Any:
    """A dataclass field left out of the JSON while it is None (default None)."""
    return dataclasses.field(default=default, metadata={_OMIT: True})


class ShapeError(ValueError):
    """A JSON value that does not have a result type's shape; ``where`` is its path."""

    def __init__(self, where: str, why: str) -> None:
        super().__init__(f"{where or 'the value'} {why}")
        self.where = where
        self.why = why


def to_json(value: Any) -> Any:
    """``value`` (a result dataclass, or anything a field may hold) as plain JSON values."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        out = {}
        for f in dataclasses.fields(value):
            v = getattr(value, f.name)
            if v is None and f.metadata.get(_OMIT):
                continue
            out[f.name] = to_json(v)
        return out
    if isinstance(value, Mapping):
        return {k: to_json(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [to_json(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def from_json(tp: type[T] | Any, data: Any, where: str = "") -> T:
    """Read ``data`` (decoded JSON) as a value of type ``tp``.

    Raises:
        ShapeError: ``data`` does not have that shape (a key missing or unknown, a value of
            another type).
    """
    if tp is Any or tp is Json:
        return data
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        options = typing.get_args(tp)
        if data is None:
            if type(None) in options:
                return None  # type: ignore[return-value]
            raise ShapeError(where, "is null")
        rest = [o for o in options if o is not type(None)]
        errors = []
        for option in rest:
            try:
                return from_json(option, data, where)
            except ShapeError as exc:
                errors.append(exc)
        raise errors[0]
    if origin is tuple:
        item, *more = typing.get_args(tp)
        if not isinstance(data, list):
            raise ShapeError(where, "is not a list")
        if more and more != [Ellipsis]:
            raise TypeError(f"fixed-length tuples are not supported: {tp}")
        return tuple(from_json(item, v, f"{where}[{i}]") for i, v in enumerate(data))  # type: ignore[return-value]
    if origin in (Mapping, dict):
        _, value_type = typing.get_args(tp)
        if not isinstance(data, dict):
            raise ShapeError(where, "is not an object")
        return {str(k): from_json(value_type, v, f"{where}.{k}") for k, v in data.items()}  # type: ignore[return-value]
    if dataclasses.is_dataclass(tp):
        return _dataclass_from_json(tp, data, where)  # type: ignore[arg-type]
    return _scalar(tp, data, where)


def _scalar(tp: Any, data: Any, where: str) -> Any:
    if tp is bool:
        if isinstance(data, bool):
            return data
        raise ShapeError(where, "is not true or false")
    if tp is int:
        if isinstance(data, int) and not isinstance(data, bool):
            return data
        raise ShapeError(where, "is not a whole number")
    if tp is float:  # an integral float may have been written as an int: kept as read
        if isinstance(data, int | float) and not isinstance(data, bool):
            return data
        raise ShapeError(where, "is not a number")
    if tp is str:
        if isinstance(data, str):
            return data
        raise ShapeError(where, "is not text")
    if tp is type(None):
        if data is None:
            return None
        raise ShapeError(where, "is not null")
    raise TypeError(f"no JSON shape for {tp!r}")


def _dataclass_from_json(cls: type[T], data: Any, where: str) -> T:
    if not isinstance(data, dict):
        raise ShapeError(where, "is not an object")
    hints = _hints(cls)
    names = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(data) - set(names))
    if unknown:
        raise ShapeError(where, f"has an unknown key {unknown[0]!r}")
    values = {}
    for name, f in names.items():
        if name not in data:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise ShapeError(where, f"has no {name!r}")
            continue
        values[name] = from_json(hints[name], data[name], f"{where}.{name}" if where else name)
    return cls(**values)
