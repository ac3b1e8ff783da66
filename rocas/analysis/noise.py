"""What "the same" means for two real runs, learned from their shared start.

Two runs of a deterministic stack agree bit for bit until they deviate; two runs of a real
stack never do: sensor noise moves every float a little, header stamps come from two clocks,
sequence numbers and ids count on their own. The paper's premise is that accident and
reference share their start, so whatever differs there is not the deviation. rocas uses the
start to learn, per channel and per field (a leaf *path*: field names from the message root,
``header.stamp.sec``, ``objects.position.x``; the elements of a repeated field share one
path):

- a field that is not a float and differs in at least :data:`IGNORE_FRACTION` of the start's
  message pairs (stamps, counters, ids) is **set aside**: it is left out of the message tree,
  and listed (``ignored_fields``);
- a float field that differs at the start gets an **absolute tolerance** of
  :data:`TOLERANCE_MARGIN` times the largest difference seen there (listed as
  ``learned_tolerances``): sensor noise of a few centimetres no longer counts, a step of a
  metre still does.

Learning is switched on only for a pair that is noisy at its start (:func:`noisy_start`):
when most channels' start messages are byte-for-byte the same (every pair a deterministic
simulator writes), the diff is the paper's exact MDR, unchanged.

:func:`masked_mdr` is the MDR of Definition 5.2 on the trees without the fields set aside,
with each float leaf compared within its own tolerance.
"""

from __future__ import annotations

import dataclasses
import fnmatch
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from rocas.analysis.mdr import EXACT, Tolerance

#: Fewest message pairs at a channel's start from which its fields are learned.
MIN_START_PAIRS = 3
#: A non-float field differing in at least this fraction of the start's pairs is set aside.
IGNORE_FRACTION = 0.9
#: A learned tolerance is this many times the largest difference seen at the start.
TOLERANCE_MARGIN = 2.0
#: A float is noise when its largest difference between the runs at the start is at most this
#: many times its largest step from one message to the next within a run.
NOISE_STEP_RATIO = 4.0
#: A pair is noisy at its start when, over its channels with start pairs, the median fraction
#: of byte-identical start pairs is below this.
NOISY_IDENTICAL_FRACTION = 0.5

_FLOATS = (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT)


@dataclass(frozen=True)
class FieldRules:
    """How one channel's messages are compared.

    Attributes:
        ignored: leaf paths left out of the message tree.
        atol: leaf path -> absolute tolerance of that float field [the field's unit].
        default: the tolerance of every other float leaf (``--atol``/``--rtol``).
        other_floats: absolute tolerance of a float leaf the start did not show (an obstacle
            that comes into view later): the channel's largest learned tolerance, its noise
            level [the fields' unit]; 0 when none was learned.
        seen: the leaf paths the start showed (they keep their own rule, exact when none).
    """

    ignored: frozenset[str] = frozenset()
    atol: Mapping[str, float] = field(default_factory=dict)
    default: Tolerance = EXACT
    other_floats: float = 0.0
    seen: frozenset[str] = frozenset()

    @property
    def trivial(self) -> bool:
        """Nothing learned or set aside: the plain MDR with :attr:`default` applies."""
        return not self.ignored and not self.atol


# -- walking two trees leaf by leaf ------------------------------------------------------

def _is_ros2(v: Any) -> bool:
    return hasattr(v, "__msgtype__") and dataclasses.is_dataclass(v)


def _children(a: Any, b: Any) -> list[tuple[str, Any, Any, bool]] | None:
    """The children of two inner nodes of one kind as (name, a, b, is_float), or None when
    ``a`` and ``b`` are leaves (or of different kinds)."""
    if isinstance(a, Message) and isinstance(b, Message):
        if a.DESCRIPTOR.full_name != b.DESCRIPTOR.full_name:
            return None
        out = []
        for fd in a.DESCRIPTOR.fields:
            out.append((fd.name, getattr(a, fd.name), getattr(b, fd.name), fd.type in _FLOATS))
        return out
    if _is_ros2(a) and _is_ros2(b):
        if a.__msgtype__ != b.__msgtype__:
            return None
        return [(f.name, getattr(a, f.name), getattr(b, f.name),
                 isinstance(getattr(a, f.name), float))
                for f in dataclasses.fields(a) if f.name != "__msgtype__"]
    if isinstance(a, dict) and isinstance(b, dict) and sorted(a) == sorted(b):
        return [(k, a[k], b[k], isinstance(a[k], float)) for k in sorted(a)]
    return None


def _sequence(v: Any) -> bool:
    return isinstance(v, (list, tuple, np.ndarray)) or (
        hasattr(v, "__len__") and hasattr(v, "__getitem__") and not isinstance(v, (str, bytes))
        and not isinstance(v, (dict, Message)) and not _is_ros2(v))


