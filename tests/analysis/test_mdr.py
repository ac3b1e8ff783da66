import math

import numpy as np
import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from hypothesis import given, settings
from hypothesis import strategies as st

from rocas.analysis.mdr import Tolerance, mdr
from rocas.msgs import planning_pb2, prediction_pb2

N_TRAJ_FIELDS = len(planning_pb2.ADCTrajectory.DESCRIPTOR.fields)
N_POINT_FIELDS = len(planning_pb2.TrajectoryPoint.DESCRIPTOR.fields)


def test_identical_messages_score_zero():
    a = planning_pb2.ADCTrajectory(estop=True)
    a.trajectory_point.add(x=1, y=2)
    assert mdr(a, planning_pb2.ADCTrajectory.FromString(a.SerializeToString())) == 0.0


def test_children_are_all_declared_fields_including_unset_ones():
    a, b = planning_pb2.ADCTrajectory(), planning_pb2.ADCTrajectory(estop=True)
    assert mdr(a, b) == 1 / N_TRAJ_FIELDS


def test_nested_message_scores_are_averaged_recursively():
    a, b = planning_pb2.ADCTrajectory(), planning_pb2.ADCTrajectory()
    a.header.timestamp_sec = 1.0
    b.header.timestamp_sec = 2.0
    n_header = len(a.header.DESCRIPTOR.fields)
    assert math.isclose(mdr(a, b), (1 / n_header) / N_TRAJ_FIELDS)


def test_repeated_field_with_different_lengths_scores_one():
    a, b = planning_pb2.ADCTrajectory(), planning_pb2.ADCTrajectory()
    a.trajectory_point.add(x=1)
    assert mdr(a, b) == 1 / N_TRAJ_FIELDS


def test_repeated_elements_are_children():
    a, b = planning_pb2.ADCTrajectory(), planning_pb2.ADCTrajectory()
    for i in range(4):
        a.trajectory_point.add(x=i)
        b.trajectory_point.add(x=i if i else 9)
    # one of four points differs in one of its fields
    assert math.isclose(mdr(a, b), (1 / N_POINT_FIELDS / 4) / N_TRAJ_FIELDS)


def test_tolerance_applies_to_floating_point_leaves_only():
    a = planning_pb2.TrajectoryPoint(x=1.0, v=2.0)
    b = planning_pb2.TrajectoryPoint(x=1.0 + 1e-9, v=2.0)
    assert mdr(a, b) == 1 / N_POINT_FIELDS
    assert mdr(a, b, Tolerance(atol=1e-6)) == 0.0
    assert mdr(a, b, Tolerance(rtol=1e-6)) == 0.0
    assert mdr(planning_pb2.ObjectDecision(id="a"), planning_pb2.ObjectDecision(id="b"),
               Tolerance(atol=10)) > 0


def test_both_nan_is_the_same_leaf():
    a = planning_pb2.TrajectoryPoint(x=float("nan"))
    assert mdr(a, planning_pb2.TrajectoryPoint(x=float("nan"))) == 0.0


def test_different_types_score_one():
    assert mdr(planning_pb2.ADCTrajectory(), prediction_pb2.PredictionObstacles()) == 1.0


def _map_class():
    fd = descriptor_pb2.FileDescriptorProto(name="m.proto", package="m", syntax="proto3")
    msg = fd.message_type.add(name="M")
    entry = msg.nested_type.add(name="CEntry")
    entry.options.map_entry = True
    F = descriptor_pb2.FieldDescriptorProto
    entry.field.add(name="key", number=1, type=F.TYPE_STRING, label=F.LABEL_OPTIONAL)
    entry.field.add(name="value", number=2, type=F.TYPE_DOUBLE, label=F.LABEL_OPTIONAL)
    msg.field.add(name="c", number=1, type=F.TYPE_MESSAGE, label=F.LABEL_REPEATED,
                  type_name=".m.M.CEntry")
    pool = descriptor_pool.DescriptorPool()
    pool.Add(fd)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName("m.M"))


