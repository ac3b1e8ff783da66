"""Message Difference Ratio (MDR, Definition 5.2 of the paper).

A message is a tree. The children of a message node are *every* field its schema declares,
in declaration order, so two messages of one type always have the same number of children
(unset fields hold their defaults). A repeated field is a node with one child per element;
a map field is a node whose children are its entries ordered by key, each entry a node with
two children (key, value). Leaves are compared exactly unless a tolerance is given for
floating-point leaves.

    MDR(t1, t2) = [t1 != t2]                     if both are leaves
                = 1                              if their child counts differ
                = mean_i MDR(t1.chd[i], t2.chd[i]) otherwise

JSON-decoded values follow the same rules: an object is a map (entries ordered by key),
an array is a repeated node, everything else is a leaf.

ROS 2 messages (decoded by ``rosbags`` into dataclasses that carry ``__msgtype__``) follow
them too: a message node's children are its declared fields in declaration order, an array
or sequence field (a list, or a numpy array for primitive element types) is a repeated node
with one child per element, everything else is a leaf; float32/float64 leaves take the
tolerance. Two messages of different ROS 2 types score 1.

Two protobuf messages must be instances of the *same* class for the fast paths
(``a == b`` is evaluated in C); the diff layer guarantees that by decoding both recordings
of a topic with one class built from their (identical) schema.
"""

from __future__ import annotations

import dataclasses
import math
import operator
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from google.protobuf.descriptor import Descriptor, FieldDescriptor
from google.protobuf.message import Message


@dataclass(frozen=True)
class Tolerance:
    """Closeness for floating-point leaves: ``|a - b| <= atol + rtol * |b|`` counts as equal.

    Attributes:
        atol: absolute tolerance (same unit as the field).
        rtol: relative tolerance (dimensionless).
    """

    atol: float = 0.0
    rtol: float = 0.0

    @property
    def exact(self) -> bool:
        return self.atol == 0.0 and self.rtol == 0.0


EXACT = Tolerance()

#: Length from which a repeated float field is compared with numpy rather than element by
#: element in Python (the same leaf rule, vectorised).
_VECTOR_MIN = 64

_FLOAT_TYPES = (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT)

# field kinds of a compiled plan
_SCALAR, _FLOAT, _MESSAGE, _REP_SCALAR, _REP_FLOAT, _REP_MESSAGE, _MAP = range(7)


@dataclass(frozen=True)
class _Field:
    name: str
    kind: int
    sub: _Plan | None = None  # message plan (message, repeated message, map value)
    map_value_kind: int = _SCALAR


@dataclass(frozen=True)
class _Plan:
    """How to compare messages of one type: its fields, and ``values(message)``, which returns
    the message's field values in the order of ``fields`` (one C call). ``compare`` is the
    plan compiled by :func:`_compiled` (once, on first use)."""

    full_name: str
    fields: tuple[_Field, ...]
    values: Callable[[Message], tuple[Any, ...]] = tuple
    compare: Callable[[Message, Message, Tolerance, bool], float] | None = field(
        default=None, compare=False, repr=False)


def _values_getter(names: list[str]) -> Callable[[Message], tuple[Any, ...]]:
    if len(names) == 1:  # attrgetter of one name returns the value, not a 1-tuple
        name = names[0]
        return lambda m: (getattr(m, name),)
    return operator.attrgetter(*names)


# keyed weakly by the message class (not by descriptor: descriptors cannot be weakly referenced,
# and every diff builds new classes, so a strong cache would grow without end; not by id(): a
# freed class's id gets reused)
_PLANS: weakref.WeakKeyDictionary[type, _Plan] = weakref.WeakKeyDictionary()


def _is_repeated(fd: FieldDescriptor) -> bool:
    flag = getattr(fd, "is_repeated", None)  # protobuf >= 6
    if flag is not None:
        return bool(flag)
    return fd.label == FieldDescriptor.LABEL_REPEATED  # older runtimes


def _plan_for_class(cls: type) -> _Plan:
    """The (cached) comparison plan of a message class."""
    plan = _PLANS.get(cls)
    if plan is None:
        plan = _PLANS[cls] = _plan_for(cls.DESCRIPTOR, {})  # type: ignore[attr-defined]
    return plan


