"""The control nodes' raw payloads match their typed messages; raw readers match typed ones."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from geometry_msgs.msg import WrenchStamped
from hypothesis import given, settings
from hypothesis import strategies as st
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from uvms_control.core.errors import ControlInputError
from uvms_control.core.law.unified_controller import ControllerResult, Phase
from uvms_thrusters.allocation import AllocationResult, AllocatorOutput
from uvms_thrusters.errors import ThrusterInputError

from uvms_control import conversions, raw_conversions
from uvms_msgs.msg import GeneralizedForce
from uvms_thrusters import conversions as thruster_conversions
from uvms_thrusters import raw_conversions as thruster_raw

JOINTS = ('joint_1', 'joint_2', 'joint_3', 'joint_4')
P = 8
finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


def vec(n: int) -> st.SearchStrategy[np.ndarray]:
    """Random finite vectors of n values."""
    return st.lists(finite, min_size=n, max_size=n).map(np.array)


def plain(msg: Any) -> dict[str, Any]:
    """A message as nested plain values, to compare two messages field by field."""
    out: dict[str, Any] = {}
    for name in type(msg).get_fields_and_field_types():
        value = getattr(msg, name)
        out[name] = plain(value) if hasattr(value, 'get_fields_and_field_types') else (
            list(value) if not isinstance(value, str | bool | int | float) else value)
    return out


def same(payload: bytes, typed: Any) -> None:
    """The payload deserializes to exactly the typed message."""
    assert plain(deserialize_message(payload, type(typed))) == plain(typed)


@settings(max_examples=30, deadline=None)
@given(t_ns=st.integers(0, 2**40), tau_b=vec(6 + len(JOINTS)))
def test_generalized_force_payload_is_the_typed_message(t_ns: int, tau_b: np.ndarray) -> None:
    """GeneralizedForce: stamp, frame, joint names, wrench and torques as the typed builder."""
    same(raw_conversions.GeneralizedForceWriter(JOINTS).payload(t_ns, tau_b),
         conversions.generalized_force_message(t_ns, tau_b, JOINTS))


@settings(max_examples=30, deadline=None)
@given(t_ns=st.integers(0, 2**40), v=st.lists(vec(3), min_size=9, max_size=9),
       w=st.floats(0.0, 1.0), v_e=finite, phase=st.sampled_from(list(Phase)))
def test_controller_state_payload_is_the_typed_message(
        t_ns: int, v: list[np.ndarray], w: float, v_e: float, phase: Phase) -> None:
    """ControllerState: every vector, W, v_e and the phase as the typed builder."""
    zeros = np.zeros(3)
    result = ControllerResult(tau_b=zeros, tau=zeros, W=w, X=v[0], X_d=v[1], X_dot=v[2],
                              X_dot_d=v[3], F_e=v[4], F_d=v[5], F_c=v[6], F_IP=v[7], F_H=v[8],
                              v_e=v_e, force_ratio=0.0, phase=phase, M_hat=zeros,
                              zeta_hat=zeros)
    same(raw_conversions.ControllerStateWriter().payload(t_ns, result),
         conversions.controller_state_message(t_ns, result))


@settings(max_examples=30, deadline=None)
@given(t_ns=st.integers(0, 2**40), thrust=vec(P), torques=vec(len(JOINTS)))
def test_actuator_command_payload_is_the_typed_message(t_ns: int, thrust: np.ndarray,
                                                       torques: np.ndarray) -> None:
    """ActuatorCommand: thrusts, names and torques as the typed builder."""
    same(thruster_raw.ActuatorCommandWriter(P, JOINTS).payload(t_ns, thrust, torques),
         thruster_conversions.actuator_command_message(t_ns, thrust, JOINTS, torques))


@settings(max_examples=30, deadline=None)
@given(t_ns=st.integers(0, 2**40), arrays=st.lists(vec(P), min_size=5, max_size=5),
       achieved=vec(6), scale=st.floats(0.01, 1.0))
def test_thruster_state_payload_is_the_typed_message(t_ns: int, arrays: list[np.ndarray],
                                                     achieved: np.ndarray, scale: float) -> None:
    """ThrusterState: the five per-thruster arrays, achieved wrench and scale."""
    allocation = AllocationResult(arrays[0], np.zeros(4), achieved, scale, 1.0)
    output = AllocatorOutput(allocation, arrays[1], np.zeros(4), arrays[2], arrays[3],
                             arrays[4])
    same(thruster_raw.ThrusterStateWriter(P).payload(t_ns, output),
         thruster_conversions.thruster_state_message(t_ns, output))


def stamped(msg: Any, t_ns: int, frame: str) -> Any:
    """The message with header stamp t_ns and frame."""
    msg.header = Header(frame_id=frame)
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(t_ns, 1_000_000_000)
    return msg


def both_ways(reader: raw_conversions.Reader, typed: Any, expected: Any) -> None:
    """The reader gives the typed reader's value, its stamp included."""
    stamp, value = reader.read(serialize_message(typed))
    assert stamp == conversions.stamp_ns(typed.header.stamp)
    for got, want in zip(value if isinstance(value, tuple) else (value,),
                         expected if isinstance(expected, tuple) else (expected,), strict=True):
        np.testing.assert_array_equal(got, want)


