"""The simulator's hot topics as raw CDR: numpy in, payloads out, and the actuator command in.

The layouts (`uvms_common.hot_messages`) are fixed for the robot at start-up, so a state is
a few `struct.pack_into` calls into preallocated buffers; the payloads carry the same types,
frames and values as the typed messages of `uvms_sim.conversions` (which a typed subscriber
reads unchanged), and that module stays the reference for them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from uvms_common.cdr_codecs import Decoded, PayloadWriter, RawDecoder
from uvms_common.hot_messages import (
    actuator_command_codec,
    clock_codec,
    contact_codec,
    dvl_codec,
    imu_codec,
    joint_state_codec,
    odometry_codec,
    pose_codec,
    pose_covariance_codec,
    wrench_codec,
)

from uvms_sim import conversions
from uvms_sim.errors import CommandError
from uvms_sim.plant import Observation

FloatArray = conversions.FloatArray


class RawStateMessages:
    """The state payloads of one observation: the raw twin of `conversions.StateMessages`.

    Attributes (bytes of the last ``update``): ``clock``, ``joint_state``, ``odometry``,
    ``wrench``, ``ee_pose``, ``contact``.
    """

    def __init__(self, joint_names: Sequence[str]) -> None:
        self._clock = PayloadWriter(clock_codec())
        self._joint_state = PayloadWriter(joint_state_codec(joint_names), ['position'],
                                          ['velocity'], ['effort'])
        self._odometry = PayloadWriter(odometry_codec(), ['pose.pose'], ['twist.twist'])
        self._wrench = PayloadWriter(wrench_codec(), ['wrench'])
        self._ee_pose = PayloadWriter(pose_codec(), ['pose'])
        self._contact = PayloadWriter(contact_codec(), ['in_contact', 'force', 'penetration',
                                                        'wall_position', 'wall_velocity'])
        self.clock = self.joint_state = self.odometry = self.wrench = b''
        self.ee_pose = self.contact = b''

    def update(self, seen: Observation, ground_truth: bool = True) -> None:
        """Fill the payloads from one observation, stamped seen.t_ns (frames as published).

        ``ground_truth`` False leaves ee_pose and contact as they were (not due).
        """
        t_ns = seen.t_ns
        q, w = seen.q.tolist(), seen.w.tolist()
        self.clock = self._clock.fill(t_ns)
        self.joint_state = self._joint_state.fill(t_ns, q[6:], w[6:],
                                                  seen.joint_torques.tolist())
        quaternion = conversions.quaternion_from_rpy(q[3], q[4], q[5])
        self.odometry = self._odometry.fill(t_ns, (*q[:3], *quaternion), w[:6])
        self.wrench = self._wrench.fill(
            t_ns, (*seen.sensor_force.tolist(), *seen.sensor_torque.tolist()))
        if not ground_truth:
            return
        p_ee, rot_ee = seen.poses['ee_link']
        self.ee_pose = self._ee_pose.fill(
            t_ns, (*p_ee.tolist(), *conversions.quaternion_from_rotation(rot_ee)))
        truth = seen.contact
        self.contact = self._contact.fill(t_ns, (
            bool(truth.in_contact), *np.asarray(truth.force_ned, dtype=float).tolist(),
            float(truth.penetration_m), float(truth.wall_position_m),
            float(truth.wall_velocity_m_s)))


#: Variance of a pose or twist component a message does not measure (robot_localization
#: ignores it); `uvms_sim.navigation_topics` builds the typed twins with the same value.
UNUSED_VARIANCE = 1.0e9
_IMU_FIELDS = ('orientation', 'orientation_covariance', 'angular_velocity',
               'angular_velocity_covariance', 'linear_acceleration',
               'linear_acceleration_covariance')


def _diagonal(variances: Sequence[float]) -> list[float]:
    """A row-major covariance matrix with the given diagonal, as a flat list."""
    return np.diag(np.asarray(variances, dtype=float)).ravel().tolist()


class RawNavigationMessages:
    """Payloads of the navigation sensor topics: the raw twins of `navigation_topics`' messages.

    Same frames and values as ``imu_message``, ``dvl_message``, ``depth_message`` and
    ``position_fix_message`` of `uvms_sim.navigation_topics` (the reference, which the tests
    compare these with).

    Args:
        gyro_var: Angular-rate variance per axis ((rad/s)^2).
        accel_var: Specific-force variance per axis ((m/s^2)^2).
    """

    def __init__(self, gyro_var: float, accel_var: float) -> None:
        self._imu = PayloadWriter(imu_codec(), _IMU_FIELDS)
        self._dvl = PayloadWriter(dvl_codec(), ['twist'])
        self._pose = PayloadWriter(pose_covariance_codec(), ['pose'])
        self._gyro_cov = _diagonal([gyro_var] * 3)
        self._accel_cov = _diagonal([accel_var] * 3)

    def imu(self, t_ns: int, rpy: FloatArray, rpy_sigma: FloatArray, w_body: FloatArray,
            f_body: FloatArray) -> bytes:
        """sensor_msgs/Imu: AHRS rpy (rad) and its sigma, rate (rad/s), specific force."""
        quaternion = conversions.quaternion_from_rpy(*(float(a) for a in rpy))
        return self._imu.fill(t_ns, (
            *quaternion, *_diagonal(np.asarray(rpy_sigma, dtype=float) ** 2),
            *np.asarray(w_body, dtype=float).tolist(), *self._gyro_cov,
            *np.asarray(f_body, dtype=float).tolist(), *self._accel_cov))

    def dvl(self, t_ns: int, v_dvl: FloatArray, sigma_m_s: float) -> bytes:
        """geometry_msgs/TwistWithCovarianceStamped: velocity in dvl_link (m/s), its sigma."""
        return self._dvl.fill(t_ns, (
            *np.asarray(v_dvl, dtype=float).tolist(), 0.0, 0.0, 0.0,
            *_diagonal([sigma_m_s ** 2] * 3 + [UNUSED_VARIANCE] * 3)))

    def pose(self, t_ns: int, p_ned: FloatArray, variances: Sequence[float]) -> bytes:
        """geometry_msgs/PoseWithCovarianceStamped in map_ned: position, identity attitude.

        ``variances`` are those of x, y, z (m^2); the attitude's are `UNUSED_VARIANCE`.
        """
        return self._pose.fill(t_ns, (
            *np.asarray(p_ned, dtype=float).tolist(), 0.0, 0.0, 0.0, 1.0,
            *_diagonal([*variances, *[UNUSED_VARIANCE] * 3])))


class ActuatorCommandReader:
    """Actuator command payloads to (stamp ns, thrusts N, joint torques N*m, model order).

    Our allocator's layout is read in place; any other (another frame id or joint order)
    goes through rclpy and `conversions.actuator_command_arrays`, as a typed message did.
    ``decoder.malformed`` counts payloads that are no ActuatorCommand at all.
    """

    def __init__(self, n_thrusters: int, joint_names: Sequence[str]) -> None:
        codec = actuator_command_codec(n_thrusters, joint_names)
        self.decoder = RawDecoder(codec)
        self._n_thrusters = n_thrusters
        self._joint_names = tuple(joint_names)
        self._thrust = codec.struct(['thrust'])
        self._torques = codec.struct(['joint_torques'])

    def read(self, data: bytes) -> tuple[int, FloatArray, FloatArray]:
        """Stamp, thrusts and torques of one payload.

        Raises:
            MalformedPayloadError: Not an ActuatorCommand (counted in ``decoder.malformed``).
            CommandError: An ActuatorCommand of wrong sizes or joints, or a NaN/Inf value.
        """
        decoded: Decoded = self.decoder.decode(data)
        if decoded.view is None:
            return conversions.actuator_command_arrays(
                decoded.message, self._n_thrusters, self._joint_names)
        (t_offset, t_struct), (j_offset, j_struct) = self._thrust, self._torques
        thrusts = t_struct.unpack_from(data, t_offset)
        torques = j_struct.unpack_from(data, j_offset)
        if not math.isfinite(sum(thrusts) + sum(torques)):
            for field, values in (('thrust', thrusts), ('joint_torques', torques)):
                if not all(math.isfinite(v) for v in values):
                    raise CommandError(f'{field} holds a non-finite value: {list(values)}')
        return decoded.stamp_ns, np.array(thrusts), np.array(torques)
