"""Messages to numpy and back for the simulator node; the only place NED/FRD meet ENU/FLU.

Every other module of uvms_sim works in map_ned and base_link_frd with numpy arrays. Here
they become ROS messages, and the static /tf twins ``map`` (ENU) and ``base_link`` (FLU)
are tied to ``map_ned`` and ``base_link_frd`` (REP-103, REP-105).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import (
    PoseStamped,
    Quaternion,
    TransformStamped,
    Vector3,
    WrenchStamped,
)
from nav_msgs.msg import Odometry
from numpy.typing import NDArray
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage
from uvms_model.contact import ContactState as ContactTruth

from uvms_msgs.msg import ActuatorCommand, ContactState
from uvms_sim.errors import CommandError

FloatArray = NDArray[np.float64]

MAP_NED = 'map_ned'
BASE_LINK_FRD = 'base_link_frd'
FT_SENSOR_LINK = 'ft_sensor_link'
MAP_ENU = 'map'
BASE_LINK_FLU = 'base_link'

#: Parent of each robot frame in the /tf tree (map -> map_ned -> base_link_frd -> ...).
FRAME_PARENTS: dict[str, str] = {
    'link_1': BASE_LINK_FRD,
    'link_2': 'link_1',
    'link_3': 'link_2',
    'ee_link': 'link_3',
    'ft_sensor_link': 'ee_link',
}

#: map_ned axes in map (ENU): north = y_enu, east = x_enu, down = -z_enu.
ROT_ENU_FROM_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: base_link (FLU) axes in base_link_frd: forward = x, left = -y, up = -z.
ROT_FRD_FROM_FLU = np.diag([1.0, -1.0, -1.0])


def time_from_ns(t_ns: int) -> Time:
    """builtin_interfaces/Time from integer nanoseconds."""
    sec, nanosec = divmod(int(t_ns), 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def ns_from_time(stamp: Time) -> int:
    """Integer nanoseconds of a builtin_interfaces/Time."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def quaternion_from_rpy(
    roll: float, pitch: float, yaw: float
) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) of rot_ned_from_body = Rz(yaw) Ry(pitch) Rx(roll) (ZYX)."""
    cr, sr = math.cos(0.5 * roll), math.sin(0.5 * roll)
    cp, sp = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    cy, sy = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


def quaternion_from_rotation(rot: FloatArray) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w), w >= 0, of a rotation matrix (Shepperd's method)."""
    m = np.asarray(rot, dtype=float)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)
        x, y, z, w = m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1], 0.25 * s * s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        x, y, z, w = 0.25 * s * s, m[0, 1] + m[1, 0], m[0, 2] + m[2, 0], m[2, 1] - m[1, 2]
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        x, y, z, w = m[0, 1] + m[1, 0], 0.25 * s * s, m[1, 2] + m[2, 1], m[0, 2] - m[2, 0]
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        x, y, z, w = m[0, 2] + m[2, 0], m[1, 2] + m[2, 1], 0.25 * s * s, m[1, 0] - m[0, 1]
    x, y, z, w = x / s, y / s, z / s, w / s
    sign = -1.0 if w < 0.0 else 1.0
    return float(sign * x), float(sign * y), float(sign * z), float(sign * w)


def _quaternion(xyzw: tuple[float, float, float, float]) -> Quaternion:
    return Quaternion(x=xyzw[0], y=xyzw[1], z=xyzw[2], w=xyzw[3])


def _vector3(v: FloatArray | Sequence[float]) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def clock_message(t_ns: int) -> Clock:
    """rosgraph_msgs/Clock at simulated time t_ns."""
    return Clock(clock=time_from_ns(t_ns))


def joint_state_message(
    t_ns: int,
    names: Sequence[str],
    positions: FloatArray,
    velocities: FloatArray,
    efforts: FloatArray,
) -> JointState:
    """sensor_msgs/JointState of the arm: rad, rad/s and the applied motor torques N*m."""
    return JointState(
        header=Header(stamp=time_from_ns(t_ns), frame_id=''),
        name=list(names),
        position=np.asarray(positions, dtype=float),
        velocity=np.asarray(velocities, dtype=float),
        effort=np.asarray(efforts, dtype=float),
    )


def odometry_message(t_ns: int, eta: FloatArray, nu: FloatArray) -> Odometry:
    """nav_msgs/Odometry of the vehicle: pose in map_ned, twist in base_link_frd.

    Args:
        t_ns: Simulated time (ns).
        eta: Position in map_ned (m) and roll, pitch, yaw (rad), shape (6,).
        nu: Body velocity [u, v, w] (m/s) and rates [p, q, r] (rad/s) in base_link_frd.
    """
    msg = Odometry(header=Header(stamp=time_from_ns(t_ns), frame_id=MAP_NED),
                   child_frame_id=BASE_LINK_FRD)
    pose = msg.pose.pose
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in eta[:3])
    pose.orientation = _quaternion(
        quaternion_from_rpy(float(eta[3]), float(eta[4]), float(eta[5])))
    msg.twist.twist.linear = _vector3(nu[:3])
    msg.twist.twist.angular = _vector3(nu[3:6])
    return msg


def wrench_message(t_ns: int, force: FloatArray, torque: FloatArray) -> WrenchStamped:
    """geometry_msgs/WrenchStamped of the wrist sensor in ft_sensor_link (N, N*m)."""
    msg = WrenchStamped(header=Header(stamp=time_from_ns(t_ns), frame_id=FT_SENSOR_LINK))
    msg.wrench.force = _vector3(force)
    msg.wrench.torque = _vector3(torque)
    return msg


