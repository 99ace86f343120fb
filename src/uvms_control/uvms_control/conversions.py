"""Messages to numpy and back for the controller node (the only such place).

Frames: vehicle pose in ``map_ned`` (NED, z down), vehicle twist in ``base_link_frd``, the
wrist wrench in ``ft_sensor_link`` (axes of ``ee_link``), the generalized force command in
``base_link_frd`` (the allocator's messages: ``uvms_thrusters.conversions``). Array fields are
filled with ``array.array('d')``, which the rosidl classes take without a per-element check.
Every reader validates sizes, frames and finiteness and raises `ControlInputError` naming the
field.
"""

from __future__ import annotations

import array
import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Vector3, WrenchStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import Header

from uvms_control.core.errors import ControlInputError
from uvms_control.core.law.unified_controller import ControllerResult
from uvms_msgs.msg import ControllerState, GeneralizedForce

FloatArray = npt.NDArray[np.float64]

MAP_NED = 'map_ned'
BASE_LINK_FRD = 'base_link_frd'
FT_SENSOR_LINK = 'ft_sensor_link'
#: Frames a wrist wrench may be given in: the sensor frame and ee_link share their axes.
WRENCH_FRAMES = ('', FT_SENSOR_LINK, 'ee_link')


def stamp_ns(stamp: Time) -> int:
    """Integer nanoseconds of a builtin_interfaces/Time."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def time_from_ns(t_ns: int) -> Time:
    """builtin_interfaces/Time from integer nanoseconds."""
    sec, nanosec = divmod(int(t_ns), 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def _finite(name: str, values: FloatArray) -> FloatArray:
    # A finite sum of a few floats is the cheap test; a huge sum may overflow, so look again.
    if not math.isfinite(sum(values.tolist())) and not np.all(np.isfinite(values)):
        raise ControlInputError(f'{name} holds a non-finite value: {values.tolist()}')
    return values


def _check_frame(field: str, frame: str, allowed: Sequence[str]) -> None:
    if frame not in allowed:
        expected = ' or '.join(repr(f) for f in allowed if f) or "''"
        raise ControlInputError(f'{field} is {frame!r}, expected {expected}')


def rpy_from_quaternion(x: float, y: float, z: float, w: float) -> tuple[float, float, float]:
    """Roll, pitch, yaw (ZYX) of rot_ned_from_body from a quaternion (normalised here).

    Raises:
        ControlInputError: for a quaternion far from unit length (not a rotation).
    """
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(norm) or abs(norm - 1.0) > 0.1:
        raise ControlInputError(
            f'pose.orientation has norm {norm:.6g}, expected a unit quaternion'
        )
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


def joint_state_arrays(
    msg: JointState, joint_names: Sequence[str]
) -> tuple[FloatArray, FloatArray]:
    """Arm joint positions (rad) and velocities (rad/s) in the model's joint order.

    Joints are matched by name; an unnamed message must list the joints in model order.

    Raises:
        ControlInputError: for missing joints, wrong sizes or non-finite values.
    """
    n = len(joint_names)
    positions = np.asarray(msg.position, dtype=np.float64)
    velocities = np.asarray(msg.velocity, dtype=np.float64)
    names = list(msg.name)
    if names and names == list(joint_names):
        if len(names) != positions.size or len(names) != velocities.size:
            raise ControlInputError(
                f'joint_states names {names} with {positions.size} positions and '
                f'{velocities.size} velocities do not cover the arm joints {list(joint_names)}'
            )
    elif names:
        missing = [name for name in joint_names if name not in names]
        if missing or len(names) != positions.size or len(names) != velocities.size:
            raise ControlInputError(
                f'joint_states names {names} with {positions.size} positions and '
                f'{velocities.size} velocities do not cover the arm joints {list(joint_names)}'
            )
        order = [names.index(name) for name in joint_names]
        positions, velocities = positions[order], velocities[order]
    elif positions.size != n or velocities.size != n:
        raise ControlInputError(
            f'joint_states has {positions.size} positions and {velocities.size} velocities, '
            f'expected {n} ({", ".join(joint_names)})'
        )
    return (
        _finite('joint_states.position', positions),
        _finite('joint_states.velocity', velocities),
    )


def odometry_arrays(msg: Odometry) -> tuple[FloatArray, FloatArray]:
    """Vehicle pose eta = [x, y, z, roll, pitch, yaw] in map_ned and twist nu in base_link_frd.

    Raises:
        ControlInputError: for other frames, a non-unit quaternion or non-finite values.
    """
    _check_frame('odometry header.frame_id', msg.header.frame_id, ('', MAP_NED))
    _check_frame('odometry child_frame_id', msg.child_frame_id, ('', BASE_LINK_FRD))
    pose, twist = msg.pose.pose, msg.twist.twist
    p, o, v, w = pose.position, pose.orientation, twist.linear, twist.angular
    position = _finite('odometry pose.position', np.array((p.x, p.y, p.z), dtype=np.float64))
    eta = np.array(
        (*position.tolist(), *rpy_from_quaternion(float(o.x), float(o.y), float(o.z), float(o.w)))
    )
    nu = np.array((v.x, v.y, v.z, w.x, w.y, w.z), dtype=np.float64)
    return eta, _finite('odometry twist', nu)


def wrench_force(msg: WrenchStamped) -> FloatArray:
    """Force (N) the end effector exerts on the environment, in ft_sensor_link axes.

    Raises:
        ControlInputError: for another frame or non-finite values.
    """
    _check_frame('wrench header.frame_id', msg.header.frame_id, WRENCH_FRAMES)
    f = msg.wrench.force
    return _finite('wrench.force', np.array([f.x, f.y, f.z], dtype=np.float64))


def _set_xyz(target: Vector3 | Point, v: npt.ArrayLike) -> None:
    """Set x, y, z of a Vector3 or Point from a 3-vector, as plain floats."""
    target.x, target.y, target.z = np.asarray(v, dtype=np.float64).tolist()


# The message builders take ``out``, a message an earlier call returned, to refill instead of
# building a new one: rclpy serializes at publish, so a node may keep
# one message per publisher. Frames and joint names are set when the message is built.


def generalized_force_message(
    t_ns: int,
    tau_b: FloatArray,
    joint_names: Sequence[str],
    out: GeneralizedForce | None = None,
) -> GeneralizedForce:
    """uvms_msgs/GeneralizedForce from tau_b (6 + n,): body wrench in base_link_frd, torques."""
    msg = out
    if msg is None:
        msg = GeneralizedForce(header=Header(frame_id=BASE_LINK_FRD))
        msg.joint_names = list(joint_names)
    msg.header.stamp = time_from_ns(t_ns)
    values = np.asarray(tau_b, dtype=np.float64).tolist()
    wrench = msg.vehicle_wrench
    wrench.force.x, wrench.force.y, wrench.force.z = values[0:3]
    wrench.torque.x, wrench.torque.y, wrench.torque.z = values[3:6]
    msg.joint_torques = array.array('d', values[6:])
    return msg




def controller_state_message(
    t_ns: int, result: ControllerResult, out: ControllerState | None = None
) -> ControllerState:
    """uvms_msgs/ControllerState of one controller step (task-space vectors in map_ned)."""
    msg = out if out is not None else ControllerState(header=Header(frame_id=MAP_NED))
    msg.header.stamp = time_from_ns(t_ns)
    msg.weight = float(result.W)
    msg.phase = int(result.phase)
    _set_xyz(msg.contact_force, result.F_e)
    _set_xyz(msg.desired_force, result.F_d)
    _set_xyz(msg.position, result.X)
    _set_xyz(msg.desired_position, result.X_d)
    _set_xyz(msg.velocity, result.X_dot)
    _set_xyz(msg.desired_velocity, result.X_dot_d)
    msg.normal_velocity = float(result.v_e)
    _set_xyz(msg.impedance_force, result.F_IP)
    _set_xyz(msg.hybrid_force, result.F_H)
    _set_xyz(msg.command_force, result.F_c)
    return msg