def _scalar(v: Any) -> bool:
    return isinstance(v, (bool, int, float, str, bytes, np.generic))


def _is_map(v: Any) -> bool:
    return hasattr(v, "keys") and hasattr(v, "items") and not isinstance(v, (dict, Message))


def _float_value(v: Any) -> bool:
    return isinstance(v, float) and not isinstance(v, bool)


def _leaf_pairs(a: Any, b: Any, path: str, is_float: bool
                ) -> Iterator[tuple[str, bool, Any, Any]]:
    """Every leaf of two trees of one shape: (path, is float, a's value, b's value); a
    repeated float field comes as one leaf of two arrays. Where the shapes differ (other
    lengths, other types), nothing is yielded below that node."""
    kids = _children(a, b)
    if kids is not None:
        for name, va, vb, f in kids:
            yield from _leaf_pairs(va, vb, f"{path}.{name}" if path else name, f)
        return
    if _is_map(a) and _is_map(b):
        ka, kb = sorted(a), sorted(b)
        if ka == kb:
            for k in ka:
                yield from _leaf_pairs(a[k], b[k], f"{path}.value" if path else "value",
                                       _float_value(a[k]))
        return
    if _sequence(a) and _sequence(b):
        if len(a) != len(b) or len(a) == 0:
            return
        if isinstance(a, np.ndarray) or isinstance(b, np.ndarray) or _scalar(a[0]):
            xa = a if isinstance(a, np.ndarray) else np.asarray(list(a))
            xb = b if isinstance(b, np.ndarray) else np.asarray(list(b))
            floats = xa.dtype.kind == "f" or xb.dtype.kind == "f"
            if floats:
                xa, xb = xa.astype(np.float64), xb.astype(np.float64)
            yield path, floats, xa, xb
            return
        for x, y in zip(a, b, strict=True):
            yield from _leaf_pairs(x, y, path, is_float)
        return
    yield path, is_float or _float_value(a), a, b


#: every leaf of two trees of one shape (public name for :mod:`rocas.analysis.align`)
leaf_pairs = _leaf_pairs


