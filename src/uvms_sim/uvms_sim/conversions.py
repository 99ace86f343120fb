"""Messages to numpy and back for the simulator node; the only place NED/FRD meet ENU/FLU.

Every other module of uvms_sim works in map_ned and base_link_frd with numpy arrays. Here
they become ROS messages, and the static /tf twins ``map`` (ENU) and ``base_link`` (FLU)
are tied to ``map_ned`` and ``base_link_frd`` (REP-103, REP-105).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

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
from uvms_model.coordinates import quaternion_xyzw
from uvms_model.kinematics import rot_ned_from_body

from uvms_msgs.msg import ActuatorCommand, ContactState
from uvms_sim.errors import CommandError
from uvms_sim.plant import Observation

FloatArray = NDArray[np.float64]

MAP_NED = 'map_ned'
BASE_LINK_FRD = 'base_link_frd'
FT_SENSOR_LINK = 'ft_sensor_link'
MAP_ENU = 'map'
BASE_LINK_FLU = 'base_link'

EE_LINK = 'ee_link'
#: Frame of the DVL's velocity (``dvl`` topic), fixed to base_link_frd by its mounting.
DVL_LINK = 'dvl_link'

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
    return quaternion_xyzw(roll, pitch, yaw)


def quaternion_from_rotation(rot: FloatArray) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w), w >= 0, of a rotation matrix (Shepperd's method)."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = np.asarray(rot, dtype=float).tolist()
    trace = m00 + m11 + m22
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)
        x, y, z, w = m21 - m12, m02 - m20, m10 - m01, 0.25 * s * s
    elif m00 > m11 and m00 > m22:
        s = 2.0 * math.sqrt(1.0 + m00 - m11 - m22)
        x, y, z, w = 0.25 * s * s, m01 + m10, m02 + m20, m21 - m12
    elif m11 > m22:
        s = 2.0 * math.sqrt(1.0 + m11 - m00 - m22)
        x, y, z, w = m01 + m10, 0.25 * s * s, m12 + m21, m02 - m20
    else:
        s = 2.0 * math.sqrt(1.0 + m22 - m00 - m11)
        x, y, z, w = m02 + m20, m12 + m21, 0.25 * s * s, m10 - m01
    x, y, z, w = x / s, y / s, z / s, w / s
    sign = -1.0 if w < 0.0 else 1.0
    return sign * x, sign * y, sign * z, sign * w


def _quaternion(xyzw: tuple[float, float, float, float]) -> Quaternion:
    return Quaternion(x=xyzw[0], y=xyzw[1], z=xyzw[2], w=xyzw[3])


def _vector3(v: FloatArray | Sequence[float]) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _set_xyz(target: Any, xyz: Sequence[float]) -> None:
    """Set x, y, z of a Vector3 or Point from plain floats."""
    target.x, target.y, target.z = xyz


def _set_xyzw(target: Quaternion, xyzw: tuple[float, float, float, float]) -> None:
    target.x, target.y, target.z, target.w = xyzw


def _fill_joint_state(
    msg: JointState, stamp: Time, positions: Any, velocities: Any, efforts: Any
) -> JointState:
    msg.header.stamp = stamp
    msg.position = np.asarray(positions, dtype=float)
    msg.velocity = np.asarray(velocities, dtype=float)
    msg.effort = np.asarray(efforts, dtype=float)
    return msg


def _fill_odometry(msg: Odometry, stamp: Time, eta: list[float], nu: list[float]) -> Odometry:
    msg.header.stamp = stamp
    pose = msg.pose.pose
    _set_xyz(pose.position, eta[:3])
    _set_xyzw(pose.orientation, quaternion_from_rpy(eta[3], eta[4], eta[5]))
    twist = msg.twist.twist
    _set_xyz(twist.linear, nu[:3])
    _set_xyz(twist.angular, nu[3:6])
    return msg


def _fill_wrench(
    msg: WrenchStamped, stamp: Time, force: list[float], torque: list[float]
) -> WrenchStamped:
    msg.header.stamp = stamp
    _set_xyz(msg.wrench.force, force)
    _set_xyz(msg.wrench.torque, torque)
    return msg


def _fill_pose(
    msg: PoseStamped, stamp: Time, p_ned: list[float], rot_ned_from_frame: FloatArray
) -> PoseStamped:
    msg.header.stamp = stamp
    _set_xyz(msg.pose.position, p_ned)
    _set_xyzw(msg.pose.orientation, quaternion_from_rotation(rot_ned_from_frame))
    return msg


def _fill_contact(msg: ContactState, stamp: Time, truth: ContactTruth) -> ContactState:
    msg.header.stamp = stamp
    msg.in_contact = bool(truth.in_contact)
    _set_xyz(msg.force, np.asarray(truth.force_ned, dtype=float).tolist())
    msg.penetration = float(truth.penetration_m)
    msg.wall_position = float(truth.wall_position_m)
    msg.wall_velocity = float(truth.wall_velocity_m_s)
    return msg


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
    msg = JointState(header=Header(frame_id=''), name=list(names))
    return _fill_joint_state(msg, time_from_ns(t_ns), positions, velocities, efforts)


def odometry_message(t_ns: int, eta: FloatArray, nu: FloatArray) -> Odometry:
    """nav_msgs/Odometry of the vehicle: pose in map_ned, twist in base_link_frd.

    Args:
        t_ns: Simulated time (ns).
        eta: Position in map_ned (m) and roll, pitch, yaw (rad), shape (6,).
        nu: Body velocity [u, v, w] (m/s) and rates [p, q, r] (rad/s) in base_link_frd.
    """
    msg = Odometry(header=Header(frame_id=MAP_NED), child_frame_id=BASE_LINK_FRD)
    return _fill_odometry(msg, time_from_ns(t_ns), _floats(eta), _floats(nu))


def wrench_message(t_ns: int, force: FloatArray, torque: FloatArray) -> WrenchStamped:
    """geometry_msgs/WrenchStamped of the wrist sensor in ft_sensor_link (N, N*m)."""
    msg = WrenchStamped(header=Header(frame_id=FT_SENSOR_LINK))
    return _fill_wrench(msg, time_from_ns(t_ns), _floats(force), _floats(torque))


def pose_message(t_ns: int, p_ned: FloatArray, rot_ned_from_frame: FloatArray) -> PoseStamped:
    """geometry_msgs/PoseStamped of a frame in map_ned."""
    msg = PoseStamped(header=Header(frame_id=MAP_NED))
    return _fill_pose(msg, time_from_ns(t_ns), _floats(p_ned), rot_ned_from_frame)


def contact_message(t_ns: int, truth: ContactTruth) -> ContactState:
    """uvms_msgs/ContactState from the plant's contact ground truth (map_ned)."""
    return _fill_contact(ContactState(header=Header(frame_id=MAP_NED)), time_from_ns(t_ns), truth)