def _plan_for(desc: Descriptor, memo: dict[Descriptor, _Plan]) -> _Plan:
    """Compile the comparison plan of a message type (``memo``: plans of this compilation)."""
    plan = memo.get(desc)
    if plan is not None:
        return plan
    # placeholder for recursive types; fields are filled below
    fields: list[_Field] = []
    plan = _Plan(desc.full_name, ())
    memo[desc] = plan
    for fd in desc.fields:
        is_repeated = _is_repeated(fd)
        if fd.type == FieldDescriptor.TYPE_MESSAGE:
            mt = fd.message_type
            if is_repeated and mt.GetOptions().map_entry:
                vfd = mt.fields_by_name["value"]
                if vfd.type == FieldDescriptor.TYPE_MESSAGE:
                    fields.append(_Field(fd.name, _MAP, _plan_for(vfd.message_type, memo), _MESSAGE))
                elif vfd.type in _FLOAT_TYPES:
                    fields.append(_Field(fd.name, _MAP, None, _FLOAT))
                else:
                    fields.append(_Field(fd.name, _MAP, None, _SCALAR))
            elif is_repeated:
                fields.append(_Field(fd.name, _REP_MESSAGE, _plan_for(mt, memo)))
            else:
                fields.append(_Field(fd.name, _MESSAGE, _plan_for(mt, memo)))
        elif fd.type in _FLOAT_TYPES:
            fields.append(_Field(fd.name, _REP_FLOAT if is_repeated else _FLOAT))
        else:
            fields.append(_Field(fd.name, _REP_SCALAR if is_repeated else _SCALAR))
    object.__setattr__(plan, "fields", tuple(fields))
    object.__setattr__(plan, "values", _values_getter([f.name for f in fields]))
    return plan


def _compiled(plan: _Plan) -> Callable[[Message, Message, Tolerance, bool], float]:
    """:func:`_unequal` for one message type as straight-line Python, built once per plan
    (as dataclasses builds ``__init__``): one block per field, in field order, with the same
    operations in the same order, so that the score is the same to the bit, without the
    per-field loop and dispatch on the field's kind. Its last argument says whether ``tol``
    is exact."""
    if plan.compare is not None:
        return plan.compare
    fields = plan.fields
    env: dict[str, Any] = {"values": plan.values, "fields": fields, "_map": _map,
                           "_float_differs": _float_differs,
                           "_repeated_leaves": _repeated_leaves}
    body = ["def compare(a, b, tol, exact):"]
    if not fields:
        body.append("    return 0.0")
    else:
        body += ["    ta = values(a)", "    tb = values(b)", "    total = 0.0"]
    for i, f in enumerate(fields):
        kind = f.kind
        body.append(f"    va = ta[{i}]; vb = tb[{i}]")
        if kind == _SCALAR:
            body += ["    if va != vb:", "        total += 1.0"]
        elif kind == _FLOAT:
            # unequal and not both NaN: different when exact (else: within the tolerance?)
            body += ["    if va != vb and (va == va or vb == vb) and "
                     "(exact or _float_differs(va, vb, tol)):", "        total += 1.0"]
        elif kind == _MESSAGE:
            body += ["    if va != vb:", f"        total += sub{i}(va, vb, tol, exact)"]
        elif kind == _REP_MESSAGE:
            # equal elements score 0: leaving them out of the sum does not change it
            body += ["    n = len(va)", "    if n != len(vb):", "        total += 1.0",
                     "    elif n:",
                     f"        total += sum(sub{i}(x, y, tol, exact) "
                     "for x, y in zip(va, vb) if x != y) / n"]
        elif kind == _MAP:
            body.append(f"    total += _map(va, vb, fields[{i}], tol)")
        else:
            body.append(f"    total += _repeated_leaves(va, vb, {kind == _REP_FLOAT}, tol)")
    if fields:
        body.append(f"    return total / {len(fields)}")
    exec("\n".join(body), env)  # noqa: S102 (code built above from field kinds and indices)
    compare = env["compare"]
    object.__setattr__(plan, "compare", compare)
    for i, f in enumerate(fields):  # after storing it: a recursive type finds its own
        if f.kind in (_MESSAGE, _REP_MESSAGE):
            env[f"sub{i}"] = _compiled(f.sub)  # type: ignore[arg-type]
    return compare


