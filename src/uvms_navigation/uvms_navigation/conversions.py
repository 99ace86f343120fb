"""The estimator's messages as numpy and back: the one place messages meet the filter.

Inputs as the simulator publishes them (``uvms_sim.navigation_topics``): sensor_msgs/Imu in
``base_link_frd`` with the AHRS orientation in ``map_ned``; geometry_msgs/
TwistWithCovarianceStamped of the DVL in its own frame; depth and position fixes as
geometry_msgs/PoseWithCovarianceStamped in ``map_ned``. Output: nav_msgs/Odometry as
``/uvms/odometry`` (pose in ``map_ned``, twist in ``base_link_frd``) with covariances.
"""

from __future__ import annotations

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu
from uvms_model.coordinates import quaternion_xyzw
from uvms_model.kinematics import euler_from_rotation

MAP_NED, BASE_LINK_FRD = 'map_ned', 'base_link_frd'


def stamp_ns(stamp: Time) -> int:
    """A header stamp in ns."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def time_from_ns(t_ns: int) -> Time:
    """A builtin_interfaces/Time of ``t_ns``."""
    return Time(sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000)


def rpy_from_xyzw(x: float, y: float, z: float, w: float) -> np.ndarray:
    """Roll, pitch, yaw (rad, ZYX) of a unit quaternion (x, y, z, w)."""
    rot = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    return np.array(euler_from_rotation(rot))


def imu_arrays(msg: Imu) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """(t_ns, rate rad/s, specific force m/s^2, AHRS roll/pitch/yaw rad) of an Imu."""
    o, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
    return (stamp_ns(msg.header.stamp), np.array([w.x, w.y, w.z]), np.array([a.x, a.y, a.z]),
            rpy_from_xyzw(o.x, o.y, o.z, o.w))


def dvl_arrays(msg: TwistWithCovarianceStamped) -> tuple[int, np.ndarray]:
    """(t_ns, velocity in the DVL frame m/s) of a DVL reading."""
    v = msg.twist.twist.linear
    return stamp_ns(msg.header.stamp), np.array([v.x, v.y, v.z])


def depth_value(msg: PoseWithCovarianceStamped) -> tuple[int, float]:
    """(t_ns, depth m, down) of a depth reading."""
    return stamp_ns(msg.header.stamp), float(msg.pose.pose.position.z)


def position_arrays(msg: PoseWithCovarianceStamped) -> tuple[int, np.ndarray, np.ndarray]:
    """(t_ns, position map_ned m, std per axis m) of a position fix."""
    p = msg.pose.pose.position
    cov = np.array(msg.pose.covariance).reshape(6, 6)
    return (stamp_ns(msg.header.stamp), np.array([p.x, p.y, p.z]),
            np.sqrt(np.diag(cov)[:3]))


def odometry_message(t_ns: int, p_ned: np.ndarray, rot: np.ndarray, v_body: np.ndarray,
                     w_body: np.ndarray, pose_cov: np.ndarray, twist_cov: np.ndarray
                     ) -> Odometry:
    """nav_msgs/Odometry as /uvms/odometry, with the filter's covariances.

    Pose covariance over (x, y, z, roll, pitch, yaw) in map_ned; twist covariance in
    base_link_frd.
    """
    msg = Odometry()
    msg.header.stamp = time_from_ns(t_ns)
    msg.header.frame_id = MAP_NED
    msg.child_frame_id = BASE_LINK_FRD
    pose = msg.pose.pose
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in p_ned)
    rpy = euler_from_rotation(rot)
    (pose.orientation.x, pose.orientation.y, pose.orientation.z,
     pose.orientation.w) = quaternion_xyzw(*rpy)
    lin, ang = msg.twist.twist.linear, msg.twist.twist.angular
    lin.x, lin.y, lin.z = (float(v) for v in v_body)
    ang.x, ang.y, ang.z = (float(v) for v in w_body)
    msg.pose.covariance = [float(v) for v in pose_cov.ravel()]
    msg.twist.covariance = [float(v) for v in twist_cov.ravel()]
    return msg