def test_map_entries_are_ordered_by_key():
    M = _map_class()
    a, b = M(), M()
    a.c["x"], a.c["y"] = 1.0, 2.0
    b.c["y"], b.c["x"] = 2.0, 1.0  # insertion order differs
    assert mdr(a, b) == 0.0
    b.c["y"] = 3.0
    # one entry of two; the entry's value child of (key, value) differs
    assert mdr(a, b) == (0.5 / 2)


def test_json_values():
    assert mdr({"a": 1, "b": [1, 2]}, {"b": [1, 2], "a": 1}) == 0.0
    assert mdr({"a": 1, "b": [1, 2]}, {"a": 1, "b": [1, 3]}) == 0.25 / 2 * 2 / 2
    assert mdr([1, 2], [1, 2, 3]) == 1.0
    assert mdr({"a": 1.0}, {"a": 1.0 + 1e-9}, Tolerance(atol=1e-6)) == 0.0
    assert mdr(True, 1) == 1.0


points = st.builds(
    planning_pb2.TrajectoryPoint,
    x=st.floats(allow_nan=True), y=st.floats(-1e3, 1e3), v=st.sampled_from([0.0, 1.0, 2.5]),
)


@st.composite
def trajectories(draw):
    m = planning_pb2.ADCTrajectory(
        estop=draw(st.booleans()), lane_id=draw(st.sampled_from(["", "l1", "l2"])),
        estop_reason=draw(st.integers(0, 3)),
    )
    for p in draw(st.lists(points, max_size=4)):
        m.trajectory_point.append(p)
    return m


json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-5, 5) | st.floats(allow_nan=False) | st.text(max_size=3),
    lambda kids: st.lists(kids, max_size=3) | st.dictionaries(st.text(max_size=2), kids, max_size=3),
    max_leaves=12,
)


@settings(max_examples=200, deadline=None)
@given(trajectories(), trajectories())
def test_protobuf_mdr_properties(a, b):
    assert mdr(a, a) == 0.0
    score = mdr(a, b)
    assert 0.0 <= score <= 1.0
    assert math.isclose(score, mdr(b, a))


@settings(max_examples=200, deadline=None)
@given(json_values, json_values)
def test_json_mdr_properties(a, b):
    assert mdr(a, a) == 0.0
    score = mdr(a, b)
    assert 0.0 <= score <= 1.0
    assert math.isclose(score, mdr(b, a))


# -- ROS 2 messages (rosbags dataclasses) ---------------------------------------------------
ROS2_POSE = (
    "uint32 id\nstring label\nfloat64[] covariance\nPoint[] path\nPoint position\n"
    "================================================================================\n"
    "MSG: pkg/Point\nfloat64 x\nfloat64 y\n"
)


@pytest.fixture(scope="module")
def ros2_msg():
    from rocas.recording.decoding import DecoderCache

    cache = DecoderCache()
    decode_other = cache.decoder("cdr", "pkg/msg/Other", "ros2msg", b"float64 x")
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(ROS2_POSE, "pkg/msg/Pose"))
    Pose = store.types["pkg/msg/Pose"]
    Point = store.types["pkg/msg/Point"]

    def make(id=1, label="car", cov=(1.0, 0.0, 0.0, 1.0), path=((0.0, 0.0), (1.0, 1.0)),
             pos=(5.0, 6.0)):
        return Pose(id=id, label=label, covariance=np.array(cov, dtype=np.float64),
                    path=[Point(x=x, y=y) for x, y in path], position=Point(x=pos[0], y=pos[1]))

    other = decode_other(b"\x00\x01\x00\x00" + np.array([1.0]).tobytes())
    return make, other


def test_ros2_identical_messages_score_zero(ros2_msg):
    make, _ = ros2_msg
    assert mdr(make(), make()) == 0.0


