"""ros2_compat.message_support: type names, classes, copies, CDR, schema text and type hashes."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from ros2_compat.message_support import (
    MessageTypeError,
    copy_message,
    deserialize,
    get_message_class,
    is_message_class,
    message_definition,
    message_type_name,
    normalize_type_name,
    provided_message_types,
    serialize,
    type_hash,
    uvms_typestore,
)
from rosbags.typesys import Stores, get_typestore
from sensor_msgs.msg import JointState

import ros2_compat
from uvms_msgs.msg import ControllerState

#: Types the graph publishes (DESIGN.md), plus what rclpy parameters and /tf need.
USED_TYPES = [
    'builtin_interfaces/msg/Time',
    'builtin_interfaces/msg/Duration',
    'std_msgs/msg/Header',
    'std_msgs/msg/String',
    'std_msgs/msg/Float64',
    'std_msgs/msg/Float64MultiArray',
    'geometry_msgs/msg/Point',
    'geometry_msgs/msg/Quaternion',
    'geometry_msgs/msg/Pose',
    'geometry_msgs/msg/PoseStamped',
    'geometry_msgs/msg/Vector3',
    'geometry_msgs/msg/Wrench',
    'geometry_msgs/msg/WrenchStamped',
    'geometry_msgs/msg/Twist',
    'geometry_msgs/msg/TwistWithCovariance',
    'geometry_msgs/msg/PoseWithCovariance',
    'geometry_msgs/msg/Transform',
    'geometry_msgs/msg/TransformStamped',
    'sensor_msgs/msg/JointState',
    'nav_msgs/msg/Odometry',
    'rosgraph_msgs/msg/Clock',
    'tf2_msgs/msg/TFMessage',
    'rcl_interfaces/msg/ParameterDescriptor',
    'rcl_interfaces/msg/FloatingPointRange',
    'rcl_interfaces/msg/IntegerRange',
    'rcl_interfaces/msg/SetParametersResult',
    'rcl_interfaces/msg/ParameterType',
    'rcl_interfaces/msg/ParameterValue',
    'rcl_interfaces/msg/Parameter',
    'uvms_msgs/msg/ActuatorCommand',
    'uvms_msgs/msg/ContactState',
    'uvms_msgs/msg/ControllerState',
    'uvms_msgs/msg/GeneralizedForce',
    'uvms_msgs/msg/ThrusterState',
]


@pytest.mark.parametrize('typename', USED_TYPES)
def test_every_used_type_is_provided(typename: str) -> None:
    """Each type the stack uses has a compat class named after it."""
    assert typename in provided_message_types()
    assert message_type_name(get_message_class(typename)) == typename


@pytest.mark.parametrize(
    ('name', 'expected'),
    [
        ('sensor_msgs/msg/JointState', 'sensor_msgs/msg/JointState'),
        ('sensor_msgs/JointState', 'sensor_msgs/msg/JointState'),
    ],
)
def test_type_names_normalize_to_pkg_msg_type(name: str, expected: str) -> None:
    """Both 'pkg/Type' and 'pkg/msg/Type' normalize to 'pkg/msg/Type'."""
    assert normalize_type_name(name) == expected


@pytest.mark.parametrize('name', ['JointState', 'sensor_msgs/srv/JointState', 'a/b/c/d', ''])
def test_malformed_type_name_is_rejected(name: str) -> None:
    """Names of neither form raise MessageTypeError (a LookupError)."""
    with pytest.raises(MessageTypeError):
        normalize_type_name(name)


def test_get_message_class_accepts_both_name_forms() -> None:
    """'pkg/msg/Type' and 'pkg/Type' give the class that `from pkg.msg import Type` gives."""
    assert get_message_class('sensor_msgs/msg/JointState') is JointState
    assert get_message_class('sensor_msgs/JointState') is JointState
    assert get_message_class('uvms_msgs/ControllerState') is ControllerState


def test_get_message_class_rejects_unknown_type() -> None:
    """An unknown type raises MessageTypeError naming it."""
    with pytest.raises(MessageTypeError, match='sensor_msgs/msg/NoSuchType'):
        get_message_class('sensor_msgs/NoSuchType')


def test_message_type_name_of_class_and_instance() -> None:
    """The type name comes from a class or an instance alike."""
    assert message_type_name(Odometry) == 'nav_msgs/msg/Odometry'
    assert message_type_name(Odometry()) == 'nav_msgs/msg/Odometry'


def test_message_type_name_rejects_non_messages() -> None:
    """Non-message classes and objects raise TypeError."""
    with pytest.raises(TypeError):
        message_type_name(dict)
    with pytest.raises(TypeError):
        message_type_name(3.0)


def test_is_message_class_tells_classes_from_instances_and_others() -> None:
    """Only message classes qualify, not instances nor plain classes."""
    assert is_message_class(JointState)
    assert not is_message_class(JointState())
    assert not is_message_class(dict)


def test_copy_message_is_deep_and_equal() -> None:
    """copy_message gives an equal message that shares no mutable state."""
    msg = JointState(name=['joint_1'], position=[1.0], velocity=[2.0], effort=[3.0])
    msg.header.frame_id = 'base_link_frd'
    copied = copy_message(msg)
    assert copied == msg
    copied.position[0] = 9.0
    copied.name.append('joint_2')
    copied.header.stamp.sec = 7
    assert msg.position[0] == 1.0
    assert msg.name == ['joint_1']
    assert msg.header.stamp.sec == 0


def test_copy_message_copies_covariance_arrays() -> None:
    """Fixed-size numpy arrays are copied, not shared."""
    msg = Odometry()
    copied = copy_message(msg)
    copied.twist.covariance[0] = 1.0
    assert msg.twist.covariance[0] == 0.0


def test_copy_message_falls_back_for_unexpected_field_values() -> None:
    """With checks off a field may hold anything; the copy is still deep."""
    msg = JointState(check_fields=False)
    msg.name = {'set', 'of', 'names'}
    copied = copy_message(msg)
    assert copied.name == msg.name
    assert copied.name is not msg.name


def test_serialize_then_deserialize_round_trips() -> None:
    """Serialize and deserialize are inverse, with rosbags able to read the bytes."""
    msg = PoseStamped()
    msg.header.frame_id = 'map_ned'
    msg.pose.position.x = 1.7771
    data = serialize(msg)
    assert deserialize(data, PoseStamped) == msg
    decoded = uvms_typestore().deserialize_cdr(data, 'geometry_msgs/msg/PoseStamped')
    assert decoded.pose.position.x == 1.7771


def test_deserialize_accepts_memoryview() -> None:
    """Recorded payloads may come as memoryview (mcap readers); they decode the same."""
    msg = ControllerState(weight=0.5, phase=ControllerState.PHASE_CONSTRAINED)
    assert deserialize(memoryview(serialize(msg)), ControllerState) == msg


@pytest.mark.parametrize('typename', USED_TYPES)
def test_message_definition_equals_rosbags_generate_msgdef(typename: str) -> None:
    """The schema text is rosbags' generate_msgdef(..., ros_version=2) output."""
    expected, _ = uvms_typestore().generate_msgdef(typename, ros_version=2)
    assert message_definition(typename) == expected


