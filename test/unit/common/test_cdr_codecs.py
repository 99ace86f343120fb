"""The hot-path codecs against rclpy's serializer and rosbags (an independent oracle)."""

from __future__ import annotations

import functools
import importlib
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rclpy.serialization import deserialize_message, serialize_message
from uvms_common.cdr_codecs import (
    CodecError,
    Leaf,
    MalformedPayloadError,
    MessageCodec,
    RawDecoder,
    read_stamp_ns,
    write_stamp,
)
from uvms_common.hot_messages import hot_codecs, joint_state_codec, wrench_codec
from uvms_recording.typestore import uvms_typestore

from uvms_description import hydrodynamics_path, robots_directory, urdf_path
from uvms_model import load_description

ROBOTS = ('paper_uvms', 'bluerov2_alpha5')
TOPICS = tuple(hot_codecs(['a'], 6))


@functools.cache
def robot_codecs(robot: str) -> dict[str, MessageCodec]:
    """The hot codecs of one shipped robot: its URDF's joints, its thrusters.yaml's count."""
    joints = load_description(urdf_path(robot), hydrodynamics_path(robot)).joint_names
    document = yaml.safe_load((robots_directory() / robot / 'thrusters.yaml').read_text())
    positions = document['/**']['ros__parameters']['thrusters']['positions_m']
    return hot_codecs(joints, len(positions) // 3)


def type_name(msg_type: type) -> str:
    """'pkg/msg/Type' of a rosidl class."""
    return f'{msg_type.__module__.split(".")[0]}/msg/{msg_type.__name__}'


def get_path(msg: Any, path: str) -> Any:
    """A field of a message by its dotted path."""
    for name in path.split('.'):
        msg = getattr(msg, name)
    return msg


def set_path(msg: Any, path: str, value: Any) -> None:
    """Set a field of a message by its dotted path."""
    *parents, name = path.split('.')
    for parent in parents:
        msg = getattr(msg, parent)
    setattr(msg, name, value)


def leaf_strategy(codec: MessageCodec, leaf: Leaf) -> st.SearchStrategy[Any]:
    """Random values of one number field: finite doubles, any integer of its type."""
    element: st.SearchStrategy[Any] = {
        'd': st.floats(allow_nan=False, width=64),
        'B': st.integers(0, 255), '?': st.booleans(),
        'i': st.integers(-2**31, 2**31 - 1), 'I': st.integers(0, 2**32 - 1),
    }[leaf.code]
    if leaf.count == 1 and leaf.path not in _sequence_paths(codec):
        return element
    return st.lists(element, min_size=leaf.count, max_size=leaf.count)


def random_values(codec: MessageCodec) -> st.SearchStrategy[dict[str, Any]]:
    """Random numbers for every number field of the layout."""
    return st.fixed_dictionaries({leaf.path: leaf_strategy(codec, leaf)
                                  for leaf in codec.fields})


def _sequence_paths(codec: MessageCodec) -> set[str]:
    fields = codec.msg_type.get_fields_and_field_types()  # type: ignore[attr-defined]
    return {name for name, kind in fields.items() if kind.startswith('sequence<')}


def encode(codec: MessageCodec, values: dict[str, Any]) -> bytes:
    """A payload written by the codec."""
    out = codec.message()
    for path, value in values.items():
        codec.pack(path, out, value if isinstance(value, list) else [value])
    return bytes(out)


def typed_message(codec: MessageCodec, fixed: dict[str, Any], values: dict[str, Any]) -> Any:
    """The rclpy message holding the given values."""
    msg = codec.msg_type()
    for path, value in {**fixed, **values}.items():
        leaf = codec.leaves.get(path)
        if isinstance(value, list) and leaf is not None and leaf.code == 'd':
            value = np.asarray(value, dtype=np.float64)
        set_path(msg, path, value)
    return msg


def fixed_values(codec: MessageCodec) -> dict[str, Any]:
    """The frame ids and names a codec was built with (its counts left out)."""
    return {path: value for path, value in codec.fixed.items() if not isinstance(value, int)}


def to_rosbags(msg: Any, store: Any) -> Any:
    """An rclpy message as the rosbags dataclass of the same type."""
    fields = type(msg).get_fields_and_field_types()
    values = {}
    for name, kind in fields.items():
        value = getattr(msg, name)
        if '/' in kind and not kind.startswith('sequence'):
            values[name] = to_rosbags(value, store)
        elif kind.startswith('sequence<double') or kind.startswith('double['):
            values[name] = np.asarray(value, dtype=np.float64)
        elif kind == 'sequence<string>':
            values[name] = list(value)
        else:
            values[name] = value
    return store.types[type_name(type(msg))](**values)


def assert_same_values(codec: MessageCodec, values: dict[str, Any], msg: Any) -> None:
    """Every value is in the message (rclpy's or rosbags'), exactly."""
    for path, value in values.items():
        got = get_path(msg, path)
        np.testing.assert_array_equal(np.asarray(got), np.asarray(value), err_msg=path)


def defined_bytes(codec: MessageCodec, data: bytes) -> bytes:
    """The payload without its padding bytes (what CDR leaves undefined)."""
    mask = np.zeros(codec.size, dtype=bool)
    mask[:2] = True
    for start, end in codec._constant:
        mask[start:end] = True
    for leaf in codec.leaves.values():
        mask[leaf.offset:leaf.offset + leaf.size] = True
    return bytes(np.frombuffer(data[:codec.size], dtype=np.uint8)[mask])


CASES = [(robot, topic) for robot in ROBOTS for topic in TOPICS]


@pytest.mark.parametrize(('robot', 'topic'), CASES)
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_our_payload_reads_the_same_in_rclpy_and_rosbags(robot: str, topic: str,
                                                         data: st.DataObject) -> None:
    """Numbers written by the codec are what rclpy and rosbags deserialize, fields intact."""
    codec = robot_codecs(robot)[topic]
    values = data.draw(random_values(codec))
    ours = encode(codec, values)
    assert len(ours) == codec.size
    from_rclpy = deserialize_message(ours, codec.msg_type)
    assert_same_values(codec, {**values, **fixed_values(codec)}, from_rclpy)
    from_rosbags = uvms_typestore().deserialize_cdr(ours, type_name(codec.msg_type))
    assert_same_values(codec, {**values, **fixed_values(codec)}, from_rosbags)
    # rclpy's serializer leaves padding bytes undefined; rosbags writes them as zeros, as we do.
    theirs = serialize_message(from_rclpy)
    assert defined_bytes(codec, theirs) == defined_bytes(codec, ours)
    assert uvms_typestore().serialize_cdr(from_rosbags, type_name(codec.msg_type)) == ours


@pytest.mark.parametrize(('robot', 'topic'), CASES)
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_rclpy_and_rosbags_payloads_read_the_same_in_ours(robot: str, topic: str,
                                                          data: st.DataObject) -> None:
    """A message serialized by rclpy or by rosbags fits the layout and views the same numbers."""
    codec = robot_codecs(robot)[topic]
    values = data.draw(random_values(codec))
    msg = typed_message(codec, fixed_values(codec), values)
    store = uvms_typestore()
    for payload in (serialize_message(msg),
                    store.serialize_cdr(to_rosbags(msg, store), type_name(codec.msg_type))):
        assert codec.check(payload) is None
        view = codec.view(payload)
        for path, value in values.items():
            np.testing.assert_array_equal(view[path], np.asarray(value), err_msg=path)
        decoded = RawDecoder(codec).decode(payload)
        assert decoded.view is not None and decoded.message is None


@pytest.mark.parametrize('t_ns', [0, 1, 999_999_999, 1_000_000_000, 123_456_789_012])
def test_stamp_round_trips_through_rclpy(t_ns: int) -> None:
    """header.stamp written in ns reads back as sec and nanosec in rclpy and in ns here."""
    codec = wrench_codec()
    out = codec.message()
    write_stamp(out, t_ns)
    stamp = deserialize_message(bytes(out), codec.msg_type).header.stamp
    assert (stamp.sec, stamp.nanosec) == divmod(t_ns, 1_000_000_000)
    assert read_stamp_ns(bytes(out)) == t_ns


def test_groups_view_contiguous_sub_messages() -> None:
    """pose.pose of an Odometry is position then orientation: 7 doubles in one view."""
    codec = robot_codecs('paper_uvms')['odometry']
    out = codec.message()
    codec.pack('pose.pose', out, [1, 2, 3, 0, 0, 0, 1])
    view = codec.view(bytes(out))
    assert view['pose.pose.orientation.w'] == 1.0
    np.testing.assert_array_equal(view['pose.pose.position'], [1, 2, 3])


def test_a_variable_field_without_its_length_is_refused() -> None:
    """A codec needs every length and string fixed; the error names the missing one."""
    from sensor_msgs.msg import JointState
    with pytest.raises(CodecError, match="'name'"):
        MessageCodec(JointState, {'header.frame_id': '', 'position': 3})


def test_a_fixed_value_for_no_field_is_refused() -> None:
    """A misspelled field path is named, not ignored."""
    from geometry_msgs.msg import WrenchStamped
    with pytest.raises(CodecError, match="'frame'"):
        MessageCodec(WrenchStamped, {'header.frame_id': '', 'frame': 'x'})


def _malformed_payloads() -> dict[str, bytes]:
    codec = wrench_codec()
    good = bytes(codec.message())
    return {
        'empty': b'',
        'truncated': good[:-9],
        'header only': good[:4],
        'encapsulation': b'\xff\xff' + good[2:],
        'garbage': bytes(range(256)),
    }


@pytest.mark.parametrize('name', list(_malformed_payloads()))
def test_malformed_payload_is_refused_and_counted(name: str) -> None:
    """A payload that neither the layout nor rclpy reads raises MalformedPayloadError, counted."""
    payload = _malformed_payloads()[name]
    decoder = RawDecoder(wrench_codec())
    assert decoder.codec.check(payload) is not None
    with pytest.raises(MalformedPayloadError):
        decoder.decode(payload)
    assert decoder.malformed == 1
    assert decoder.last_error.startswith('WrenchStamped: ')


def test_another_layout_is_read_by_rclpy_for_the_typed_checks() -> None:
    """A JointState with other joints does not fit; rclpy reads it, the node's checks judge."""
    from sensor_msgs.msg import JointState
    codec = joint_state_codec(['joint_1', 'joint_2', 'joint_3'])
    foreign = serialize_message(JointState(name=['joint_1'], position=[0.5], velocity=[0.0],
                                           effort=[0.0]))
    assert codec.check(foreign) is not None
    decoded = RawDecoder(codec).decode(foreign)
    assert decoded.view is None and list(decoded.message.name) == ['joint_1']


def test_trailing_padding_is_accepted_but_not_more() -> None:
    """Up to 3 trailing bytes (XCDR rounds a payload to 4 bytes) fit; 4 do not."""
    codec = wrench_codec()
    good = bytes(codec.message())
    assert codec.check(good + b'\0\0\0') is None
    assert codec.check(good + b'\0\0\0\0') is not None


def test_module_imports_rclpy_only_for_the_fallback() -> None:
    """The codec module itself needs numpy only: rclpy is imported by the fallback path."""
    source = importlib.util.find_spec('uvms_common.cdr_codecs').origin  # type: ignore[union-attr]
    text = open(source).read()
    assert 'import rclpy' not in text.split('class RawDecoder')[0]
