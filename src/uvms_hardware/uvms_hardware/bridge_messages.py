"""The bridges' sensor messages, built as the simulator builds them (uvms_sim.navigation_topics).

The one place where device numbers meet ROS messages. Frames, conventions and covariances are
the simulator's, so the estimator (uvms_navigation) runs unchanged on bridge data:

- ``imu``: sensor_msgs/Imu in ``base_link_frd``; orientation of base_link_frd in ``map_ned``
  (ArduSub's ATTITUDE_QUATERNION is already body FRD in NED: q1..q4 = w, x, y, z); angular
  velocity (rad/s) and specific force (m/s^2, -9.81 on z at rest, as ArduPilot's accelerometer
  reads); covariances from the robot's navigation figures (noise density^2 * rate).
- ``depth``: geometry_msgs/PoseWithCovarianceStamped in ``map_ned``, z = depth (m, down), only
  z's variance finite (sigma^2 + bias^2 / 3), orientation identity.
- ``dvl``: geometry_msgs/TwistWithCovarianceStamped in ``dvl_link``, linear velocity only.
- ``battery``: sensor_msgs/BatteryState (V, A, fraction).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped
from sensor_msgs.msg import BatteryState, Imu

#: Frames and the unused-variance value of uvms_sim (a test keeps them equal).
MAP_NED = 'map_ned'
BASE_LINK_FRD = 'base_link_frd'
DVL_LINK = 'dvl_link'
UNUSED_VARIANCE = 1.0e9
#: Standard gravity (m/s^2): ArduPilot's mG -> m/s^2.
G_M_S2 = 9.80665


def stamp(t_ns: int) -> Time:
    """builtin_interfaces/Time of nanoseconds."""
    return Time(sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000)


def _diag(values: Sequence[float]) -> list[float]:
    n = len(values)
    return [float(values[i]) if i == j else 0.0 for i in range(n) for j in range(n)]


@dataclass(frozen=True)
class ImuNoise:
    """Covariances of the imu message (the simulator's: navigation.imu of the robot)."""

    gyro_var: float
    accel_var: float
    rpy_var: tuple[float, float, float]

    @classmethod
    def from_navigation(cls, values: dict[str, Any]) -> ImuNoise:
        """From the robot's ``navigation.imu.*`` values (flat dotted names)."""
        rate_hz = float(values['navigation.imu.rate_hz'])
        rp = float(values['navigation.imu.roll_pitch_sigma_rad']) ** 2
        return cls(float(values['navigation.imu.gyro_noise_density']) ** 2 * rate_hz,
                   float(values['navigation.imu.accel_noise_density']) ** 2 * rate_hz,
                   (rp, rp, float(values['navigation.imu.yaw_sigma_rad']) ** 2))


def imu_message(t_ns: int, quaternion_wxyz: Sequence[float], w_body_rad_s: Sequence[float],
                f_body_m_s2: Sequence[float], noise: ImuNoise) -> Imu:
    """sensor_msgs/Imu (base_link_frd; orientation of base_link_frd in map_ned)."""
    msg = Imu()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = BASE_LINK_FRD
    o = msg.orientation
    o.w, o.x, o.y, o.z = (float(q) for q in quaternion_wxyz)
    msg.orientation_covariance = _diag(noise.rpy_var)
    av, la = msg.angular_velocity, msg.linear_acceleration
    av.x, av.y, av.z = (float(v) for v in w_body_rad_s)
    la.x, la.y, la.z = (float(v) for v in f_body_m_s2)
    msg.angular_velocity_covariance = _diag([noise.gyro_var] * 3)
    msg.linear_acceleration_covariance = _diag([noise.accel_var] * 3)
    return msg


def imu_from_raw_imu(raw: Any) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(w rad/s, f m/s^2) of a RAW_IMU as ArduPilot fills it (mrad/s, mG; body FRD)."""
    w = tuple(getattr(raw, f'{a}gyro') * 1e-3 for a in 'xyz')
    f = tuple(getattr(raw, f'{a}acc') * 1e-3 * G_M_S2 for a in 'xyz')
    return w, f


def depth_from_pressure(press_abs_hpa: float, surface_pa: float, density_kg_m3: float,
                        gravity_m_s2: float = G_M_S2) -> float:
    """Depth (m, down) = (p - p_surface) / (rho g), p from hPa (as uvms-simlab computes it)."""
    return (press_abs_hpa * 100.0 - surface_pa) / (density_kg_m3 * gravity_m_s2)


def depth_message(t_ns: int, depth_m: float, variance_m2: float) -> PoseWithCovarianceStamped:
    """Depth as a pose in map_ned with only z (m, down) measured."""
    msg = PoseWithCovarianceStamped()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = MAP_NED
    msg.pose.pose.position.z = float(depth_m)
    msg.pose.pose.orientation.w = 1.0
    msg.pose.covariance = _diag([UNUSED_VARIANCE, UNUSED_VARIANCE, variance_m2] +
                                [UNUSED_VARIANCE] * 3)
    return msg


def dvl_message(t_ns: int, v_dvl_m_s: Sequence[float], covariance_m2_s2: Sequence[float]
                ) -> TwistWithCovarianceStamped:
    """A bottom-locked velocity (m/s) in dvl_link; its 3x3 covariance row-major."""
    msg = TwistWithCovarianceStamped()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = DVL_LINK
    lin = msg.twist.twist.linear
    lin.x, lin.y, lin.z = (float(v) for v in v_dvl_m_s)
    cov = _diag([0.0] * 3 + [UNUSED_VARIANCE] * 3)
    for i in range(3):
        for j in range(3):
            cov[6 * i + j] = float(covariance_m2_s2[3 * i + j])
    msg.twist.covariance = cov
    return msg


def battery_message(t_ns: int, voltage_v: float, current_a: float, remaining: float
                    ) -> BatteryState:
    """sensor_msgs/BatteryState from SYS_STATUS figures (NaN where not reported)."""
    msg = BatteryState()
    msg.header.stamp = stamp(t_ns)
    msg.voltage = float(voltage_v)
    msg.current = float(current_a)
    msg.percentage = float(remaining)
    msg.present = True
    msg.power_supply_status = BatteryState.POWER_SUPPLY_STATUS_DISCHARGING
    return msg


def battery_from_sys_status(sys_status: Any) -> tuple[float, float, float]:
    """(V, A, fraction 0-1) of SYS_STATUS (mV, cA, %; -1 / 65535 = not reported -> NaN)."""
    nan = float('nan')
    voltage_v = nan if sys_status.voltage_battery in (0, 65535) else \
        sys_status.voltage_battery / 1000.0
    current_a = nan if sys_status.current_battery < 0 else sys_status.current_battery / 100.0
    remaining = nan if sys_status.battery_remaining < 0 else \
        sys_status.battery_remaining / 100.0
    return voltage_v, current_a, remaining
