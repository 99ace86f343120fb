"""Compat message classes behave like the rosidl_generator_py classes of ROS 2 Jazzy.

Each test names the rosidl behaviour it mirrors (template rosidl_generator_py/resource/
_msg.py.em, Jazzy). Jazzy checks field types only with ``check_fields=True`` (or
ROS_PYTHON_CHECK_FIELDS=1); the tests that check types pass ``check_fields=True``
explicitly, so they state Jazzy's behaviour whatever the compat default is.
"""

from __future__ import annotations

import array
import copy
import os
import pickle
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import (
    Point,
    Pose,
    PoseWithCovariance,
    Quaternion,
    Vector3,
    Wrench,
)
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, ParameterType
from ros2_compat.message_support import provided_message_types, uvms_typestore
from rosbags.interfaces import Nodetype
from sensor_msgs.msg import JointState, NavSatStatus
from std_msgs.msg import Bool, Byte, Char, Empty, Float64, Header, Int8, String, UInt64

import ros2_compat
from uvms_msgs.msg import ControllerState

ALL_TYPES = provided_message_types()
UVMS_MSG_DIR = Path(__file__).resolve().parents[3] / 'src' / 'uvms_msgs' / 'msg'

#: .msg primitive -> rosidl type string (rosidl_adapter maps char to uint8, byte to octet).
IDL_NAMES = {
    'bool': 'boolean',
    'byte': 'octet',
    'char': 'uint8',
    'float32': 'float',
    'float64': 'double',
    'string': 'string',
    **{name: name for name in ('int8', 'uint8', 'int16', 'uint16', 'int32', 'uint32')},
    **{name: name for name in ('int64', 'uint64')},
}


def _expected_type_string(desc: tuple[object, object]) -> str:
    """Return rosidl's type string of a rosbags field description (written independently)."""
    nodetype, rest = desc
    if nodetype == Nodetype.BASE:
        name, bound = rest  # type: ignore[misc]
        return f'string<{bound}>' if name == 'string' and bound else IDL_NAMES[name]
    if nodetype == Nodetype.NAME:
        pkg, _, type_ = str(rest).split('/')
        return f'{pkg}/{type_}'
    element_desc, count = rest  # type: ignore[misc]
    element = _expected_type_string(element_desc)
    if nodetype == Nodetype.ARRAY:
        return f'{element}[{count}]'
    return f'sequence<{element}, {count}>' if count else f'sequence<{element}>'


def _message_class(typename: str) -> type:
    from ros2_compat.message_support import get_message_class

    return get_message_class(typename)


@pytest.mark.parametrize('typename', ALL_TYPES)
def test_fields_and_types_equal_the_jazzy_definition(typename: str) -> None:
    """get_fields_and_field_types() lists rosbags' Jazzy fields in order, with rosidl types."""
    _, fielddefs = uvms_typestore().fielddefs[typename]
    expected = {
        name: _expected_type_string(desc)
        for name, desc in fielddefs
        if name != 'structure_needs_at_least_one_member'
    }
    fields = _message_class(typename).get_fields_and_field_types()  # type: ignore[attr-defined]
    assert fields == expected
    assert list(fields) == list(expected)


@pytest.mark.parametrize('typename', ALL_TYPES)
def test_class_has_slots_for_its_fields_and_check_flag(typename: str) -> None:
    """__slots__ is '_' + each field, then '_check_fields', as Jazzy generates it."""
    cls = _message_class(typename)
    fields = list(cls.get_fields_and_field_types())  # type: ignore[attr-defined]
    assert cls.__slots__ == [f'_{name}' for name in fields] + ['_check_fields']
    assert len(cls.SLOT_TYPES) == len(fields)  # type: ignore[attr-defined]


@pytest.mark.parametrize('typename', ALL_TYPES)
def test_constants_are_class_attributes(typename: str) -> None:
    """Every .msg constant is a class attribute with its value."""
    constants, _ = uvms_typestore().fielddefs[typename]
    cls = _message_class(typename)
    for name, _, value in constants:
        assert getattr(cls, name) == value


@pytest.mark.parametrize('typename', ALL_TYPES)
def test_repr_has_rosidl_format(typename: str) -> None:
    """The repr is 'pkg.msg.Type(field=value, ...)' with the package path of the module."""
    msg = _message_class(typename)()
    pkg, _, type_ = typename.split('/')
    assert repr(msg).startswith(f'{pkg}.msg.{type_}(')