def _floats(values: FloatArray | Sequence[float]) -> list[float]:
    """Plain Python floats of a vector."""
    return np.asarray(values, dtype=float).tolist()  # type: ignore[no-any-return]


class StateMessages:
    """The simulator's state messages, built once and refilled for every published state.

    rclpy serializes a message when it is published (the bundled runtime copies it), so
    refilling the same objects is safe; it spares building some 30 sub-messages per state.
    The fields hold the messages of the last ``update``, all stamped with its time.

    Example:
        >>> messages = StateMessages(('shoulder', 'elbow', 'wrist'))  # doctest: +SKIP
        >>> messages.update(plant.observe())  # doctest: +SKIP
        >>> odometry_publisher.publish(messages.odometry)  # doctest: +SKIP
    """

    def __init__(self, joint_names: Sequence[str]) -> None:
        self.clock = Clock()
        self.joint_state = JointState(header=Header(frame_id=''), name=list(joint_names))
        self.odometry = Odometry(header=Header(frame_id=MAP_NED), child_frame_id=BASE_LINK_FRD)
        self.wrench = WrenchStamped(header=Header(frame_id=FT_SENSOR_LINK))
        self.ee_pose = PoseStamped(header=Header(frame_id=MAP_NED))
        self.contact = ContactState(header=Header(frame_id=MAP_NED))

    def update(self, seen: Observation, ground_truth: bool = True) -> None:
        """Refill the messages from one observation of the plant, stamped seen.t_ns.

        ``ground_truth`` False leaves ee_pose and contact as they were (not due).
        """
        stamp = time_from_ns(seen.t_ns)
        q, w = seen.q.tolist(), seen.w.tolist()
        self.clock.clock = stamp
        _fill_joint_state(self.joint_state, stamp, seen.q[6:], seen.w[6:], seen.joint_torques)
        _fill_odometry(self.odometry, stamp, q[:6], w[:6])
        _fill_wrench(self.wrench, stamp, seen.sensor_force.tolist(), seen.sensor_torque.tolist())
        if not ground_truth:
            return
        p_ee, rot_ee = seen.poses['ee_link']
        _fill_pose(self.ee_pose, stamp, p_ee.tolist(), rot_ee)
        _fill_contact(self.contact, stamp, seen.contact)


def _transform(
    t_ns: int, parent: str, child: str, p: FloatArray, rot: FloatArray
) -> TransformStamped:
    """TransformStamped: pose of ``child`` in ``parent`` (p in parent, rot_parent_from_child)."""
    msg = TransformStamped(header=Header(stamp=time_from_ns(t_ns), frame_id=parent),
                           child_frame_id=child)
    msg.transform.translation = _vector3(p)
    msg.transform.rotation = _quaternion(quaternion_from_rotation(rot))
    return msg


