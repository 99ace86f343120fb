"""The simulator's navigation sensor topics: imu, dvl, depth, position_fix (when enabled).

The one place where the readings of ``uvms_model.nav_sensors`` become messages. They go on
the wire as raw CDR through the fixed layouts of ``uvms_common.hot_messages``
(``uvms_sim.raw_conversions.RawNavigationMessages``), as the other topics of each control
period do; the typed builders below are the reference those payloads are tested against
(same types, frames and values, so any typed subscriber reads them unchanged). Messages, as
robot_localization consumes them:

- ``imu``: sensor_msgs/Imu in ``base_link_frd`` (the IMU at the vehicle origin): angular
  velocity (rad/s) and specific force (m/s^2, -9.81 along z at rest, as a NED/FRD IMU
  reads), orientation of ``base_link_frd`` in ``map_ned`` from the AHRS; covariances from
  the configured noise (the bias is not in them).
- ``dvl``: geometry_msgs/TwistWithCovarianceStamped in ``dvl_link`` (its mounting:
  ``navigation.dvl.position_m`` / ``orientation_rpy``), only readings with bottom lock, as
  ArduSub's DVL extension drops invalid ones. Chosen over marine_acoustic_msgs/Dvl because
  it has a wheel (common_interfaces) and robot_localization fuses it directly; the beams and
  figure of merit of a Dvl message are not simulated.
- ``depth``: geometry_msgs/PoseWithCovarianceStamped in ``map_ned`` with z the depth (m, down)
  and only z's variance finite: robot_localization's usual depth input.
- ``position_fix``: geometry_msgs/PoseWithCovarianceStamped in ``map_ned``, position only.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu
from uvms_model.kinematics import rot_ned_from_body
from uvms_model.nav_sensor_parameters import NavigationParameters
from uvms_model.nav_sensors import (
    DepthReading,
    DvlReading,
    ImuReading,
    NavigationSensors,
    NavigationTruth,
    PositionFixReading,
    Reading,
)

from uvms_sim.conversions import (
    BASE_LINK_FRD,
    DVL_LINK,
    MAP_NED,
    quaternion_from_rpy,
    time_from_ns,
)
from uvms_sim.device_timing import DeviceTiming
from uvms_sim.raw_conversions import UNUSED_VARIANCE, RawNavigationMessages

__all__ = ['UNUSED_VARIANCE', 'NavigationTopics', 'depth_message', 'dvl_message', 'dvl_mount',
           'imu_message', 'position_fix_message']


def _stamp(t_ns: int) -> Time:
    return time_from_ns(t_ns)


def imu_message(reading: ImuReading, gyro_var: float, accel_var: float) -> Imu:
    """sensor_msgs/Imu of one reading (base_link_frd; orientation in map_ned)."""
    msg = Imu()
    msg.header.stamp = _stamp(reading.t_ns)
    msg.header.frame_id = BASE_LINK_FRD
    x, y, z, w = quaternion_from_rpy(*(float(a) for a in reading.rpy))
    msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w = x, y, z, w
    msg.orientation_covariance = np.diag(reading.rpy_sigma ** 2).ravel().tolist()
    av, la = msg.angular_velocity, msg.linear_acceleration
    av.x, av.y, av.z = (float(v) for v in reading.w_body)
    la.x, la.y, la.z = (float(v) for v in reading.f_body)
    msg.angular_velocity_covariance = (np.eye(3) * gyro_var).ravel().tolist()
    msg.linear_acceleration_covariance = (np.eye(3) * accel_var).ravel().tolist()
    return msg


def dvl_message(reading: DvlReading) -> TwistWithCovarianceStamped:
    """geometry_msgs/TwistWithCovarianceStamped of a valid DVL reading (dvl_link)."""
    msg = TwistWithCovarianceStamped()
    msg.header.stamp = _stamp(reading.t_ns)
    msg.header.frame_id = DVL_LINK
    lin = msg.twist.twist.linear
    lin.x, lin.y, lin.z = (float(v) for v in reading.v_dvl)
    cov = np.diag([reading.sigma_m_s ** 2] * 3 + [UNUSED_VARIANCE] * 3)
    msg.twist.covariance = cov.ravel().tolist()
    return msg


def _pose_message(t_ns: int, p_ned: np.ndarray, variances: list[float]
                  ) -> PoseWithCovarianceStamped:
    msg = PoseWithCovarianceStamped()
    msg.header.stamp = _stamp(t_ns)
    msg.header.frame_id = MAP_NED
    pos = msg.pose.pose.position
    pos.x, pos.y, pos.z = (float(v) for v in p_ned)
    msg.pose.pose.orientation.w = 1.0
    msg.pose.covariance = np.diag(variances + [UNUSED_VARIANCE] * 3).ravel().tolist()
    return msg


def depth_message(reading: DepthReading, bias_max_m: float) -> PoseWithCovarianceStamped:
    """Depth as a pose with only z (m, down) measured; variance noise + uniform bias."""
    variance = reading.sigma_m ** 2 + bias_max_m ** 2 / 3.0
    return _pose_message(reading.t_ns, np.array([0.0, 0.0, reading.depth_m]),
                         [UNUSED_VARIANCE, UNUSED_VARIANCE, variance])


def position_fix_message(reading: PositionFixReading) -> PoseWithCovarianceStamped:
    """A position fix as a pose in map_ned with the position's variances."""
    return _pose_message(reading.t_ns, reading.p_ned, list(reading.sigma_m ** 2))


def dvl_mount(params: NavigationParameters) -> tuple[tuple[float, ...], tuple[float, ...]] | None:
    """The DVL's mounting (position m, roll-pitch-yaw rad in base_link_frd), None when off."""
    if not params.switch.enabled:
        return None
    return params.dvl.position_m, params.dvl.orientation_rpy