@settings(max_examples=30, deadline=None)
@given(q=vec(4), dq=vec(4), t_ns=st.integers(0, 2**40))
def test_joint_states_read_as_the_typed_reader(q: np.ndarray, dq: np.ndarray,
                                               t_ns: int) -> None:
    """Our layout (read in place) and another joint order (typed) give the model's order."""
    reader = raw_conversions.joint_state_reader(JOINTS)
    ours = stamped(JointState(name=list(JOINTS), position=q, velocity=dq, effort=np.zeros(4)),
                   t_ns, '')
    assert reader.decode(serialize_message(ours)).view is not None
    both_ways(reader, ours, (q, dq))
    order = [2, 0, 3, 1]
    shuffled = stamped(JointState(name=[JOINTS[i] for i in order], position=q[order],
                                  velocity=dq[order], effort=np.zeros(4)), t_ns, '')
    assert reader.decode(serialize_message(shuffled)).view is None
    both_ways(reader, shuffled, (q, dq))


@pytest.mark.parametrize('rpy', [(0.0, 0.0, 0.0), (0.3, -0.2, 1.4), (-1.0, 0.5, -3.0)])
def test_odometry_reads_as_the_typed_reader(rpy: tuple[float, float, float]) -> None:
    """Pose to eta (roll, pitch, yaw from the quaternion) and twist to nu, both layouts."""
    from uvms_model.coordinates import quaternion_xyzw
    msg = stamped(Odometry(child_frame_id='base_link_frd'), 4_000_000, 'map_ned')
    p, o = msg.pose.pose.position, msg.pose.pose.orientation
    p.x, p.y, p.z = 1.0, -2.0, 3.0
    o.x, o.y, o.z, o.w = quaternion_xyzw(*rpy)
    t = msg.twist.twist
    t.linear.x, t.angular.z = 0.5, -0.25
    reader = raw_conversions.odometry_reader()
    assert reader.decode(serialize_message(msg)).view is not None
    both_ways(reader, msg, conversions.odometry_arrays(msg))
    unnamed = stamped(msg, 4_000_000, '')
    unnamed.child_frame_id = ''
    assert reader.decode(serialize_message(unnamed)).view is None
    both_ways(reader, unnamed, conversions.odometry_arrays(msg))


@pytest.mark.parametrize(('topic', 'field'), [('wrench', 'wrench.force'),
                                              ('odometry', 'odometry twist'),
                                              ('command', 'generalized force')])
def test_non_finite_values_in_our_layout_are_rejected_naming_the_field(topic: str,
                                                                       field: str) -> None:
    """NaN/Inf read in place are refused as the typed readers refuse them."""
    if topic == 'wrench':
        msg = stamped(WrenchStamped(), 0, 'ft_sensor_link')
        msg.wrench.force.y = math.nan
        reader = raw_conversions.wrench_reader()
    elif topic == 'odometry':
        msg = stamped(Odometry(child_frame_id='base_link_frd'), 0, 'map_ned')
        msg.pose.pose.orientation.w = 1.0
        msg.twist.twist.angular.x = math.inf
        reader = raw_conversions.odometry_reader()
    else:
        msg = stamped(GeneralizedForce(joint_names=list(JOINTS),
                                       joint_torques=[0.0, math.nan, 0.0, 0.0]),
                      0, 'base_link_frd')
        reader = thruster_raw.generalized_force_reader(JOINTS)
    reader_is_allocators = topic not in ('wrench', 'odometry')
    data = serialize_message(msg)
    assert reader.decode(data).view is not None
    with pytest.raises(ThrusterInputError if reader_is_allocators else ControlInputError,
                       match=field):
        reader.read(data)


def test_odometry_in_another_frame_is_refused_as_before() -> None:
    """An ENU odometry (frame 'map') does not fit; the typed check names the frame."""
    msg = stamped(Odometry(child_frame_id='base_link_frd'), 0, 'map')
    msg.pose.pose.orientation.w = 1.0
    with pytest.raises(ControlInputError, match='frame_id'):
        raw_conversions.odometry_reader().read(serialize_message(msg))


def test_generalized_force_in_another_joint_order_is_reordered() -> None:
    """A command naming the joints in another order reads in the model's order."""
    msg = stamped(GeneralizedForce(joint_names=['joint_4', 'joint_3', 'joint_2', 'joint_1'],
                                   joint_torques=[4.0, 3.0, 2.0, 1.0]), 0, 'base_link_frd')
    msg.vehicle_wrench.force.x = 10.0
    _, tau_b = thruster_raw.generalized_force_reader(JOINTS).read(serialize_message(msg))
    np.testing.assert_array_equal(tau_b, [10.0, 0, 0, 0, 0, 0, 1.0, 2.0, 3.0, 4.0])