def test_ros2_children_are_the_declared_fields(ros2_msg):
    make, other = ros2_msg
    assert mdr(make(), make(id=2)) == pytest.approx(1 / 5)
    assert mdr(make(), make(label="truck")) == pytest.approx(1 / 5)
    # a primitive array is a repeated node: one of four leaves differs
    assert mdr(make(), make(cov=(1.0, 0.5, 0.0, 1.0))) == pytest.approx(1 / 4 / 5)
    assert mdr(make(), make(cov=(1.0,))) == pytest.approx(1 / 5)  # child counts differ
    # a sequence of messages: one of two points, one of its two fields
    assert mdr(make(), make(path=((0.0, 0.0), (1.0, 2.0)))) == pytest.approx(1 / 2 / 2 / 5)
    assert mdr(make(), make(pos=(5.0, 7.0))) == pytest.approx(1 / 2 / 5)
    assert mdr(make(), other) == 1.0 and mdr(make(), {"id": 1}) == 1.0


def test_ros2_float_leaves_take_the_tolerance(ros2_msg):
    make, _ = ros2_msg
    a, b = make(cov=(1.0, 0.0, 0.0, 1.0), pos=(5.0, 6.0)), make(cov=(1.0, 1e-9, 0.0, 1.0),
                                                                  pos=(5.0, 6.0 + 1e-9))
    assert mdr(a, b) > 0.0
    assert mdr(a, b, Tolerance(atol=1e-6)) == 0.0
    nan = make(cov=(float("nan"), 0.0, 0.0, 1.0))
    assert mdr(nan, make(cov=(float("nan"), 0.0, 0.0, 1.0))) == 0.0


def _cloud_class():
    """A message with a long repeated float field (a range scan) and a scalar."""
    fdp = descriptor_pb2.FileDescriptorProto(name="cloud_test.proto", package="t")
    m = fdp.message_type.add(name="Cloud")
    m.field.add(name="ranges", number=1, type=descriptor_pb2.FieldDescriptorProto.TYPE_FLOAT,
                label=descriptor_pb2.FieldDescriptorProto.LABEL_REPEATED)
    m.field.add(name="ring", number=2, type=descriptor_pb2.FieldDescriptorProto.TYPE_INT32)
    pool = descriptor_pool.DescriptorPool()
    pool.Add(fdp)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName("t.Cloud"))


@pytest.mark.parametrize("tol", [Tolerance(), Tolerance(atol=0.01), Tolerance(rtol=0.001)])
def test_long_float_fields_follow_the_leaf_rule(tol):
    """A scan long enough to be compared as an array scores what the element-wise rule says:
    equal or both NaN is the same leaf, an infinity only equals itself, tolerances apply."""
    cls = _cloud_class()
    rng = np.random.default_rng(3)
    base = rng.uniform(1, 80, 500).astype(np.float32)
    other = (base + rng.normal(0, 0.005, 500) * (rng.random(500) < 0.3)).astype(np.float32)
    base[:4] = [np.nan, np.inf, -np.inf, 5.0]
    other[:4] = [np.nan, np.inf, np.inf, np.nan]
    a, b = cls(ranges=base.tolist(), ring=1), cls(ranges=other.tolist(), ring=1)
    x, y = np.asarray(a.ranges, dtype=np.float64), np.asarray(b.ranges, dtype=np.float64)
    differ = sum(
        not (p == q or (math.isnan(p) and math.isnan(q)))
        and (tol.exact or math.isinf(p) or math.isinf(q) or math.isnan(p) or math.isnan(q)
             or abs(p - q) > tol.atol + tol.rtol * abs(q))
        for p, q in zip(x.tolist(), y.tolist(), strict=True)
    )
    assert differ > 3
    assert mdr(a, b, tol) == (differ / 500) / 2
    assert mdr(a, cls(ranges=base.tolist(), ring=1), tol) == 0.0
