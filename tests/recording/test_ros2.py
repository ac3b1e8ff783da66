"""ROS 2 (cdr / ros2msg) channels: decoding through rosbags, per schema content."""

import numpy as np
import pytest
from ros2_mix import CHANNELS

from rocas.recording import open_recording
from rocas.recording.decoding import DecoderCache


def test_every_channel_of_a_ros2_bag_decodes(ros2_pair):
    acc, _, _ = ros2_pair
    rec = open_recording(acc)
    first = {}
    for m in rec.decoded():
        first.setdefault(m.channel.topic, m.message)
    assert set(first) == {c[0] for c in CHANNELS}
    for topic, st in rec.report.channel_stats.items():
        assert st.messages > 0 and st.decoded == st.messages, topic
        assert st.undecodable == 0 and st.skipped_encoding == 0, topic
    odom = first["/localization/odometry"]
    assert odom.__msgtype__ == "nav_msgs/msg/Odometry"
    assert odom.twist.twist.linear.x == 10.0 and odom.child_frame_id == "base_link"
    assert isinstance(odom.pose.covariance, np.ndarray) and odom.pose.covariance.shape == (36,)
    pred = first["/prediction/obstacles"]
    assert len(pred.obstacles) == 6 and len(pred.obstacles[0].trajectory) == 20
    assert first["/control/cmd"].drive.acceleration == pytest.approx(-1.5)


POINT = "float64 x\nfloat64 y"
POINT3 = "float64 x\nfloat64 y\nfloat64 z"


def test_one_type_name_defined_twice_gets_two_decoders():
    cache = DecoderCache()
    a = cache.decoder("cdr", "pkg/msg/P", "ros2msg", POINT.encode())
    b = cache.decoder("cdr", "pkg/msg/P", "ros2msg", POINT3.encode())
    assert a is not b
    assert cache.decoder("cdr", "pkg/msg/P", "ros2msg", POINT.encode()) is a
    header = b"\x00\x01\x00\x00"  # CDR little endian
    p2 = a(header + np.array([1.0, 2.0]).tobytes())
    p3 = b(header + np.array([1.0, 2.0, 3.0]).tobytes())
    assert (p2.x, p2.y) == (1.0, 2.0) and p3.z == 3.0


@pytest.mark.parametrize(
    ("name", "encoding", "data", "reason"),
    [
        ("", "ros2msg", b"", "no ROS 2 schema"),
        ("pkg/msg/P", "jsonschema", b"{}", "not ros2msg or ros2idl"),
        ("pkg/msg/P", "ros2msg", b"float64 x\nnot_a_type$ y", "cannot be loaded"),
    ],
)
def test_a_broken_ros2_schema_makes_its_messages_undecodable(name, encoding, data, reason):
    decode = DecoderCache().decoder("cdr", name, encoding, data)
    with pytest.raises(Exception, match=reason):
        decode(b"\x00\x01\x00\x00")