def test_module_is_rosidl_submodule() -> None:
    """Classes live in 'pkg.msg._snake_name' modules, as rosidl generates them."""
    assert JointState.__module__ == 'sensor_msgs.msg._joint_state'
    assert _message_class('tf2_msgs/msg/TFMessage').__module__ == 'tf2_msgs.msg._tf_message'
    assert _message_class('sensor_msgs/msg/PointCloud2').__module__ == (
        'sensor_msgs.msg._point_cloud2'
    )


def test_joint_state_default_constructs_empty() -> None:
    """JointState() has a zero stamp, empty frame and empty arrays of the rosidl types."""
    msg = JointState()
    assert msg.header.stamp.sec == 0
    assert msg.header.stamp.nanosec == 0
    assert msg.header.frame_id == ''
    assert msg.name == []
    for field in (msg.position, msg.velocity, msg.effort):
        assert isinstance(field, array.array)
        assert field.typecode == 'd'
        assert len(field) == 0


def test_keyword_construction_sets_fields() -> None:
    """Keyword arguments set fields; float64[] are converted to array('d')."""
    msg = JointState(
        header=Header(stamp=Time(sec=3, nanosec=5), frame_id='base_link_frd'),
        name=['joint_1', 'joint_2'],
        position=[0.1, 0.2],
    )
    assert msg.header.stamp.sec == 3
    assert msg.header.frame_id == 'base_link_frd'
    assert msg.name == ['joint_1', 'joint_2']
    assert msg.position == array.array('d', [0.1, 0.2])


def test_unknown_keyword_is_rejected_with_rosidl_message() -> None:
    """rosidl: AssertionError 'Invalid arguments passed to constructor: <names>' (sorted)."""
    expected = r'^Invalid arguments passed to constructor: nmae, x$'
    with pytest.raises(AssertionError, match=expected):
        JointState(nmae=['a'], x=1, check_fields=True)


def test_unknown_keyword_is_ignored_without_field_checks() -> None:
    """Jazzy with check_fields=False ignores unknown keywords silently."""
    msg = JointState(nmae=['a'], check_fields=False)
    assert msg.name == []


