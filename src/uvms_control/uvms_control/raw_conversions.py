"""The controller's hot topics as raw CDR: payloads in and out, numpy inside.

A reader takes a payload of a raw subscription: our simulator's layout is read in place with
`struct` (the allocator's topics: ``uvms_thrusters.raw_conversions``); any other layout (a
frame id of '', joints in another order, from another publisher) is deserialized by rclpy
and judged by the typed readers of `uvms_control.conversions`, which stay the reference; a
payload that is no message of the type raises `MalformedPayloadError` (counted in
``decoder.malformed``). Writers fill preallocated payloads
(`uvms_common.cdr_codecs.PayloadWriter`) with the values the typed builders of
`uvms_control.conversions` put in their messages.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from uvms_common.cdr_codecs import PayloadWriter
from uvms_common.cdr_codecs import RawReader as Reader
from uvms_common.hot_messages import (
    controller_state_codec,
    generalized_force_codec,
    joint_state_codec,
    odometry_codec,
    wrench_codec,
)

from uvms_control import conversions
from uvms_control.conversions import FloatArray
from uvms_control.core.errors import ControlInputError
from uvms_control.core.law.unified_controller import ControllerResult

_STATE_FIELDS = ('weight', 'phase', 'contact_force', 'desired_force', 'position',
                 'desired_position', 'velocity', 'desired_velocity', 'normal_velocity',
                 'impedance_force', 'hybrid_force', 'command_force')


def _finite(name: str, values: tuple[float, ...]) -> FloatArray:
    if not math.isfinite(sum(values)) and not all(math.isfinite(v) for v in values):
        raise ControlInputError(f'{name} holds a non-finite value: {list(values)}')
    return np.array(values)


def joint_state_reader(joint_names: Sequence[str]) -> Reader:
    """``joint_states`` to arm positions (rad) and velocities (rad/s), model joint order."""
    codec = joint_state_codec(joint_names)
    (p_at, p_struct), (v_at, v_struct) = codec.struct(['position']), codec.struct(['velocity'])

    def fast(data: bytes) -> tuple[FloatArray, FloatArray]:
        return (_finite('joint_states.position', p_struct.unpack_from(data, p_at)),
                _finite('joint_states.velocity', v_struct.unpack_from(data, v_at)))

    names = list(joint_names)
    return Reader(codec, fast, lambda msg: conversions.joint_state_arrays(msg, names))


def odometry_reader() -> Reader:
    """``odometry`` to eta = [x, y, z, roll, pitch, yaw] (map_ned) and nu (base_link_frd)."""
    codec = odometry_codec()
    (pose_at, pose), (twist_at, twist) = codec.struct(['pose.pose']), codec.struct(['twist.twist'])

    def fast(data: bytes) -> tuple[FloatArray, FloatArray]:
        x, y, z, qx, qy, qz, qw = pose.unpack_from(data, pose_at)
        position = _finite('odometry pose.position', (x, y, z))
        eta = np.array((*position.tolist(), *conversions.rpy_from_quaternion(qx, qy, qz, qw)))
        return eta, _finite('odometry twist', twist.unpack_from(data, twist_at))

    return Reader(codec, fast, conversions.odometry_arrays)


def wrench_reader() -> Reader:
    """``wrench`` to the force (N) the end effector exerts, in ft_sensor_link axes."""
    codec = wrench_codec()
    at, force = codec.struct(['wrench.force'])
    return Reader(codec, lambda data: _finite('wrench.force', force.unpack_from(data, at)),
                  conversions.wrench_force)


def controller_readers(joint_names: Sequence[str]) -> dict[str, tuple[type, Reader]]:
    """The controller's input topics: their message types and readers, in TOPICS order."""
    return {'joint_states': (JointState, joint_state_reader(joint_names)),
            'odometry': (Odometry, odometry_reader()),
            'wrench': (WrenchStamped, wrench_reader())}




class GeneralizedForceWriter:
    """uvms_msgs/GeneralizedForce payloads from tau_b (6 + n,), frame base_link_frd."""

    def __init__(self, joint_names: Sequence[str]) -> None:
        self._payload = PayloadWriter(generalized_force_codec(joint_names), ['vehicle_wrench'],
                                      ['joint_torques'])

    def payload(self, t_ns: int, tau_b: FloatArray) -> bytes:
        """The command stamped t_ns."""
        values = np.asarray(tau_b, dtype=np.float64).tolist()
        return self._payload.fill(t_ns, values[:6], values[6:])


class ControllerStateWriter:
    """uvms_msgs/ControllerState payloads of controller steps (task space in map_ned)."""

    def __init__(self) -> None:
        self._payload = PayloadWriter(controller_state_codec(), _STATE_FIELDS)

    def payload(self, t_ns: int, result: ControllerResult) -> bytes:
        """The state of one step stamped t_ns."""
        vectors = np.concatenate((result.F_e, result.F_d, result.X, result.X_d, result.X_dot,
                                  result.X_dot_d)).tolist()
        forces = np.concatenate((result.F_IP, result.F_H, result.F_c)).tolist()
        return self._payload.fill(t_ns, (float(result.W), int(result.phase), *vectors,
                                         float(result.v_e), *forces))
