"""rclpy.serialization of the compat runtime: CDR bytes as ROS 2 writes them.

rosbags' CDR codec is the independent oracle; the literal byte strings are what
rclpy.serialization.serialize_message returns on ROS 2 Jazzy (rmw_fastrtps).
"""

from __future__ import annotations

import array
import zlib

import numpy as np
import pytest
from message_samples import assert_same_values, random_message, to_rosbags
from rclpy.impl.implementation_singleton import RCLError
from rclpy.serialization import deserialize_message, serialize_message
from ros2_compat.message_support import (
    get_message_class,
    provided_message_types,
    uvms_typestore,
)

ALL_TYPES = provided_message_types()
SEEDS = (0, 1, 2)


def _rng(typename: str, seed: int) -> np.random.Generator:
    return np.random.default_rng([zlib.crc32(typename.encode()), seed])


@pytest.mark.parametrize('seed', SEEDS)
@pytest.mark.parametrize('typename', ALL_TYPES)
def test_serialized_bytes_equal_rosbags_cdr(typename: str, seed: int) -> None:
    """serialize_message of a random message gives exactly rosbags' serialize_cdr bytes."""
    store = uvms_typestore()
    msg = random_message(get_message_class(typename), _rng(typename, seed))
    expected = bytes(store.serialize_cdr(to_rosbags(msg), typename, little_endian=True))
    assert serialize_message(msg) == expected


@pytest.mark.parametrize('seed', SEEDS)
@pytest.mark.parametrize('typename', ALL_TYPES)
def test_rosbags_reads_back_the_field_values(typename: str, seed: int) -> None:
    """The rosbags deserialize_cdr of our bytes yields the values of the serialized message."""
    msg = random_message(get_message_class(typename), _rng(typename, seed))
    decoded = uvms_typestore().deserialize_cdr(serialize_message(msg), typename)
    assert_same_values(msg, decoded)


@pytest.mark.parametrize('seed', SEEDS)
@pytest.mark.parametrize('typename', ALL_TYPES)
def test_round_trip_gives_an_equal_message(typename: str, seed: int) -> None:
    """deserialize_message(serialize_message(m)) == m, as rclpy's test_serialization checks."""
    cls = get_message_class(typename)
    msg = random_message(cls, _rng(typename, seed))
    assert deserialize_message(serialize_message(msg), cls) == msg


@pytest.mark.parametrize('typename', ALL_TYPES)
def test_default_message_round_trips_and_matches_rosbags(typename: str) -> None:
    """A default-constructed message of every type round-trips and matches rosbags."""
    cls = get_message_class(typename)
    msg = cls()
    data = serialize_message(msg)
    assert data == bytes(uvms_typestore().serialize_cdr(to_rosbags(msg), typename))
    assert deserialize_message(data, cls) == msg


def test_string_message_bytes_are_the_ros2_encoding() -> None:
    """std_msgs/String 'hello': header 00 01 00 00, length 6 with the NUL, text, NUL."""
    string_cls = get_message_class('std_msgs/msg/String')
    data = serialize_message(string_cls(data='hello'))
    assert data == b'\x00\x01\x00\x00\x06\x00\x00\x00hello\x00'


def test_float64_after_a_string_is_aligned_to_eight_bytes_of_payload() -> None:
    """Alignment counts from the end of the 4-byte header, so a double can need 4 pad bytes."""
    header_cls = get_message_class('std_msgs/msg/Header')
    odometry_cls = get_message_class('nav_msgs/msg/Odometry')
    msg = odometry_cls(header=header_cls(frame_id='map'), child_frame_id='')
    msg.pose.pose.position.x = 1.0
    data = serialize_message(msg)
    # payload: sec, nanosec, len 4, 'map\0' (16 bytes), len 1, '\0' (21), pad to 24.
    assert data[4 + 21 : 4 + 24] == b'\x00\x00\x00'
    assert data[4 + 24 : 4 + 32] == np.float64(1.0).tobytes()