@pytest.mark.parametrize(
    ('setting', 'checked'), [(None, True), ('1', True), ('0', False), ('', False)]
)
def test_field_checks_default_follows_ros_python_check_fields(
    setting: str | None, checked: bool
) -> None:
    """Jazzy checks when ROS_PYTHON_CHECK_FIELDS is '1'; compat also checks when it is unset."""
    env = {k: v for k, v in os.environ.items() if k != 'ROS_PYTHON_CHECK_FIELDS'}
    if setting is not None:
        env['ROS_PYTHON_CHECK_FIELDS'] = setting
    env['PYTHONPATH'] = str(Path(ros2_compat.__file__).resolve().parents[1])
    code = (
        'import ros2_compat; ros2_compat.activate()\n'
        'from std_msgs.msg import Float64\n'
        'print(Float64()._check_fields)\n'
    )
    result = subprocess.run(
        [sys.executable, '-c', code], env=env, capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == str(checked)


@pytest.mark.parametrize('value', [1, '1.0', None])
def test_float_field_rejects_non_float(value: object) -> None:
    """A float64 field takes only float: "The 'x' field must be of type 'float'"."""
    msg = Point(check_fields=True)
    with pytest.raises(AssertionError, match=r"^The 'x' field must be of type 'float'$"):
        msg.x = value  # type: ignore[assignment]


def test_float_field_accepts_infinity_and_numpy_float() -> None:
    """Infinity passes the range check; numpy.float64 is a float subclass."""
    msg = Point(x=float('inf'), y=np.float64(2.0), check_fields=True)
    assert msg.x == float('inf')
    assert msg.y == 2.0


def test_int_field_rejects_float() -> None:
    """An integer field takes only int."""
    msg = Time(check_fields=True)
    with pytest.raises(AssertionError, match=r"^The 'sec' field must be of type 'int'$"):
        msg.sec = 1.0  # type: ignore[assignment]


@pytest.mark.parametrize(
    ('cls', 'value', 'message'),
    [
        (Int8, 128, r"^The 'data' field must be an integer in \[-128, 127\]$"),
        (Int8, -129, r"^The 'data' field must be an integer in \[-128, 127\]$"),
        (Char, 256, r"^The 'data' field must be an unsigned integer in \[0, 255\]$"),
        (
            UInt64,
            -1,
            r"^The 'data' field must be an unsigned integer in \[0, 18446744073709551615\]$",
        ),
    ],
)
def test_int_field_rejects_out_of_range(cls: type, value: int, message: str) -> None:
    """Integer fields check their range with rosidl's messages."""
    with pytest.raises(AssertionError, match=message):
        cls(data=value, check_fields=True)


def test_string_field_rejects_non_str() -> None:
    """A string field takes only str."""
    with pytest.raises(AssertionError, match=r"^The 'data' field must be of type 'str'$"):
        String(data=b'bytes', check_fields=True)


def test_bool_field_rejects_int() -> None:
    """A bool field takes only bool."""
    with pytest.raises(AssertionError, match=r"^The 'data' field must be of type 'bool'$"):
        Bool(data=1, check_fields=True)


def test_byte_field_takes_one_byte() -> None:
    """A byte (octet) field holds bytes of length 1, by default a zero byte."""
    assert Byte().data == b'\x00'
    with pytest.raises(AssertionError, match="must be of type 'bytes' or 'ByteString'"):
        Byte(data=b'ab', check_fields=True)


def test_nested_field_requires_the_exact_class() -> None:
    """A nested field takes only its message class: "must be a sub message of type 'Point'"."""
    with pytest.raises(
        AssertionError, match=r"^The 'position' field must be a sub message of type 'Point'$"
    ):
        Pose(position=Vector3(), check_fields=True)


def test_sequence_field_rejects_wrong_element_type() -> None:
    """string[] elements must all be str."""
    with pytest.raises(
        AssertionError,
        match=r"^The 'name' field must be a set or sequence and each value of type 'str'$",
    ):
        JointState(name=['a', 1], check_fields=True)


def test_bounded_sequence_rejects_too_many_elements() -> None:
    """A bounded sequence (FloatingPointRange[<=1]) checks its length."""
    with pytest.raises(AssertionError, match='with length <= 1'):
        ParameterDescriptor(
            floating_point_range=[FloatingPointRange(), FloatingPointRange()], check_fields=True
        )


@pytest.mark.parametrize(
    'values', [[1.0, 2.0, 3.0], (1.0, 2.0, 3.0), np.array([1.0, 2.0, 3.0]), [1, 2, 3]]
)
def test_float64_sequence_constructor_accepts_list_tuple_numpy(values: object) -> None:
    """The constructor wraps float64[] values in array.array('d', values)."""
    msg = JointState(position=values, check_fields=True)
    assert isinstance(msg.position, array.array)
    assert msg.position == array.array('d', [1.0, 2.0, 3.0])


def test_float64_sequence_setter_stores_array_d() -> None:
    """Assigning a list stores a new array('d'); an array('d') is stored as is."""
    msg = JointState(check_fields=True)
    msg.position = [1.0, 2.0]
    assert msg.position == array.array('d', [1.0, 2.0])
    values = array.array('d', [3.0])
    msg.velocity = values
    assert msg.velocity is values


def test_float64_sequence_setter_rejects_wrong_typecode() -> None:
    """An array.array of another type code is rejected when fields are checked."""
    msg = JointState(check_fields=True)
    with pytest.raises(AssertionError, match="must have the type code of 'd'"):
        msg.position = array.array('f', [1.0])


def test_float64_sequence_setter_takes_numpy_like_jazzy_default() -> None:
    """Deliberate leniency: Jazzy's default setter takes numpy, so the checked compat one does.

    (rosidl's checked setter would reject a numpy array: it is no collections.abc.Sequence.)
    """
    msg = JointState(check_fields=True)
    msg.position = np.array([1.0, 2.0])
    msg.velocity = np.array([3, 4])
    assert msg.position == array.array('d', [1.0, 2.0])
    assert msg.velocity == array.array('d', [3.0, 4.0])


def test_float64_sequence_setter_rejects_numpy_of_strings() -> None:
    """A numpy array of non-numbers is still rejected when fields are checked."""
    msg = JointState(check_fields=True)
    with pytest.raises(AssertionError, match="The 'position' field must be a set or sequence"):
        msg.position = np.array(['a', 'b'])


def test_float64_sequence_setter_takes_numpy_without_checks() -> None:
    """With check_fields=False the setter converts a numpy array to array('d')."""
    msg = JointState(check_fields=False)
    msg.position = np.array([1.5, 2.5])
    assert msg.position == array.array('d', [1.5, 2.5])


def test_covariance_defaults_to_numpy_zeros_of_length_36() -> None:
    """float64[36] is a numpy float64 array of 36 zeros by default."""
    covariance = PoseWithCovariance().covariance
    assert isinstance(covariance, np.ndarray)
    assert covariance.dtype == np.float64
    assert covariance.shape == (36,)
    assert not covariance.any()


def test_covariance_accepts_a_list_of_36_and_stores_numpy() -> None:
    """A list of 36 floats becomes a numpy array."""
    msg = PoseWithCovariance(covariance=[float(i) for i in range(36)], check_fields=True)
    assert isinstance(msg.covariance, np.ndarray)
    assert msg.covariance[35] == 35.0


def test_covariance_rejects_wrong_size() -> None:
    """A numpy array of the wrong size is rejected: 'must have a size of 36'."""
    msg = PoseWithCovariance(check_fields=True)
    with pytest.raises(AssertionError, match='must have a size of 36'):
        msg.covariance = np.zeros(35)


def test_covariance_rejects_wrong_dtype() -> None:
    """A numpy array of another dtype is rejected: "must have the dtype of 'numpy.float64'"."""
    msg = PoseWithCovariance(check_fields=True)
    with pytest.raises(AssertionError, match=r"must have the dtype of 'numpy\.float64'"):
        msg.covariance = np.zeros(36, dtype=np.float32)


def test_equal_messages_compare_equal() -> None:
    """== compares every field, numpy arrays element-wise."""
    first = Odometry(child_frame_id='base_link_frd')
    second = Odometry(child_frame_id='base_link_frd')
    assert first == second
    second.pose.covariance[7] = 1.0
    assert first != second


def test_messages_of_different_types_are_unequal() -> None:
    """The rosidl __eq__ returns False for another class, even with the same fields."""
    assert Point() != Vector3()
    assert Point() != 0


def test_quaternion_defaults_to_identity() -> None:
    """Quaternion.msg has 'float64 w 1': Quaternion().w == 1.0, W__DEFAULT too."""
    assert Quaternion().w == 1.0
    assert Quaternion.W__DEFAULT == 1.0
    assert Pose().orientation.w == 1.0


def test_nav_sat_status_defaults_to_status_unknown() -> None:
    """NavSatStatus.msg has 'int8 status -2' (STATUS_UNKNOWN)."""
    assert NavSatStatus().status == NavSatStatus.STATUS_UNKNOWN == -2


def test_empty_message_has_no_fields() -> None:
    """The placeholder member of an empty .msg is not a Python field."""
    assert Empty.get_fields_and_field_types() == {}
    assert Empty() == Empty()
    assert ParameterType.PARAMETER_DOUBLE == 3


def test_slots_reject_new_attributes() -> None:
    """Messages have __slots__: assigning an attribute that is no field raises."""
    msg = Float64()
    with pytest.raises(AttributeError):
        msg.value = 1.0  # type: ignore[attr-defined]


def test_repr_strips_array_prefix_of_sequences() -> None:
    """The repr shows float64[] as a list: position=[1.0, 2.0], empty as []."""
    text = repr(JointState(position=[1.0, 2.0]))
    assert 'position=[1.0, 2.0], velocity=[], effort=[]' in text
    assert text.startswith(
        'sensor_msgs.msg.JointState(header=std_msgs.msg.Header(stamp=builtin_interfaces.msg.'
        "Time(sec=0, nanosec=0), frame_id=''), name=[]"
    )


def test_get_fields_and_field_types_returns_a_copy() -> None:
    """Changing the returned dict does not change the class."""
    fields = Wrench.get_fields_and_field_types()
    fields['torque'] = 'nonsense'
    assert Wrench.get_fields_and_field_types()['torque'] == 'geometry_msgs/Vector3'


def test_deepcopy_is_independent_and_equal() -> None:
    """copy.deepcopy gives an equal message sharing no mutable state."""
    msg = Odometry(child_frame_id='base_link_frd')
    msg.pose.covariance[0] = 2.0
    joints = JointState(name=['a'], position=[1.0])
    odometry_copy, joints_copy = copy.deepcopy(msg), copy.deepcopy(joints)
    assert odometry_copy == msg
    assert joints_copy == joints
    odometry_copy.pose.covariance[0] = 3.0
    odometry_copy.pose.pose.position.x = 4.0
    joints_copy.position[0] = 5.0
    joints_copy.name.append('b')
    assert msg.pose.covariance[0] == 2.0
    assert msg.pose.pose.position.x == 0.0
    assert joints.position[0] == 1.0
    assert joints.name == ['a']


def test_messages_pickle_and_unpickle_equal() -> None:
    """Messages pickle (for multiprocessing and caches) and come back equal."""
    msg = Odometry(child_frame_id='base_link_frd')
    msg.pose.covariance[0] = 1.0
    assert pickle.loads(pickle.dumps(msg)) == msg


def test_shallow_copy_shares_nested_messages() -> None:
    """copy.copy copies the top level only, as for any slotted object."""
    msg = Pose()
    shallow = copy.copy(msg)
    assert shallow == msg
    assert shallow.position is msg.position


def test_controller_state_constants_and_fields() -> None:
    """uvms_msgs/ControllerState has its phase constants and typed fields."""
    assert ControllerState.PHASE_CONSTRAINED == 2
    fields = ControllerState.get_fields_and_field_types()
    assert fields['phase'] == 'uint8'
    assert fields['contact_force'] == 'geometry_msgs/Vector3'
    assert fields['position'] == 'geometry_msgs/Point'


_FIELD_LINE = re.compile(r'^([A-Za-z][\w/]*(?:\[[^\]]*\])?)\s+([a-z]\w*)\s*$')


def _msg_file_fields(path: Path) -> dict[str, str]:
    """Field name -> .msg type of a .msg file, skipping comments and constants."""
    fields = {}
    for raw in path.read_text(encoding='utf-8').splitlines():
        line = raw.split('#', 1)[0].strip()
        match = _FIELD_LINE.match(line)
        if match and '=' not in line:
            fields[match.group(2)] = match.group(1)
    return fields


def _msg_to_rosidl(msg_type: str) -> str:
    """Return the rosidl type string of a .msg field type ('float64[]', 'std_msgs/Header')."""
    base, _, rest = msg_type.partition('[')
    element = IDL_NAMES.get(base, base)
    if not rest:
        return element
    size = rest.rstrip(']')
    return f'{element}[{size}]' if size else f'sequence<{element}>'


@pytest.mark.parametrize('path', sorted(UVMS_MSG_DIR.glob('*.msg')), ids=lambda p: p.stem)
def test_uvms_msgs_classes_have_the_fields_of_their_msg_files(path: Path) -> None:
    """Each src/uvms_msgs/msg/*.msg gives a class with exactly the file's fields and types."""
    import uvms_msgs.msg

    cls = getattr(uvms_msgs.msg, path.stem)
    expected = {name: _msg_to_rosidl(typ) for name, typ in _msg_file_fields(path).items()}
    assert cls.get_fields_and_field_types() == expected


def test_uvms_msgs_package_lists_five_types() -> None:
    """dir(uvms_msgs.msg) lists every .msg file of src/uvms_msgs/msg."""
    import uvms_msgs.msg

    assert sorted(p.stem for p in UVMS_MSG_DIR.glob('*.msg')) == sorted(dir(uvms_msgs.msg))
    assert len(dir(uvms_msgs.msg)) == 5


def test_unknown_class_name_raises_attribute_error() -> None:
    """A name that is no message of the package is an AttributeError, as for a real module."""
    import sensor_msgs.msg

    with pytest.raises(AttributeError):
        _ = sensor_msgs.msg.NoSuchMessage  # type: ignore[attr-defined]


def test_type_support_attributes_are_set() -> None:
    """The check_for_type_support of rclpy reads msg_type._TYPE_SUPPORT: it must be set."""
    assert JointState._TYPE_SUPPORT is not None  # type: ignore[attr-defined]
    JointState.__class__.__import_type_support__()  # type: ignore[attr-defined]