def frame_parents(frame_names: Sequence[str]) -> dict[str, str]:
    """Parent of each moving robot frame in the /tf tree, from the model's frame list.

    ``frame_names`` is root, the arm links base to tip, ee_link, ft_sensor_link
    (``UvmsModel.frame_names``): each arm link and ee_link hangs on the frame before it
    (fixed links between them are folded into these transforms); ft_sensor_link is on
    /tf_static.

    >>> frame_parents(('base_link_frd', 'upper', 'fore', 'wrist', 'ee_link', 'ft_sensor_link'))
    {'upper': 'base_link_frd', 'fore': 'upper', 'wrist': 'fore', 'ee_link': 'wrist'}
    """
    chain = [name for name in frame_names if name != FT_SENSOR_LINK]
    return dict(zip(chain[1:], chain[:-1], strict=True))


def tf_message(
    t_ns: int, poses: Mapping[str, tuple[FloatArray, FloatArray]],
    parents: Mapping[str, str],
) -> TFMessage:
    """/tf of the robot: map_ned -> base_link_frd -> arm links -> ee_link.

    Args:
        t_ns: Simulated time (ns).
        poses: {frame: (p_ned, rot_ned_from_frame)} of the plant.
        parents: Parent of each moving frame (``frame_parents``).
    """
    p_base, rot_base = poses[BASE_LINK_FRD]
    transforms = [_transform(t_ns, MAP_NED, BASE_LINK_FRD, p_base, rot_base)]
    for child, parent in parents.items():
        p_parent, rot_parent = poses[parent]
        p_child, rot_child = poses[child]
        transforms.append(_transform(
            t_ns, parent, child,
            rot_parent.T @ (p_child - p_parent), rot_parent.T @ rot_child,
        ))
    return TFMessage(transforms=transforms)


def static_tf_message(
    t_ns: int, poses: Mapping[str, tuple[FloatArray, FloatArray]],
    dvl_mount: tuple[Sequence[float], Sequence[float]] | None = None,
) -> TFMessage:
    """/tf_static: the ENU/FLU twins and the sensor mounts.

    ``map`` (ENU) is the parent of ``map_ned``; ``base_link`` (FLU) hangs under
    ``base_link_frd`` (a frame has one parent in tf2, and base_link_frd's is map_ned), so
    tools that expect ``map`` and ``base_link`` find them; ``ft_sensor_link`` is fixed to
    ``ee_link``; ``dvl_link`` (the frame of ``dvl`` messages) to ``base_link_frd``.

    Args:
        t_ns: Stamp (ns).
        poses: Frame poses of the model (``UvmsModel.frame_poses``).
        dvl_mount: The DVL's ``navigation.dvl.position_m`` (m, in base_link_frd) and
            ``orientation_rpy`` (rad, ZYX: rot_body_from_dvl as ``uvms_model.nav_sensors``
            uses it); None: no DVL, no ``dvl_link``.
    """
    p_ee, rot_ee = poses[EE_LINK]
    p_s, rot_s = poses[FT_SENSOR_LINK]
    transforms = [
        _transform(t_ns, MAP_ENU, MAP_NED, np.zeros(3), ROT_ENU_FROM_NED),
        _transform(t_ns, BASE_LINK_FRD, BASE_LINK_FLU, np.zeros(3), ROT_FRD_FROM_FLU),
        _transform(t_ns, EE_LINK, FT_SENSOR_LINK, rot_ee.T @ (p_s - p_ee), rot_ee.T @ rot_s),
    ]
    if dvl_mount is not None:
        position_m, rpy = dvl_mount
        transforms.append(_transform(t_ns, BASE_LINK_FRD, DVL_LINK,
                                     np.asarray(position_m, dtype=np.float64),
                                     rot_ned_from_body(*(float(a) for a in rpy))))
    return TFMessage(transforms=transforms)


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
    if math.isfinite(sum(thrusts.tolist()) + sum(torques.tolist())):
        return ns_from_time(msg.header.stamp), thrusts, torques  # all finite: the usual case
    for field, values in (('thrust', thrusts), ('joint_torques', torques)):
        if not np.isfinite(values).all():
            msg_text = f'{field} holds a non-finite value: {values.tolist()}'
            raise CommandError(msg_text)
    return ns_from_time(msg.header.stamp), thrusts, torques


def current_message(t_ns: int, v_ned: FloatArray) -> Any:
    """geometry_msgs/TwistStamped of the ocean current: the water's velocity in map_ned (m/s).

    The angular part is zero (a uniform, irrotational current).
    """
    from geometry_msgs.msg import TwistStamped

    msg = TwistStamped(header=Header(frame_id=MAP_NED, stamp=time_from_ns(t_ns)))
    msg.twist.linear = _vector3(v_ned)
    return msg