def test_float32_round_trip_rounds_like_a_c_float() -> None:
    """A float32 field comes back as the nearest float32, as rclpy's test_set_float32 shows."""
    float32_cls = get_message_class('std_msgs/msg/Float32')
    exact = deserialize_message(serialize_message(float32_cls(data=1.125)), float32_cls)
    rounded = deserialize_message(serialize_message(float32_cls(data=3.14)), float32_cls)
    assert exact.data == 1.125
    assert rounded.data == float(np.float32(3.14))


def test_deserialized_sequences_are_arrays_and_fixed_arrays_writable_numpy() -> None:
    """Deserialized float64[] are array('d') and float64[36] writable float64 numpy arrays."""
    odometry_cls = get_message_class('nav_msgs/msg/Odometry')
    joint_state_cls = get_message_class('sensor_msgs/msg/JointState')
    odometry = deserialize_message(serialize_message(odometry_cls()), odometry_cls)
    joints = deserialize_message(
        serialize_message(joint_state_cls(position=[1.0, 2.0])), joint_state_cls
    )
    odometry.pose.covariance[0] = 5.0
    assert odometry.pose.covariance.dtype == np.float64
    assert odometry.pose.covariance.shape == (36,)
    assert isinstance(joints.position, array.array)
    assert joints.position.typecode == 'd'


def test_deserialize_accepts_trailing_alignment_padding() -> None:
    """Up to 3 padding bytes after the payload (as DDS delivers them) are ignored."""
    bool_cls = get_message_class('std_msgs/msg/Bool')
    assert deserialize_message(b'\x00\x01\x00\x00\x01\x00\x00\x00', bool_cls).data is True


def test_serialize_message_rejects_a_non_message_like_rclpy() -> None:
    """As rclpy: AttributeError (no _TYPE_SUPPORT); the compat error is a TypeError too."""
    with pytest.raises(AttributeError, match='_TYPE_SUPPORT'):
        serialize_message('not a message')
    with pytest.raises(TypeError):
        serialize_message({'data': 1.0})


def test_deserialize_message_rejects_a_non_message_type() -> None:
    """deserialize_message needs a message class, as in rclpy."""
    with pytest.raises(AttributeError, match='_TYPE_SUPPORT'):
        deserialize_message(b'\x00\x01\x00\x00', dict)


def test_truncated_data_raises_rcl_error() -> None:
    """Bytes that end inside the payload fail like rmw_deserialize does (RCLError)."""
    joint_state_cls = get_message_class('sensor_msgs/msg/JointState')
    data = serialize_message(joint_state_cls(name=['a', 'b'], position=[1.0, 2.0]))
    with pytest.raises(RCLError, match='failed to deserialize'):
        deserialize_message(data[:-5], joint_state_cls)


def test_big_endian_encapsulation_is_rejected() -> None:
    """Only little-endian CDR (header 00 01) is read."""
    float64_cls = get_message_class('std_msgs/msg/Float64')
    with pytest.raises(RCLError):
        deserialize_message(b'\x00\x00\x00\x00' + bytes(8), float64_cls)


def test_unserializable_field_value_raises_with_the_type_name() -> None:
    """A field holding a value its type cannot take (checks off) fails at serialization."""
    int32_cls = get_message_class('std_msgs/msg/Int32')
    msg = int32_cls(data='seven', check_fields=False)
    with pytest.raises(ValueError, match='std_msgs/msg/Int32'):
        serialize_message(msg)


def test_covariance_matrix_serializes_row_major() -> None:
    """A (6, 6) covariance (size 36 passes rosidl's check) is written as 36 row-major values."""
    pose_cls = get_message_class('geometry_msgs/msg/PoseWithCovariance')
    matrix = np.arange(36.0).reshape(6, 6)
    as_matrix = pose_cls(check_fields=True)
    as_matrix.covariance = matrix
    flat = pose_cls(covariance=matrix.ravel())
    assert serialize_message(as_matrix) == serialize_message(flat)
