"""Messages to numpy and back for the controller and allocator nodes (the only such place).

Frames: vehicle pose in ``map_ned`` (NED, z down), vehicle twist in ``base_link_frd``, the
wrist wrench in ``ft_sensor_link`` (axes of ``ee_link``), the generalized force command in
``base_link_frd``. Array fields are filled with ``array.array('d')``, which both the real
rosidl classes and ros2_compat accept. Every reader validates sizes, frames and finiteness
and raises `ControlInputError` naming the field.
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

from uvms_control.core.allocation import AllocatorOutput
from uvms_control.core.errors import ControlInputError
from uvms_control.core.unified_controller import ControllerResult
from uvms_msgs.msg import ActuatorCommand, ControllerState, GeneralizedForce, ThrusterState

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
    if not np.all(np.isfinite(values)):
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
    if names:
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
    position = _finite(
        'odometry pose.position',
        np.array([pose.position.x, pose.position.y, pose.position.z], dtype=np.float64),
    )
    o = pose.orientation
    eta = np.empty(6)
    eta[:3] = position
    eta[3:] = rpy_from_quaternion(float(o.x), float(o.y), float(o.z), float(o.w))
    nu = np.array(
        [
            twist.linear.x,
            twist.linear.y,
            twist.linear.z,
            twist.angular.x,
            twist.angular.y,
            twist.angular.z,
        ],
        dtype=np.float64,
    )
    return eta, _finite('odometry twist', nu)


def wrench_force(msg: WrenchStamped) -> FloatArray:
    """Force (N) the end effector exerts on the environment, in ft_sensor_link axes.

    Raises:
        ControlInputError: for another frame or non-finite values.
    """
    _check_frame('wrench header.frame_id', msg.header.frame_id, WRENCH_FRAMES)
    f = msg.wrench.force
    return _finite('wrench.force', np.array([f.x, f.y, f.z], dtype=np.float64))


def _vector3(v: FloatArray) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _point(v: FloatArray) -> Point:
    return Point(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _floats(values: npt.ArrayLike) -> array.array[float]:
    return array.array('d', np.asarray(values, dtype=np.float64).tolist())


def generalized_force_message(
    t_ns: int, tau_b: FloatArray, joint_names: Sequence[str]
) -> GeneralizedForce:
    """uvms_msgs/GeneralizedForce from tau_b (9,): body wrench in base_link_frd, joint torques."""
    msg = GeneralizedForce(header=Header(stamp=time_from_ns(t_ns), frame_id=BASE_LINK_FRD))
    msg.vehicle_wrench.force = _vector3(tau_b[0:3])
    msg.vehicle_wrench.torque = _vector3(tau_b[3:6])
    msg.joint_names = list(joint_names)
    msg.joint_torques = _floats(tau_b[6:])
    return msg


def generalized_force_arrays(
    msg: GeneralizedForce, joint_names: Sequence[str]
) -> tuple[int, FloatArray]:
    """Stamp (ns) and tau_b (6 + n,) of a command, joint torques in the model's order.

    Raises:
        ControlInputError: for another frame, wrong joint names or sizes, non-finite values.
    """
    _check_frame('command header.frame_id', msg.header.frame_id, ('', BASE_LINK_FRD))
    torques = np.asarray(msg.joint_torques, dtype=np.float64)
    names = list(msg.joint_names)
    n = len(joint_names)
    if torques.size != n:
        raise ControlInputError(
            f'joint_torques has {torques.size} values, expected {n} ({", ".join(joint_names)})'
        )
    if names and names != list(joint_names):
        if sorted(names) != sorted(joint_names):
            raise ControlInputError(
                f'joint_names {names} do not match the arm joints {list(joint_names)}'
            )
        torques = torques[[names.index(name) for name in joint_names]]
    wrench = msg.vehicle_wrench
    tau_b = np.empty(6 + n)
    tau_b[:6] = (
        wrench.force.x,
        wrench.force.y,
        wrench.force.z,
        wrench.torque.x,
        wrench.torque.y,
        wrench.torque.z,
    )
    tau_b[6:] = torques
    return stamp_ns(msg.header.stamp), _finite('generalized force', tau_b)


def controller_state_message(t_ns: int, result: ControllerResult) -> ControllerState:
    """uvms_msgs/ControllerState of one controller step (task-space vectors in map_ned)."""
    msg = ControllerState(header=Header(stamp=time_from_ns(t_ns), frame_id=MAP_NED))
    msg.weight = float(result.W)
    msg.phase = int(result.phase)
    msg.contact_force = _vector3(result.F_e)
    msg.desired_force = _vector3(result.F_d)
    msg.position = _point(result.X)
    msg.desired_position = _point(result.X_d)
    msg.velocity = _vector3(result.X_dot)
    msg.desired_velocity = _vector3(result.X_dot_d)
    msg.normal_velocity = float(result.v_e)
    msg.impedance_force = _vector3(result.F_IP)
    msg.hybrid_force = _vector3(result.F_H)
    msg.command_force = _vector3(result.F_c)
    return msg


def actuator_command_message(
    t_ns: int, thrust: FloatArray, joint_names: Sequence[str], joint_torques: FloatArray
) -> ActuatorCommand:
    """uvms_msgs/ActuatorCommand: actual thrusts (N) and motor torques (N m)."""
    return ActuatorCommand(
        header=Header(stamp=time_from_ns(t_ns), frame_id=BASE_LINK_FRD),
        thrust=_floats(thrust),
        joint_names=list(joint_names),
        joint_torques=_floats(joint_torques),
    )


def thruster_state_message(t_ns: int, output: AllocatorOutput) -> ThrusterState:
    """uvms_msgs/ThrusterState of one allocator step."""
    allocation = output.allocation
    msg = ThrusterState(header=Header(stamp=time_from_ns(t_ns), frame_id=BASE_LINK_FRD))
    msg.desired_thrust = _floats(allocation.thrust)
    msg.actual_thrust = _floats(output.thrust)
    msg.propeller_speed = _floats(output.propeller_speed)
    msg.reference_speed = _floats(output.reference_speed)
    msg.motor_current = _floats(output.motor_current)
    msg.achieved_wrench.force = _vector3(allocation.achieved_wrench[0:3])
    msg.achieved_wrench.torque = _vector3(allocation.achieved_wrench[3:6])
    msg.saturation_scale = float(allocation.saturation_scale)
    return msg