def _float_differs(a: float, b: float, tol: Tolerance) -> bool:
    if a == b:
        return False
    if a != a and b != b:  # both NaN: the same leaf value
        return False
    if tol.exact:
        return True
    if math.isinf(a) or math.isinf(b):
        return True
    return abs(a - b) > tol.atol + tol.rtol * abs(b)


def _leaf(a: Any, b: Any, is_float: bool, tol: Tolerance) -> float:
    if is_float:
        return 1.0 if _float_differs(a, b, tol) else 0.0
    return 0.0 if a == b else 1.0


def _repeated_leaves(va: Any, vb: Any, is_float: bool, tol: Tolerance) -> float:
    n = len(va)
    if n != len(vb):
        return 1.0
    if n == 0:
        return 0.0
    if is_float and n >= _VECTOR_MIN:
        # a point cloud, a range scan: compared as arrays (protobuf's containers hand numpy
        # their buffer, so no Python float is made)
        return _array(np.asarray(va, dtype=np.float64), np.asarray(vb, dtype=np.float64), tol)
    la, lb = list(va), list(vb)
    if la == lb:
        return 0.0
    if is_float:
        return sum(_float_differs(x, y, tol) for x, y in zip(la, lb, strict=True)) / n
    return sum(x != y for x, y in zip(la, lb, strict=True)) / n


def _message(a: Message, b: Message, plan: _Plan, tol: Tolerance) -> float:
    if a == b:
        return 0.0
    return _unequal(a, b, plan, tol)


def _unequal(a: Message, b: Message, plan: _Plan, tol: Tolerance) -> float:
    """MDR of two messages of one class, field by field (any two; cheapest when they differ:
    it skips the whole-message equality check, which costs a walk over both in C).

    Per field: a leaf scores 1 if it differs; a submessage scores its own MDR when it is
    not equal; a repeated message field scores 1 if the lengths differ, else the mean of
    its elements' MDRs (equal elements skipped: they score 0); map and repeated leaf fields
    as :func:`_map` and :func:`_repeated_leaves`. The message scores the mean over its
    fields (:func:`_compiled` runs these rules).
    """
    return _compiled(plan)(a, b, tol, tol.atol == 0.0 and tol.rtol == 0.0)


def _map(va: Any, vb: Any, f: _Field, tol: Tolerance) -> float:
    n = len(va)
    if n != len(vb):
        return 1.0
    if n == 0:
        return 0.0
    total = 0.0
    for ka, kb in zip(sorted(va), sorted(vb), strict=True):
        key_score = 0.0 if ka == kb else 1.0
        if f.map_value_kind == _MESSAGE:
            val_score = _message(va[ka], vb[kb], f.sub, tol)  # type: ignore[arg-type]
        else:
            val_score = _leaf(va[ka], vb[kb], f.map_value_kind == _FLOAT, tol)
        total += (key_score + val_score) / 2.0
    return total / n


def _json(a: Any, b: Any, tol: Tolerance) -> float:
    if isinstance(a, dict) and isinstance(b, dict):
        n = len(a)
        if n != len(b):
            return 1.0
        if n == 0:
            return 0.0
        total = 0.0
        for ka, kb in zip(sorted(a), sorted(b), strict=True):
            total += ((0.0 if ka == kb else 1.0) + _json(a[ka], b[kb], tol)) / 2.0
        return total / n
    if isinstance(a, list) and isinstance(b, list):
        n = len(a)
        if n != len(b):
            return 1.0
        if n == 0:
            return 0.0
        return sum(_json(x, y, tol) for x, y in zip(a, b, strict=True)) / n
    if isinstance(a, (dict, list)) or isinstance(b, (dict, list)):
        # an inner node against a leaf: child counts differ unless the node is empty
        return 1.0
    if isinstance(a, float) or isinstance(b, float):
        if isinstance(a, bool) or isinstance(b, bool):
            return 0.0 if a == b else 1.0
        if isinstance(a, (int, float)) and isinstance(b, (int, float)):
            return 1.0 if _float_differs(float(a), float(b), tol) else 0.0
    return 0.0 if (type(a) is type(b) and a == b) else 1.0


#: ROS 2 message class -> its field names in declaration order
_ROS2_FIELDS: weakref.WeakKeyDictionary[type, tuple[str, ...]] = weakref.WeakKeyDictionary()


def _is_ros2(value: Any) -> bool:
    return hasattr(value, "__msgtype__") and dataclasses.is_dataclass(value)


