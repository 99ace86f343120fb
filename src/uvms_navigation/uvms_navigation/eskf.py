"""Error-state extended Kalman filter over pose, velocity, IMU biases and sensor errors.

Pure numpy (no rclpy, no messages). The filter of Solà, "Quaternion kinematics for the
error-state Kalman filter" (arXiv:1711.02508, 2017), sec. 5.3 and 6-7, with the attitude as a
rotation matrix and its error local (body frame, Solà's "local angular error", sec. 7.2), and
the velocity kept in the body frame, as DVL-aided navigation of underwater vehicles does
(Fossen 2021, "Handbook of Marine Craft Hydrodynamics and Motion Control", 2nd ed., ch. 14):
the DVL then measures a state linearly, while a velocity in map_ned would enter it through
R^T v, whose Jacobian at an uncertain v gives yaw information that does not exist (measured:
yaw NEES 2.8 times its bound at rest with a DVL; Huang, Mourikis, Roumeliotis 2010,
"Observability-based rules for designing consistent EKF SLAM estimators").

- Nominal state: p (map_ned), v (base_link_frd), R = rot_ned_from_body, accelerometer bias
  a_b and gyro bias w_b (base_link_frd), depth sensor bias b_d, AHRS errors e (roll, pitch,
  yaw).
- Error state dx (19): dp, dv, dtheta, da_b, dw_b, db_d, de; true R = R Exp(dtheta).
- Prediction with an IMU sample (a_m, w_m) over dt, f = a_m - a_b, w = w_m - w_b, g in
  map_ned (the body-frame form of Solà eq. 260 and Fossen eq. 14.x: v' = f + R^T g - w x v):
  p += R v dt;  v += (f + R^T g - w x v) dt;  R <- R Exp(w dt); biases and AHRS errors decay
  as their Gauss-Markov models, x <- e^(-dt/tau) x (Maybeck 1979, sec. 4.11).
- Error transition F, first order: dp += (R dv - R [v]x dtheta) dt;
  dv += (-[w]x dv + [R^T g]x dtheta - da_b - [v]x dw_b) dt;
  dtheta <- Exp(w dt)^T dtheta - dw_b dt (Solà eq. 270c); Gauss-Markov blocks e^(-dt/tau).
  Process noise Q_i (Solà eq. 271): white noise densities N^2 dt on dv and dtheta;
  Gauss-Markov increments K^2 tau/2 (1 - e^(-2 dt/tau)) on the biases and AHRS errors.
- Update (Solà eq. 274-276): K = P H^T (H P H^T + V)^-1, dx = K (y - h(x)),
  P <- (I - K H) P (I - K H)^T + K V K^T (Joseph form), then injection x <- x (+) dx
  (eq. 282) and reset with G = I (first order, eq. 287 with dtheta small).

Measurement models (H the Jacobian with respect to dx):
- AHRS roll, pitch, yaw: rpy(R) + e; H = [J2(rpy) on dtheta, I on de] (J2: Euler rates
  from body rates, paper sec. 3.2).
- DVL in its frame: C^T (v + (w_m - w_b) x r); H = C^T [I on dv, [r]x on dw_b];
  V = sigma^2 I with sigma = a + b |v| of the prediction.
- Depth: p_z + b_d; position fix: p.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from uvms_model.kinematics import (
    euler_from_rotation,
    euler_rate_matrix,
    rot_ned_from_body,
    skew,
)
from uvms_model.nav_sensor_parameters import NavigationParameters

FloatArray = NDArray[np.float64]
GRAVITY_NED = np.array([0.0, 0.0, 9.81])

P, V, TH, BA, BG, BD, AE = (slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12), slice(12, 15),
                            slice(15, 16), slice(16, 19))
"""Slices of the error state: position, velocity, attitude, biases, depth bias, AHRS error."""
N_ERROR = 19
_AHRS_REGULARISATION_RAD = 1e-3
"""White noise the filter assumes on an AHRS angle beside its Gauss-Markov error: the AHRS model
has none, but an exact sum theta + e makes H P H^T singular and the update lose the
theta-e correlation to rounding (yaw variance collapsed 50-fold over 5 s with tau 1e5 s)."""


_I3 = np.eye(3)
_I19 = np.eye(N_ERROR)
_I3.flags.writeable = _I19.flags.writeable = False
"""Identities made once (read-only): ``np.eye`` was called 8 times per IMU sample."""


def cross3(a: FloatArray, b: FloatArray) -> FloatArray:
    """``np.cross`` of two 3-vectors, bit for bit, without its general axis handling.

    Each component is one product minus another, each rounded, as ``np.cross`` computes it
    (``multiply`` then ``-=``): the same doubles at a tenth of the cost.
    """
    a1, a2, a3 = a.tolist()
    b1, b2, b3 = b.tolist()
    return np.array((a2 * b3 - a3 * b2, a3 * b1 - a1 * b3, a1 * b2 - a2 * b1))


def exp_so3(phi: FloatArray) -> FloatArray:
    """Rotation matrix Exp(phi) of a rotation vector (Rodrigues; Solà eq. 77)."""
    angle = math.sqrt(float(phi @ phi))
    k = skew(phi)
    if angle < 1e-8:
        return _I3 + k + 0.5 * k @ k
    return (_I3 + math.sin(angle) / angle * k
            + (1.0 - math.cos(angle)) / angle ** 2 * k @ k)


def wrap(angle: FloatArray) -> FloatArray:
    """Angles wrapped to [-pi, pi)."""
    return (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi


@dataclass(frozen=True)
class EstimatorSettings:
    """The filter's noise model (the robot's sensor figures) and its start.

    Attributes:
        sensors: The navigation sensor figures (``navigation.yaml``).
        initial_position_sigma_m: Start std of the position (m).
        initial_velocity_sigma_m_s: Start std of the velocity, per body axis (m/s).
        initial_attitude_sigma_rad: Start std of roll, pitch and yaw (rad).
        dvl_gate: Chi-square gate of a DVL innovation (3 dof); larger is rejected.
    """

    sensors: NavigationParameters
    initial_position_sigma_m: float = 1.0
    initial_velocity_sigma_m_s: float = 0.1
    initial_attitude_sigma_rad: float = 0.1
    dvl_gate: float = 16.27  # chi-square 3 dof, 0.999


class ErrorStateEkf:
    """The error-state EKF of the module docstring.

    Example:
        >>> ekf = ErrorStateEkf(EstimatorSettings(NavigationParameters()))
        >>> ekf.reset(0, [0.0, 0.0, 2.0], [0.0, 0.0, 0.0])
        >>> ekf.predict(5_000_000, [0.0, 0.0, 0.0], [0.0, 0.0, -9.81])
        >>> bool(abs(ekf.v_ned[2]) < 1e-9)
        True
    """

    def __init__(self, settings: EstimatorSettings) -> None:
        self.settings = settings
        imu = settings.sensors.imu
        self._tau = np.array([imu.accel_bias_time_constant_s] * 3
                             + [imu.gyro_bias_time_constant_s] * 3
                             + [math.inf] + [imu.ahrs_time_constant_s] * 3)
        # Gauss-Markov walks; stationary std K sqrt(tau/2) (the AHRS's is given as a std).
        ahrs = np.array([imu.roll_pitch_sigma_rad] * 2 + [imu.yaw_sigma_rad])
        self._stationary_var = np.concatenate((
            np.full(3, imu.accel_bias_random_walk ** 2 * imu.accel_bias_time_constant_s / 2),
            np.full(3, imu.gyro_bias_random_walk ** 2 * imu.gyro_bias_time_constant_s / 2),
            [settings.sensors.depth.bias_max_m ** 2 / 3.0],  # uniform in +-bias_max_m
            ahrs ** 2))
        dvl = settings.sensors.dvl
        self._rot_body_from_dvl = rot_ned_from_body(*dvl.orientation_rpy)
        self._r_dvl = np.array(dvl.position_m)
        self.reset(0, np.zeros(3), np.zeros(3))

    def reset(self, t_ns: int, p_ned: ArrayLike, rpy: ArrayLike,
              v_ned: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        """Start at ``t_ns`` from a pose guess with the settings' start covariance."""
        s = self.settings
        self.t_ns = int(t_ns)
        self.p_ned: FloatArray = np.array(p_ned, dtype=float)
        self.rot: FloatArray = rot_ned_from_body(*np.asarray(rpy, dtype=float))
        self.v_body: FloatArray = self.rot.T @ np.asarray(v_ned, dtype=float)
        self.x_gm = np.zeros(10)  # a_b, w_b, b_d, e: the Gauss-Markov part of the state
        self.w_m = np.zeros(3)
        variances = np.concatenate((np.full(3, s.initial_position_sigma_m ** 2),
                                    np.full(3, s.initial_velocity_sigma_m_s ** 2),
                                    np.full(3, s.initial_attitude_sigma_rad ** 2),
                                    self._stationary_var))
        self.cov = np.diag(variances)
        self.last_dvl_ns: int | None = None
        self.dvl_rejected = 0
        self._covariances: tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None = None

    def reset_from_ahrs(self, t_ns: int, p_ned: ArrayLike, rpy_m: ArrayLike,
                        v_ned: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        """Start with the attitude of an AHRS reading (initial alignment).

        The attitude error is then minus the AHRS error: dtheta = -J2^-1 e, so the start
        covariance holds that correlation exactly (P_theta = J2^-1 S J2^-T, P_theta,e =
        -J2^-1 S, S the AHRS error covariance) instead of two independent priors.
        """
        self.reset(t_ns, p_ned, rpy_m, v_ned)
        rpy = np.asarray(rpy_m, dtype=float)
        j_inv = np.linalg.inv(euler_rate_matrix(rpy[0], rpy[1]))
        s_e = np.diag(self._stationary_var[7:10])
        self.cov[TH, TH] = j_inv @ s_e @ j_inv.T
        self.cov[TH, AE] = -j_inv @ s_e
        self.cov[AE, TH] = self.cov[TH, AE].T
        self._covariances = None  # the covariance changed in place

    @property
    def accel_bias(self) -> FloatArray:
        """Estimated accelerometer bias in base_link_frd (m/s^2)."""
        return self.x_gm[0:3]

    @property
    def gyro_bias(self) -> FloatArray:
        """Estimated gyro bias in base_link_frd (rad/s)."""
        return self.x_gm[3:6]

    @property
    def rpy(self) -> FloatArray:
        """Estimated roll, pitch, yaw (rad)."""
        return np.array(euler_from_rotation(self.rot))

    @property
    def w_body(self) -> FloatArray:
        """Bias-corrected angular velocity of the last IMU sample, base_link_frd (rad/s)."""
        return self.w_m - self.gyro_bias

    @property
    def v_ned(self) -> FloatArray:
        """Estimated linear velocity in map_ned (m/s)."""
        return self.rot @ self.v_body

    def predict(self, t_ns: int, w_m: ArrayLike, f_m: ArrayLike) -> None:
        """Propagate to ``t_ns`` with an IMU sample (rate rad/s, specific force m/s^2)."""
        dt = (int(t_ns) - self.t_ns) * 1e-9
        self.w_m = np.asarray(w_m, dtype=float)
        if dt <= 0.0:
            return
        imu = self.settings.sensors.imu
        f = np.asarray(f_m, dtype=float) - self.accel_bias
        w = self.w_m - self.gyro_bias
        v = self.v_body
        g_body = self.rot.T @ GRAVITY_NED
        step = exp_so3(w * dt)
        decay = np.exp(-dt / self._tau)
        fx = _I19.copy()
        fx[P, V] = self.rot * dt
        fx[P, TH] = -self.rot @ skew(v) * dt
        fx[V, V] = _I3 - skew(w) * dt
        fx[V, TH] = skew(g_body) * dt
        fx[V, BA] = -_I3 * dt
        fx[V, BG] = -skew(v) * dt
        fx[TH, TH] = step.T
        fx[TH, BG] = -_I3 * dt
        fx[9:, 9:] = np.diag(decay)
        q = np.zeros(N_ERROR)
        q[V] = imu.accel_noise_density ** 2 * dt
        q[TH] = imu.gyro_noise_density ** 2 * dt
        q[9:] = self._stationary_var * (1.0 - decay ** 2)
        self.p_ned = self.p_ned + self.rot @ v * dt
        self.v_body = v + (f + g_body - cross3(w, v)) * dt
        self.rot = self.rot @ step
        self.x_gm = self.x_gm * decay
        self.cov = fx @ self.cov @ fx.T + np.diag(q)
        self.t_ns = int(t_ns)

    def update_attitude(self, rpy_m: ArrayLike) -> float:
        """Fuse an AHRS roll, pitch, yaw (rad); returns the innovation's NIS."""
        h = np.zeros((3, N_ERROR))
        rpy = self.rpy
        h[:, TH] = euler_rate_matrix(rpy[0], rpy[1])
        h[:, AE] = _I3
        y = wrap(np.asarray(rpy_m, dtype=float) - rpy - self.x_gm[7:10])
        return self._update(y, h, np.full(3, _AHRS_REGULARISATION_RAD ** 2))

    def update_dvl(self, v_dvl: ArrayLike) -> float | None:
        """Fuse a valid DVL velocity (m/s, DVL frame); None if the gate rejected it."""
        c_t = self._rot_body_from_dvl.T
        predicted = c_t @ (self.v_body + cross3(self.w_body, self._r_dvl))
        dvl = self.settings.sensors.dvl
        sigma = dvl.sigma_base_m_s + dvl.sigma_per_speed * float(np.linalg.norm(predicted))
        h = np.zeros((3, N_ERROR))
        h[:, V] = c_t
        h[:, BG] = c_t @ skew(self._r_dvl)
        y = np.asarray(v_dvl, dtype=float) - predicted
        noise = np.full(3, max(sigma, 1e-6) ** 2)
        s = h @ self.cov @ h.T + np.diag(noise)
        nis = float(y @ np.linalg.solve(s, y))
        if nis > self.settings.dvl_gate:
            self.dvl_rejected += 1
            return None
        self.last_dvl_ns = self.t_ns
        return self._update(y, h, noise)

    def update_depth(self, depth_m: float) -> float:
        """Fuse a depth reading (m, positive down)."""
        h = np.zeros((1, N_ERROR))
        h[0, 2] = 1.0
        h[0, 15] = 1.0
        y = np.array([depth_m - self.p_ned[2] - self.x_gm[6]])
        sigma = self.settings.sensors.depth.sigma_m
        return self._update(y, h, np.array([max(sigma, 1e-6) ** 2]))

    def update_position(self, p_ned_m: ArrayLike, sigma_m: ArrayLike | None = None) -> float:
        """Fuse a position fix in map_ned (m), std ``sigma_m`` per axis (the settings' if None)."""
        fix = self.settings.sensors.position_fix
        sigma = (np.array([fix.sigma_horizontal_m] * 2 + [fix.sigma_vertical_m])
                 if sigma_m is None else np.asarray(sigma_m, dtype=float))
        h = np.zeros((3, N_ERROR))
        h[:, P] = _I3
        y = np.asarray(p_ned_m, dtype=float) - self.p_ned
        return self._update(y, h, np.maximum(sigma, 1e-6) ** 2)

    def _update(self, y: FloatArray, h: FloatArray, noise: FloatArray) -> float:
        """Kalman update in Joseph form, injection and reset (Solà eq. 274-287)."""
        s = h @ self.cov @ h.T + np.diag(noise)
        gain = np.linalg.solve(s, h @ self.cov).T
        dx = gain @ y
        i_kh = _I19 - gain @ h
        self.cov = i_kh @ self.cov @ i_kh.T + gain @ np.diag(noise) @ gain.T
        self.cov = 0.5 * (self.cov + self.cov.T)
        self.p_ned = self.p_ned + dx[P]
        self.v_body = self.v_body + dx[V]
        self.rot = self.rot @ exp_so3(dx[TH])
        self.x_gm = self.x_gm + dx[9:]
        return float(y @ np.linalg.solve(s, y))

    def extrapolated(self, t_ns: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Position, rot_ned_from_body and body velocity carried to ``t_ns``.

        At constant body velocity and rate from the filter's time; the filter does not move.
        """
        dt = max(int(t_ns) - self.t_ns, 0) * 1e-9
        if dt == 0.0:
            return self.p_ned.copy(), self.rot.copy(), self.v_body.copy()
        return (self.p_ned + self.rot @ self.v_body * dt, self.rot @ exp_so3(self.w_body * dt),
                self.v_body.copy())

    def pose_covariance(self) -> FloatArray:
        """6x6 covariance of (x, y, z in map_ned; roll, pitch, yaw) (m^2, rad^2); read-only.

        Computed once per filter state (`_covariance_pair`): the estimator publishes at each
        control period, the filter changes only with an IMU, DVL, depth or fix reading.
        """
        return self._covariance_pair()[0]

    def twist_covariance(self) -> FloatArray:
        """6x6 covariance of (linear velocity, angular velocity) in base_link_frd; read-only."""
        return self._covariance_pair()[1]

    def _covariance_pair(self) -> tuple[FloatArray, FloatArray]:
        """The pose and twist covariances of the present ``cov`` and ``rot``, cached.

        ``predict``, ``_update`` and ``reset`` assign new ``cov`` and ``rot`` arrays, so the
        cache holds while both are the very arrays it was computed from (kept referenced, so
        an identity is never reused); ``reset_from_ahrs``, which writes ``cov`` in place,
        drops it. The values are those computed afresh: nothing in the arithmetic changes.
        """
        cached = self._covariances
        if cached is not None and cached[0] is self.cov and cached[1] is self.rot:
            return cached[2], cached[3]
        pose, twist = self._pose_covariance(), self._twist_covariance()
        pose.flags.writeable = twist.flags.writeable = False
        self._covariances = (self.cov, self.rot, pose, twist)
        return pose, twist

    def _pose_covariance(self) -> FloatArray:
        j = np.eye(6)
        rpy = self.rpy
        j[3:, 3:] = euler_rate_matrix(rpy[0], rpy[1])
        block = self.cov[0:9, 0:9][np.ix_([0, 1, 2, 6, 7, 8], [0, 1, 2, 6, 7, 8])]
        return j @ block @ j.T

    def _twist_covariance(self) -> FloatArray:
        out = np.zeros((6, 6))
        out[:3, :3] = self.cov[V, V]
        imu = self.settings.sensors.imu
        gyro = imu.gyro_noise_density ** 2 * imu.rate_hz
        out[3:, 3:] = self.cov[BG, BG] + _I3 * gyro
        return out