def test_message_definition_delimits_dependencies_as_rosbag2() -> None:
    """Dependencies follow 80 '=' and 'MSG: pkg/Type' (not pkg/msg/Type), as Foxglove needs."""
    text = message_definition('sensor_msgs/JointState')
    assert text.startswith('std_msgs/Header header\nstring[] name\nfloat64[] position\n')
    assert f'{"=" * 80}\nMSG: std_msgs/Header\n' in text
    assert f'{"=" * 80}\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n' in text
    assert 'MSG: std_msgs/msg/Header' not in text


def test_message_definition_of_uvms_type_keeps_constants() -> None:
    """Our own types' schema text lists their constants and fields."""
    text = message_definition('uvms_msgs/msg/ControllerState')
    assert 'uint8 PHASE_CONSTRAINED=2' in text
    assert 'geometry_msgs/Vector3 contact_force' in text


def test_type_hash_equals_rosbags_rihs01() -> None:
    """type_hash is rosbags' hash_rihs01 for Jazzy and uvms_msgs types."""
    store = uvms_typestore()
    for typename in ('sensor_msgs/msg/JointState', 'uvms_msgs/msg/ThrusterState'):
        assert type_hash(typename) == store.hash_rihs01(typename)


def test_type_hash_of_std_msgs_string_is_the_jazzy_value() -> None:
    """std_msgs/msg/String hashes to the RIHS01 value `ros2 topic info -v` shows on Jazzy."""
    assert type_hash('std_msgs/String') == (
        'RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18'
    )


def test_unknown_type_has_no_definition_nor_hash() -> None:
    """Schema text and hash of an unknown type raise MessageTypeError."""
    with pytest.raises(MessageTypeError):
        message_definition('uvms_msgs/msg/Nothing')
    with pytest.raises(MessageTypeError):
        type_hash('uvms_msgs/msg/Nothing')


def test_uvms_typestore_holds_jazzy_and_uvms_types() -> None:
    """The store has every Jazzy type of rosbags plus the five uvms_msgs types."""
    store = uvms_typestore()
    jazzy = get_typestore(Stores.ROS2_JAZZY)
    assert set(jazzy.fielddefs) <= set(store.fielddefs)
    uvms = {name for name in store.fielddefs if name.startswith('uvms_msgs/')}
    assert len(uvms) == 5


def test_uvms_typestore_works_without_activating_the_overlay() -> None:
    """A plain import of message_support neither activates the overlay nor imports rclpy."""
    code = (
        'import sys\n'
        'sys.meta_path[:] = [f for f in sys.meta_path if type(f).__name__ != "_FallbackFinder"]\n'
        'from ros2_compat.message_support import uvms_typestore, message_definition\n'
        'store = uvms_typestore()\n'
        'assert "uvms_msgs/msg/ControllerState" in store.fielddefs\n'
        'assert message_definition("uvms_msgs/msg/ContactState")\n'
        'assert not any(type(f).__name__ == "_FallbackFinder" for f in sys.meta_path)\n'
        'assert "rclpy" not in sys.modules and "sensor_msgs" not in sys.modules\n'
    )
    source_root = Path(ros2_compat.__file__).resolve().parents[1]
    subprocess.run(
        [sys.executable, '-c', code],
        check=True,
        env={'PYTHONPATH': str(source_root)},
    )


def test_recorded_payload_decodes_with_rosbags_store() -> None:
    """A uvms_msgs payload we serialize decodes with the rosbags store (recorder, plots)."""
    msg = ControllerState(weight=0.25, normal_velocity=-0.01)
    msg.contact_force.x = 150.0
    decoded = uvms_typestore().deserialize_cdr(serialize(msg), 'uvms_msgs/msg/ControllerState')
    assert decoded.weight == 0.25
    assert decoded.contact_force.x == 150.0
    np.testing.assert_equal(decoded.normal_velocity, -0.01)