def _ros2_fields(cls: type) -> tuple[str, ...]:
    names = _ROS2_FIELDS.get(cls)
    if names is None:
        names = _ROS2_FIELDS[cls] = tuple(
            f.name for f in dataclasses.fields(cls) if f.name != "__msgtype__"
        )
    return names


def _array(a: np.ndarray, b: np.ndarray, tol: Tolerance) -> float:
    """A primitive array field: a repeated node of leaves (vectorised)."""
    n = a.shape[0]
    if n != b.shape[0]:
        return 1.0
    if n == 0:
        return 0.0
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        fa, fb = a.astype(np.float64), b.astype(np.float64)
        same = (fa == fb) | (np.isnan(fa) & np.isnan(fb))
        if not tol.exact:
            finite = np.isfinite(fa) & np.isfinite(fb)
            with np.errstate(invalid="ignore"):
                close = np.abs(fa - fb) <= tol.atol + tol.rtol * np.abs(fb)
            same |= finite & close
        return float(n - np.count_nonzero(same)) / n
    return float(np.count_nonzero(a != b)) / n


def _ros2_value(va: Any, vb: Any, tol: Tolerance) -> float:
    if isinstance(va, np.ndarray) and isinstance(vb, np.ndarray):
        return _array(va, vb, tol)
    if isinstance(va, list) and isinstance(vb, list):
        n = len(va)
        if n != len(vb):
            return 1.0
        if n == 0:
            return 0.0
        return sum(_ros2_value(x, y, tol) for x, y in zip(va, vb, strict=True)) / n
    if _is_ros2(va) and _is_ros2(vb):
        return _ros2(va, vb, tol)
    if isinstance(va, float) and isinstance(vb, float):
        return 1.0 if _float_differs(va, vb, tol) else 0.0
    if type(va) is not type(vb):
        return 1.0
    return 0.0 if va == vb else 1.0


def _ros2(a: Any, b: Any, tol: Tolerance) -> float:
    if a.__msgtype__ != b.__msgtype__:
        return 1.0
    names = _ros2_fields(type(a))
    if type(b) is not type(a) and _ros2_fields(type(b)) != names:
        return 1.0  # one type name, two definitions: the child counts differ
    if not names:
        return 0.0
    return sum(_ros2_value(getattr(a, k), getattr(b, k), tol) for k in names) / len(names)


def mdr(a: Any, b: Any, tol: Tolerance = EXACT) -> float:
    """MDR of two decoded messages (protobuf messages of one class, ROS 2 messages, or JSON
    values).

    Returns:
        A score in [0, 1]: 0 for identical trees, 1 for entirely different ones.
    """
    if isinstance(a, Message) and isinstance(b, Message):
        if a.DESCRIPTOR.full_name != b.DESCRIPTOR.full_name:
            return 1.0
        if type(a) is not type(b):
            # different classes of one type (decoded from two pools): compare via bytes
            b2 = type(a)()
            b2.ParseFromString(b.SerializeToString())
            b = b2
        return _message(a, b, _plan_for_class(type(a)), tol)
    if isinstance(a, Message) or isinstance(b, Message):
        return 1.0
    if _is_ros2(a) and _is_ros2(b):
        return _ros2(a, b, tol)
    if _is_ros2(a) or _is_ros2(b):
        return 1.0
    return _json(a, b, tol)


def repeated_lengths(message: Any) -> tuple[int, ...]:
    """The lengths of a decoded message's top-level repeated fields, in declaration order: how
    many elements (obstacles, lights, points) the message holds, which :mod:`series` compares
    from bin to bin to see content enter both runs at once.

    A protobuf message gives its repeated and map fields, a ROS 2 message its list and array
    fields, a JSON object its arrays (keys sorted); anything else has none (``()``).
    """
    if isinstance(message, Message):
        plan = _plan_for_class(type(message))
        return tuple(len(getattr(message, f.name)) for f in plan.fields
                     if f.kind in (_REP_SCALAR, _REP_FLOAT, _REP_MESSAGE, _MAP))
    if _is_ros2(message):
        return tuple(len(v) for k in _ros2_fields(type(message))
                     if isinstance(v := getattr(message, k), (list, np.ndarray)))
    if isinstance(message, dict):
        return tuple(len(message[k]) for k in sorted(message) if isinstance(message[k], list))
    return ()
