"""The estimator's topics as raw CDR: sensor payloads in, odometry/filtered payloads out.

A reader takes a payload of a raw subscription: the simulator's layout
(``uvms_common.hot_messages``) is read in place with `struct`; any other layout (another
publisher's frame id) is deserialized by rclpy and converted by the typed readers of
`uvms_navigation.conversions`, which stay the reference; a payload that is no message of the
type raises `MalformedPayloadError` (counted in ``decoder.malformed``). The writer fills a
preallocated ``odometry/filtered`` payload with the values `conversions.odometry_message`
puts in its message.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from uvms_common.cdr_codecs import PayloadWriter
from uvms_common.cdr_codecs import RawReader as Reader
from uvms_common.hot_messages import (
    clock_codec,
    dvl_codec,
    imu_codec,
    odometry_codec,
    pose_covariance_codec,
)
from uvms_model.coordinates import quaternion_xyzw
from uvms_model.kinematics import euler_from_rotation

from uvms_navigation import conversions


def _without_stamp(typed: Callable[[Any], tuple[Any, ...]]) -> Callable[[Any], Any]:
    """A typed reader of `conversions` (stamp first) giving the value without its stamp."""
    return lambda msg: typed(msg)[1:]


def imu_reader() -> Reader:
    """``imu`` to (rate rad/s, specific force m/s^2, AHRS roll/pitch/yaw rad), as imu_arrays."""
    codec = imu_codec()
    (q_at, q_struct), (w_at, w_struct), (f_at, f_struct) = (
        codec.struct(['orientation']), codec.struct(['angular_velocity']),
        codec.struct(['linear_acceleration']))

    def fast(data: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return (np.array(w_struct.unpack_from(data, w_at)),
                np.array(f_struct.unpack_from(data, f_at)),
                conversions.rpy_from_xyzw(*q_struct.unpack_from(data, q_at)))

    return Reader(codec, fast, _without_stamp(conversions.imu_arrays))


def dvl_reader() -> Reader:
    """``dvl`` to (velocity in the DVL frame m/s,), as dvl_arrays."""
    codec = dvl_codec()
    at, linear = codec.struct(['twist.twist.linear'])
    return Reader(codec, lambda data: (np.array(linear.unpack_from(data, at)),),
                  _without_stamp(conversions.dvl_arrays))


def depth_reader() -> Reader:
    """``depth`` to (depth m, down,), as depth_value."""
    codec = pose_covariance_codec()
    at, z = codec.struct(['pose.pose.position.z'])
    return Reader(codec, lambda data: (float(z.unpack_from(data, at)[0]),),
                  _without_stamp(conversions.depth_value))


def position_fix_reader() -> Reader:
    """``position_fix`` to (position map_ned m, std per axis m), as position_arrays."""
    codec = pose_covariance_codec()
    (p_at, p_struct), (c_at, c_struct) = (codec.struct(['pose.pose.position']),
                                          codec.struct(['pose.covariance']))

    def fast(data: bytes) -> tuple[np.ndarray, np.ndarray]:
        cov = np.array(c_struct.unpack_from(data, c_at)).reshape(6, 6)
        return np.array(p_struct.unpack_from(data, p_at)), np.sqrt(np.diag(cov)[:3])

    return Reader(codec, fast, _without_stamp(conversions.position_arrays))


def clock_reader() -> Reader:
    """``/clock`` to its time (ns) alone; rosgraph_msgs/Clock has no other field."""
    return Reader(clock_codec(), lambda data: (), lambda msg: ())


class OdometryWriter:
    """``odometry/filtered`` payloads: nav_msgs/Odometry as `conversions.odometry_message`."""

    def __init__(self) -> None:
        self._payload = PayloadWriter(odometry_codec(), ['pose', 'twist'])

    def payload(self, t_ns: int, p_ned: np.ndarray, rot: np.ndarray, v_body: np.ndarray,
                w_body: np.ndarray, pose_cov: np.ndarray, twist_cov: np.ndarray) -> bytes:
        """The estimate stamped t_ns (pose in map_ned, twist in base_link_frd, covariances)."""
        quaternion = quaternion_xyzw(*euler_from_rotation(rot))
        return self._payload.fill(t_ns, (
            *np.asarray(p_ned, dtype=float).tolist(), *quaternion,
            *np.asarray(pose_cov, dtype=float).ravel().tolist(),
            *np.asarray(v_body, dtype=float).tolist(), *np.asarray(w_body, dtype=float).tolist(),
            *np.asarray(twist_cov, dtype=float).ravel().tolist()))