class FieldLearner:
    """Accumulates one channel's start pairs and turns them into :class:`FieldRules`."""

    def __init__(self) -> None:
        self.pairs = 0
        self.identical = 0
        self.first_identical = 0  # among the first MIN_START_PAIRS pairs
        self.differ: dict[str, int] = {}
        self.is_float: dict[str, bool] = {}
        self.max_abs: dict[str, float] = {}
        # within each run, from one start message to the next: steps, steps that changed the
        # leaf, steps that lowered it, the largest float step
        self.steps: dict[str, list[int]] = {}
        self.max_step: dict[str, float] = {}
        self._last: tuple[dict[str, list[Any]], dict[str, list[Any]]] | None = None
        self.seen_paths: set[str] = set()

    def add(self, a: Any, b: Any, identical: bool) -> None:
        """One start pair (decoded messages, consecutive pairs in time order; ``identical``:
        their payloads are the same)."""
        self.pairs += 1
        if identical:
            self.identical += 1
            self.first_identical += self.pairs <= MIN_START_PAIRS
        now = (_values(a), _values(b))
        self.seen_paths.update(now[0], now[1])
        if self._last is not None:
            for prev, cur in zip(self._last, now, strict=True):
                self._step(prev, cur)
        self._last = now
        if identical:
            return
        seen_here: dict[str, bool] = {}
        for path, is_float, va, vb in _leaf_pairs(a, b, "", False):
            differs, biggest = _leaf_difference(va, vb, is_float)
            seen_here[path] = seen_here.get(path, False) or differs
            self.is_float[path] = self.is_float.get(path, False) or is_float
            if biggest > self.max_abs.get(path, 0.0):
                self.max_abs[path] = biggest
        for path, differs in seen_here.items():
            if differs:
                self.differ[path] = self.differ.get(path, 0) + 1

    def _step(self, prev: dict[str, list[Any]], cur: dict[str, list[Any]]) -> None:
        for path, values in cur.items():
            before = prev.get(path)
            if before is None or len(before) != len(values):
                continue
            st = self.steps.setdefault(path, [0, 0, 0])
            st[0] += 1
            changed = lowered = False
            for x, y in zip(before, values, strict=True):
                if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
                    xa, ya = np.asarray(x), np.asarray(y)
                    if xa.shape != ya.shape:
                        changed = True
                        continue
                    if not np.array_equal(xa, ya):
                        changed = True
                        if xa.dtype.kind in "iuf" and ya.dtype.kind in "iuf":
                            d = ya.astype(np.float64) - xa.astype(np.float64)
                            lowered = lowered or bool(np.any(d < 0))
                            fin = np.abs(d[np.isfinite(d)])
                            if len(fin):
                                self.max_step[path] = max(self.max_step.get(path, 0.0),
                                                          float(fin.max()))
                elif x != y:
                    changed = True
                    if isinstance(x, (int, float)) and isinstance(y, (int, float)) \
                            and not isinstance(x, bool):
                        lowered = lowered or y < x
                        d = abs(float(y) - float(x))
                        if math.isfinite(d):
                            self.max_step[path] = max(self.max_step.get(path, 0.0), d)
            st[1] += changed
            st[2] += lowered

    @property
    def identical_fraction(self) -> float:
        return self.identical / self.pairs if self.pairs else 1.0

    def rules(self, default: Tolerance, learn_floats: bool) -> FieldRules:
        """The rules learned (``learn_floats`` False: floats keep ``default``).

        - A leaf that differs between the runs in at least :data:`IGNORE_FRACTION` of the
          start pairs and changes from one message to the next within the runs in at least
          half of the steps is a stamp, a counter or a changing id: set aside. So is a float
          that differs that often, never falls within the runs, and differs between them by
          more than :data:`NOISE_STEP_RATIO` of its steps (a clock: two runs' stamps).
        - Another float that differs at the start is noise when its largest difference
          between the runs is at most :data:`NOISE_STEP_RATIO` times its largest step from
          one message to the next within a run (sensor noise is as large between runs as
          between messages; two different drives differ by far more): it gets a tolerance of
          :data:`TOLERANCE_MARGIN` times that difference. Otherwise the difference is real
          (present from the start) and the leaf stays exact.
        """
        if self.pairs < MIN_START_PAIRS:
            return FieldRules(default=default)
        ignored, atol = set(), {}
        for path, n_diff in self.differ.items():
            share = n_diff / self.pairs
            steps, changed, lowered = self.steps.get(path, (0, 0, 0))
            moving = steps > 0 and 2 * changed >= steps
            biggest = self.max_abs.get(path, 0.0)
            step = self.max_step.get(path, 0.0)
            if share >= IGNORE_FRACTION and moving and (
                    not self.is_float.get(path)
                    or (lowered == 0 and biggest > NOISE_STEP_RATIO * step)):
                ignored.add(path)
                continue
            if not (self.is_float.get(path) and learn_floats):
                continue
            if math.isfinite(biggest) and 0 < biggest <= NOISE_STEP_RATIO * step:
                atol[path] = TOLERANCE_MARGIN * biggest
        return FieldRules(frozenset(ignored), atol, default,
                          max(atol.values()) if atol else 0.0, frozenset(self.seen_paths))


def _values(message: Any) -> dict[str, list[Any]]:
    """Every leaf value of one message by path (repeated elements in order)."""
    out: dict[str, list[Any]] = {}
    for path, _, va, _ in _leaf_pairs(message, message, "", False):
        out.setdefault(path, []).append(va)
    return out


def _leaf_difference(va: Any, vb: Any, is_float: bool) -> tuple[bool, float]:
    """(whether two leaves differ, the largest absolute difference of their float values)."""
    if isinstance(va, np.ndarray):
        if va.shape != vb.shape:
            return True, 0.0
        if va.dtype.kind in "f" and vb.dtype.kind in "f":
            same = (va == vb) | (np.isnan(va) & np.isnan(vb))
            if same.all():
                return False, 0.0
            with np.errstate(invalid="ignore"):
                d = np.abs(va - vb)[~same]
            finite = d[np.isfinite(d)]
            return True, float(finite.max()) if len(finite) else math.inf
        return bool(np.any(va != vb)), 0.0
    if is_float and isinstance(va, (int, float)) and isinstance(vb, (int, float)):
        if va == vb or (va != va and vb != vb):
            return False, 0.0
        d = abs(float(va) - float(vb))
        return True, d if math.isfinite(d) else math.inf
    return (va != vb), 0.0


def noisy_start(learners: Iterable[FieldLearner]) -> bool:
    """Whether a pair is noisy from its very start: over the channels with enough start pairs,
    the median fraction of byte-identical pairs among each channel's first
    :data:`MIN_START_PAIRS` is below :data:`NOISY_IDENTICAL_FRACTION`. Two runs of a
    deterministic stack write the same first messages on most channels, even when an entity
    differs from the start (it changes the channels that see it) or a module departs within
    the first seconds; two runs of a real stack differ in every message (stamps, noise)."""
    fractions = sorted(x.first_identical / MIN_START_PAIRS for x in learners
                       if x.pairs >= MIN_START_PAIRS)
    if not fractions:
        return False
    k = len(fractions) // 2
    median = fractions[k] if len(fractions) % 2 else (fractions[k - 1] + fractions[k]) / 2
    return median < NOISY_IDENTICAL_FRACTION