def pose_message(t_ns: int, p_ned: FloatArray, rot_ned_from_frame: FloatArray) -> PoseStamped:
    """geometry_msgs/PoseStamped of a frame in map_ned."""
    msg = PoseStamped(header=Header(stamp=time_from_ns(t_ns), frame_id=MAP_NED))
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = (float(v) for v in p_ned)
    msg.pose.orientation = _quaternion(quaternion_from_rotation(rot_ned_from_frame))
    return msg


def contact_message(t_ns: int, truth: ContactTruth) -> ContactState:
    """uvms_msgs/ContactState from the plant's contact ground truth (map_ned)."""
    return ContactState(
        header=Header(stamp=time_from_ns(t_ns), frame_id=MAP_NED),
        in_contact=bool(truth.in_contact),
        force=_vector3(truth.force_ned),
        penetration=float(truth.penetration_m),
        wall_position=float(truth.wall_position_m),
        wall_velocity=float(truth.wall_velocity_m_s),
    )


def _transform(
    t_ns: int, parent: str, child: str, p: FloatArray, rot: FloatArray
) -> TransformStamped:
    """TransformStamped: pose of ``child`` in ``parent`` (p in parent, rot_parent_from_child)."""
    msg = TransformStamped(header=Header(stamp=time_from_ns(t_ns), frame_id=parent),
                           child_frame_id=child)
    msg.transform.translation = _vector3(p)
    msg.transform.rotation = _quaternion(quaternion_from_rotation(rot))
    return msg


def tf_message(
    t_ns: int, poses: Mapping[str, tuple[FloatArray, FloatArray]]
) -> TFMessage:
    """/tf of the robot: map_ned -> base_link_frd -> link_1 -> ... -> ft_sensor_link.

    Args:
        t_ns: Simulated time (ns).
        poses: {frame: (p_ned, rot_ned_from_frame)} of the plant.
    """
    p_base, rot_base = poses[BASE_LINK_FRD]
    transforms = [_transform(t_ns, MAP_NED, BASE_LINK_FRD, p_base, rot_base)]
    for child, parent in FRAME_PARENTS.items():
        if child == FT_SENSOR_LINK:
            continue  # fixed to ee_link: on /tf_static
        p_parent, rot_parent = poses[parent]
        p_child, rot_child = poses[child]
        transforms.append(_transform(
            t_ns, parent, child,
            rot_parent.T @ (p_child - p_parent), rot_parent.T @ rot_child,
        ))
    return TFMessage(transforms=transforms)


def static_tf_message(
    t_ns: int, poses: Mapping[str, tuple[FloatArray, FloatArray]]
) -> TFMessage:
    """/tf_static: the ENU/FLU twins and the sensor mount.

    ``map`` (ENU) is the parent of ``map_ned``; ``base_link`` (FLU) hangs under
    ``base_link_frd`` (a frame has one parent in tf2, and base_link_frd's is map_ned), so
    tools that expect ``map`` and ``base_link`` find them; ``ft_sensor_link`` is fixed to
    ``ee_link``.
    """
    p_ee, rot_ee = poses['ee_link']
    p_s, rot_s = poses[FT_SENSOR_LINK]
    return TFMessage(transforms=[
        _transform(t_ns, MAP_ENU, MAP_NED, np.zeros(3), ROT_ENU_FROM_NED),
        _transform(t_ns, BASE_LINK_FRD, BASE_LINK_FLU, np.zeros(3), ROT_FRD_FROM_FLU),
        _transform(t_ns, 'ee_link', FT_SENSOR_LINK, rot_ee.T @ (p_s - p_ee), rot_ee.T @ rot_s),
    ])


def actuator_command_arrays(
    msg: ActuatorCommand, n_thrusters: int, joint_names: Sequence[str]
) -> tuple[int, FloatArray, FloatArray]:
    """Stamp (ns), thrusts (N) and joint torques (N*m, in the model's joint order).

    Raises:
        CommandError: Wrong number of thrusts or torques, unknown or repeated joint names,
            or a NaN/Inf value; the message names the field.
    """
    thrusts = np.asarray(msg.thrust, dtype=float)
    torques = np.asarray(msg.joint_torques, dtype=float)
    if thrusts.shape != (n_thrusters,):
        msg_text = f'thrust has {thrusts.size} values, expected {n_thrusters} (one per thruster)'
        raise CommandError(msg_text)
    if torques.shape != (len(joint_names),):
        msg_text = (
            f'joint_torques has {torques.size} values, expected {len(joint_names)} '
            f'({", ".join(joint_names)})'
        )
        raise CommandError(msg_text)
    names = list(msg.joint_names)
    if names and names != list(joint_names):
        if sorted(names) != sorted(joint_names):
            msg_text = f'joint_names {names} do not match the arm joints {list(joint_names)}'
            raise CommandError(msg_text)
        torques = torques[[names.index(name) for name in joint_names]]
    for field, values in (('thrust', thrusts), ('joint_torques', torques)):
        if not np.isfinite(values).all():
            msg_text = f'{field} holds a non-finite value: {values.tolist()}'
            raise CommandError(msg_text)
    return ns_from_time(msg.header.stamp), thrusts, torques