class NavigationTopics:
    """Samples the navigation sensors at each published state and publishes what is due.

    The truth's linear acceleration is the backward difference of the NED velocity between
    published states (one publish period late, 2 ms at 500 Hz). With device timing
    (``devices.imu|dvl|depth.latency_s``) a reading goes out with the first state at or
    after its time plus its latency, stamped with its own time (as the DVL's
    time_of_validity); the sensors' rates are navigation's.
    """

    def __init__(self, node: Node, params: NavigationParameters, seed: int,
                 devices: DeviceTiming | None = None) -> None:
        self.params = params
        self.sensors = NavigationSensors(params, seed)
        timing = devices if devices is not None else DeviceTiming({})
        self._rng = np.random.default_rng(seed + 3)
        self._latency = {kind: (round(timing[name].latency_s * 1e9),
                                round(timing[name].jitter_s * 1e9))
                         for kind, name in ((ImuReading, 'imu'), (DvlReading, 'dvl'),
                                            (DepthReading, 'depth'))}
        self._delayed: deque[tuple[int, Reading]] = deque()
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._imu = node.create_publisher(Imu, 'imu', qos)
        self._dvl = node.create_publisher(TwistWithCovarianceStamped, 'dvl', qos)
        self._depth = node.create_publisher(PoseWithCovarianceStamped, 'depth', qos)
        self._fix = (node.create_publisher(PoseWithCovarianceStamped, 'position_fix', qos)
                     if params.position_fix.enabled else None)
        imu = params.imu
        self._gyro_var = imu.gyro_noise_density ** 2 * imu.rate_hz
        self._accel_var = imu.accel_noise_density ** 2 * imu.rate_hz
        self._raw = RawNavigationMessages(self._gyro_var, self._accel_var)
        self._depth_bias_var = params.depth.bias_max_m ** 2 / 3.0
        self._last: tuple[int, np.ndarray] | None = None
        #: The last IMU and depth payloads, and the subscriptions matched when each went out.
        self._last_sent: dict[str, bytes] = {}
        self._sent_to = {'imu': 0, 'depth': 0}

    def publish(self, t_ns: int, q: np.ndarray, w: np.ndarray) -> None:
        """Measure the vehicle state (q, w of the plant) at ``t_ns`` and publish what is due."""
        rot = rot_ned_from_body(*q[3:6])
        v_ned = rot @ w[0:3]
        a_ned = np.zeros(3)
        if self._last is not None and t_ns > self._last[0]:
            a_ned = (v_ned - self._last[1]) / ((t_ns - self._last[0]) * 1e-9)
        self._last = (t_ns, v_ned)
        truth = NavigationTruth.of(q[0:3], q[3:6], w[0:3], w[3:6], a_ned)
        for reading in self.sensors.sample(t_ns, truth):
            latency_ns, jitter_ns = self._latency.get(type(reading), (0, 0))
            if latency_ns == 0:
                self._send(reading)
                continue
            if jitter_ns:
                latency_ns += round(float(self._rng.uniform(-1.0, 1.0)) * jitter_ns)
            self._delayed.append((reading.t_ns + latency_ns, reading))
        if self._delayed:
            due = sorted((item for item in self._delayed if item[0] <= t_ns),
                         key=lambda item: item[1].t_ns)
            self._delayed = deque(item for item in self._delayed if item[0] > t_ns)
            for _, reading in due:
                self._send(reading)

    def republish_held(self) -> None:
        """Send the last IMU and depth samples again if a subscriber joined since they went out.

        Real time, while the initial state is held: the estimator starts on its first IMU
        and depth samples and publishes on /clock only after them; a held state's sensors are
        sampled once (time stands still), so an estimator whose subscription was matched after
        those samples never started and the loop never closed (seen on a loaded machine,
        `uvms launch case1_estimated`, 60 s then an error). Sent again only when the number of
        matched subscriptions grew, so a started estimator sees a sample at most once more per
        late subscriber, at the same stamp (a prediction of zero length, the same depth).
        """
        for publisher, kind in ((self._imu, 'imu'), (self._depth, 'depth')):
            count = publisher.get_subscription_count()
            last = self._last_sent.get(kind)
            if last is not None and count > self._sent_to[kind]:
                self._sent_to[kind] = count
                publisher.publish(last)

    def _remember(self, kind: str, publisher: Any, payload: bytes) -> None:
        """Publish ``payload`` and keep it (and who got it) for ``republish_held``."""
        self._last_sent[kind] = payload
        self._sent_to[kind] = publisher.get_subscription_count()
        publisher.publish(payload)

    def _send(self, reading: Reading) -> None:
        raw = self._raw
        if isinstance(reading, ImuReading):
            self._remember('imu', self._imu, bytes(raw.imu(
                reading.t_ns, reading.rpy, reading.rpy_sigma, reading.w_body, reading.f_body)))
        elif isinstance(reading, DvlReading):
            if reading.valid:
                self._dvl.publish(raw.dvl(reading.t_ns, reading.v_dvl, reading.sigma_m_s))
        elif isinstance(reading, DepthReading):
            variance = reading.sigma_m ** 2 + self._depth_bias_var
            self._remember('depth', self._depth, bytes(raw.pose(
                reading.t_ns, (0.0, 0.0, reading.depth_m),
                (UNUSED_VARIANCE, UNUSED_VARIANCE, variance))))
        elif self._fix is not None:
            self._fix.publish(raw.pose(reading.t_ns, reading.p_ned,
                                       (reading.sigma_m ** 2).tolist()))