def with_ignored(rules: FieldRules, topic: str, patterns: Iterable[str],
                 paths: Iterable[str]) -> FieldRules:
    """``rules`` with every leaf path of ``paths`` that a ``--ignore-field`` pattern matches
    (as ``PATH`` or ``TOPIC:PATH``, shell-style wildcards) set aside as well."""
    pats = list(patterns)
    if not pats:
        return rules
    extra = {p for p in paths for pat in pats
             if fnmatch.fnmatchcase(p, pat) or fnmatch.fnmatchcase(f"{topic}:{p}", pat)}
    if not extra - rules.ignored:
        return rules
    return dataclasses.replace(rules, ignored=rules.ignored | extra)


def leaf_paths(message: Any) -> list[str]:
    """Every leaf path of one decoded message (repeated elements share a path)."""
    return [p for p, *_ in _leaf_pairs(message, message, "", False)]


# -- the MDR with the rules ------------------------------------------------------------

def masked_mdr(a: Any, b: Any, rules: FieldRules) -> float:
    """MDR (Definition 5.2) of two decoded messages with ``rules``: the fields set aside are
    not children of their parent (a node left with no children is itself left out), and a
    float leaf with a learned tolerance differs only beyond it."""
    score = _masked(a, b, "", False, rules)
    return 0.0 if score is None else score


def _masked(a: Any, b: Any, path: str, is_float: bool, rules: FieldRules) -> float | None:
    if path in rules.ignored:
        return None
    kids = _children(a, b)
    if kids is not None:
        total, n = 0.0, 0
        for name, va, vb, f in kids:
            s = _masked(va, vb, f"{path}.{name}" if path else name, f, rules)
            if s is not None:
                total += s
                n += 1
        return total / n if n else None
    if isinstance(a, Message) or isinstance(b, Message) or _is_ros2(a) or _is_ros2(b):
        return 1.0  # two message types, or a message against a leaf
    if _is_map(a) and _is_map(b):
        if len(a) != len(b):
            return 1.0
        if not len(a):
            return 0.0
        sub = f"{path}.value" if path else "value"
        total = 0.0
        for ka, kb in zip(sorted(a), sorted(b), strict=True):
            v = _masked(a[ka], b[kb], sub, _float_value(a[ka]), rules)
            total += ((0.0 if ka == kb else 1.0) + (0.0 if v is None else v)) / 2.0
        return total / len(a)
    if _sequence(a) and _sequence(b):
        if len(a) != len(b):
            return 1.0
        if len(a) == 0:
            return 0.0
        if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
            return _array(np.asarray(a), np.asarray(b), _tolerance(path, rules))
        scores = [_masked(x, y, path, is_float or _float_value(x), rules) for x, y in
                  zip(a, b, strict=True)]
        kept = [s for s in scores if s is not None]
        return sum(kept) / len(kept) if kept else None
    if _sequence(a) or _sequence(b) or isinstance(a, dict) or isinstance(b, dict):
        return 1.0
    if (is_float or _float_value(a) or _float_value(b)) and isinstance(a, (int, float)) \
            and isinstance(b, (int, float)) and not isinstance(a, bool) \
            and not isinstance(b, bool):
        return 1.0 if _float_differs(float(a), float(b), _tolerance(path, rules)) else 0.0
    return 0.0 if (type(a) is type(b) and a == b) else 1.0


def _tolerance(path: str, rules: FieldRules) -> Tolerance:
    atol = rules.atol.get(path)
    if atol is None:
        if path in rules.seen or not rules.other_floats:
            return rules.default
        atol = rules.other_floats
    return Tolerance(max(atol, rules.default.atol), rules.default.rtol)


def _float_differs(a: float, b: float, tol: Tolerance) -> bool:
    if a == b or (a != a and b != b):
        return False
    if math.isinf(a) or math.isinf(b):
        return True
    return not abs(a - b) <= tol.atol + tol.rtol * abs(b)


def _array(a: np.ndarray, b: np.ndarray, tol: Tolerance) -> float:
    n = a.shape[0]
    if a.dtype.kind in "fc" or b.dtype.kind in "fc":
        fa, fb = a.astype(np.float64), b.astype(np.float64)
        same = (fa == fb) | (np.isnan(fa) & np.isnan(fb))
        if not tol.exact:
            with np.errstate(invalid="ignore"):
                same |= np.isfinite(fa) & np.isfinite(fb) & (
                    np.abs(fa - fb) <= tol.atol + tol.rtol * np.abs(fb))
        return float(n - np.count_nonzero(same)) / n
    return float(np.count_nonzero(a != b)) / n
