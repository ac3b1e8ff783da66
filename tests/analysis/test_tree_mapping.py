"""Property tests of the message -> tree mapping behind MDR.

Changing exactly one leaf of a message must give MDR = prod(1 / child count) along the
path from the root to that leaf: every declared field is a child (set or not), every element
of a repeated field is a child of the field's node.
"""

import math

from google.protobuf.descriptor import FieldDescriptor
from hypothesis import given, settings
from hypothesis import strategies as st

from rocas.analysis.mdr import mdr
from rocas.msgs import perception_pb2, planning_pb2, prediction_pb2

TYPES = [planning_pb2.ADCTrajectory, prediction_pb2.PredictionObstacles,
         perception_pb2.PerceptionObstacles]


def _repeated(fd):
    flag = getattr(fd, "is_repeated", None)
    return flag if flag is not None else fd.label == FieldDescriptor.LABEL_REPEATED


def _fill(msg, draw, depth=0):
    """Set a random subset of fields, recursively, with short repeated fields."""
    for fd in msg.DESCRIPTOR.fields:
        if not draw(st.booleans()):
            continue
        if fd.type == FieldDescriptor.TYPE_MESSAGE:
            if depth > 3:
                continue
            if _repeated(fd):
                for _ in range(draw(st.integers(0, 3))):
                    _fill(getattr(msg, fd.name).add(), draw, depth + 1)
            else:
                _fill(getattr(msg, fd.name), draw, depth + 1)
        elif not _repeated(fd):
            setattr(msg, fd.name, _value(fd, draw))


def _value(fd, draw):
    if fd.type in (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT):
        return draw(st.floats(-100, 100, width=32))
    if fd.type == FieldDescriptor.TYPE_BOOL:
        return draw(st.booleans())
    if fd.type == FieldDescriptor.TYPE_STRING:
        return draw(st.text("abc", max_size=3))
    if fd.type == FieldDescriptor.TYPE_ENUM:
        return draw(st.sampled_from([v.number for v in fd.enum_type.values]))
    return draw(st.integers(0, 1000))


def _leaves(msg, weight=1.0, path=()):
    """Every scalar leaf: (path, weight = prod 1/child-count, field descriptor, owner)."""
    n = len(msg.DESCRIPTOR.fields)
    for fd in msg.DESCRIPTOR.fields:
        w = weight / n
        if fd.type == FieldDescriptor.TYPE_MESSAGE:
            if _repeated(fd):
                items = getattr(msg, fd.name)
                for i, sub in enumerate(items):
                    yield from _leaves(sub, w / len(items), (*path, fd.name, i))
            else:
                yield from _leaves(getattr(msg, fd.name), w, (*path, fd.name))
        elif not _repeated(fd):
            yield (*path, fd.name), w, fd, msg


def _changed(fd, value):
    if fd.type in (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT):
        return value + 1.0
    if fd.type == FieldDescriptor.TYPE_BOOL:
        return not value
    if fd.type == FieldDescriptor.TYPE_STRING:
        return value + "z"
    if fd.type == FieldDescriptor.TYPE_ENUM:
        others = [v.number for v in fd.enum_type.values if v.number != value]
        return others[0]
    return value + 1


@st.composite
def message_and_leaf(draw):
    cls = draw(st.sampled_from(TYPES))
    msg = cls()
    _fill(msg, draw)
    leaves = list(_leaves(msg))
    index = draw(st.integers(0, len(leaves) - 1))
    return msg, index


@settings(max_examples=300, deadline=None)
@given(message_and_leaf())
def test_one_changed_leaf_scores_its_path_weight(case):
    msg, index = case
    other = type(msg).FromString(msg.SerializeToString())
    path, weight, fd, owner = list(_leaves(other))[index]
    setattr(owner, fd.name, _changed(fd, getattr(owner, fd.name)))
    assert math.isclose(mdr(msg, other), weight, rel_tol=1e-9)
    assert math.isclose(mdr(other, msg), weight, rel_tol=1e-9)


@settings(max_examples=100, deadline=None)
@given(message_and_leaf())
def test_a_round_trip_through_bytes_is_the_same_tree(case):
    msg, _ = case
    assert mdr(msg, type(msg).FromString(msg.SerializeToString())) == 0.0
