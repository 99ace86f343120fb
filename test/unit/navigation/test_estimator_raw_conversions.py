"""The estimator's raw readers and writer agree with its typed conversions."""

from __future__ import annotations

import numpy as np
import pytest
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import Imu
from uvms_common.cdr_codecs import MalformedPayloadError
from uvms_model.coordinates import quaternion_xyzw
from uvms_model.kinematics import rot_ned_from_body

from uvms_navigation import conversions, raw_conversions


def stamped(msg: object, frame: str, t_ns: int = 1_234_000_000) -> object:
    """The message with a header stamp t_ns and a frame id."""
    msg.header.stamp = conversions.time_from_ns(t_ns)  # type: ignore[attr-defined]
    msg.header.frame_id = frame  # type: ignore[attr-defined]
    return msg


def imu(frame: str = 'base_link_frd') -> Imu:
    """An Imu as the simulator publishes it (rate, specific force, AHRS attitude)."""
    msg = Imu()
    x, y, z, w = quaternion_xyzw(0.1, -0.2, 1.3)
    msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w = x, y, z, w
    msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z = 0.01, -0.02, 0.3
    a = msg.linear_acceleration
    a.x, a.y, a.z = 0.5, -0.1, -9.81
    return stamped(msg, frame)  # type: ignore[return-value]


def dvl(frame: str = 'dvl_link') -> TwistWithCovarianceStamped:
    """A DVL velocity in its frame."""
    msg = TwistWithCovarianceStamped()
    v = msg.twist.twist.linear
    v.x, v.y, v.z = 0.2, -0.05, 0.01
    return stamped(msg, frame)  # type: ignore[return-value]


def pose(frame: str = 'map_ned') -> PoseWithCovarianceStamped:
    """A position fix (or depth) in map_ned with per-axis variances."""
    msg = PoseWithCovarianceStamped()
    p = msg.pose.pose.position
    p.x, p.y, p.z = 3.0, -1.5, 2.25
    msg.pose.covariance = np.diag([0.04, 0.09, 0.01, 1e9, 1e9, 1e9]).ravel().tolist()
    return stamped(msg, frame)  # type: ignore[return-value]


CASES = [
    (raw_conversions.imu_reader, imu, conversions.imu_arrays),
    (raw_conversions.dvl_reader, dvl, conversions.dvl_arrays),
    (raw_conversions.depth_reader, pose, conversions.depth_value),
    (raw_conversions.position_fix_reader, pose, conversions.position_arrays),
]


def assert_same(got: tuple[object, ...], expected: tuple[object, ...]) -> None:
    """Every value equal (arrays element-wise, to the last bit)."""
    assert len(got) == len(expected)
    for a, b in zip(got, expected, strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize(('make_reader', 'make_msg', 'typed'), CASES)
def test_simulator_layout_reads_in_place_as_the_typed_reader(make_reader, make_msg, typed
                                                             ) -> None:
    """A payload of the simulator's layout is viewed, not deserialized, with equal values."""
    reader, msg = make_reader(), make_msg()
    payload = serialize_message(msg)
    assert reader.decoder.codec.check(payload) is None
    t_ns, value = reader.read(payload)
    expected = typed(msg)
    assert t_ns == expected[0] == 1_234_000_000
    assert_same(value, expected[1:])


@pytest.mark.parametrize(('make_reader', 'make_msg', 'typed'), CASES)
def test_another_frame_id_reads_through_rclpy_alike(make_reader, make_msg, typed
                                                    ) -> None:
    """Another publisher's frame id does not fit the layout; the typed path gives the same."""
    reader, msg = make_reader(), make_msg(frame='')
    payload = serialize_message(msg)
    assert reader.decoder.codec.check(payload) is not None
    t_ns, value = reader.read(payload)
    assert t_ns == 1_234_000_000
    assert_same(value, typed(msg)[1:])
    assert reader.decoder.malformed == 0


@pytest.mark.parametrize('make_reader', [case[0] for case in CASES]
                         + [raw_conversions.clock_reader])
@pytest.mark.parametrize('payload', [b'', b'\x00\x01\x00\x00', b'\x01\x00' + bytes(90),
                                     bytes(range(200))])
def test_garbage_is_malformed_and_counted(make_reader, payload: bytes) -> None:
    """A payload that is no message of the topic's type raises and is counted."""
    reader = make_reader()
    with pytest.raises(MalformedPayloadError):
        reader.read(payload)
    assert reader.decoder.malformed == 1


def test_odometry_payload_equals_the_typed_message() -> None:
    """odometry/filtered: pose, attitude, twist and both covariances as odometry_message."""
    rng = np.random.default_rng(5)
    p, v, w = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    rot = rot_ned_from_body(0.2, -0.4, 2.9)
    a, b = rng.normal(size=(6, 6)), rng.normal(size=(6, 6))
    pose_cov, twist_cov = a @ a.T, b @ b.T
    payload = raw_conversions.OdometryWriter().payload(7_000_000, p, rot, v, w, pose_cov,
                                                       twist_cov)
    expected = conversions.odometry_message(7_000_000, p, rot, v, w, pose_cov, twist_cov)
    got = deserialize_message(payload, Odometry)
    assert serialize_message(got) == serialize_message(expected)
    assert (got.header.frame_id, got.child_frame_id) == ('map_ned', 'base_link_frd')
    np.testing.assert_array_equal(np.array(got.pose.covariance).reshape(6, 6), pose_cov)
