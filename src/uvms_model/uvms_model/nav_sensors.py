"""Navigation sensors: IMU with AHRS, DVL with bottom lock, depth sensor, USBL position fix.

Pure numpy. Each sensor draws its noise from its own ``numpy.random.Generator`` seeded by the
run's seed and a fixed stream number, so a run is deterministic and adding one sensor does
not change another's noise. Noise models:

- White noise of density N sampled at rate f: standard deviation N sqrt(f) per sample (IEEE
  Std 952-1997, annex C; the Allan deviation of it is N / sqrt(T)).
- Bias: first-order Gauss-Markov b' = -b / tau + w, w of density K, discretised exactly:
  b_k+1 = e^(-dt/tau) b_k + K sqrt(tau/2 (1 - e^(-2 dt/tau))) n_k (as uuv_simulator's IMU
  plugin, after Maybeck 1979, sec. 4.11); for T << tau its Allan deviation is K sqrt(T/3).
- IMU specific force f = R^T (a - g) with g = (0, 0, 9.81) m/s^2 in map_ned: at rest the
  accelerometer reads -g along body z (up, -9.81 in base_link_frd).
- AHRS: the true roll, pitch, yaw plus Gauss-Markov errors of their own standard deviation
  (yaw worse: a magnetometer near thrusters).
- DVL: velocity over ground of the DVL origin in the DVL frame, v + w x r, with noise
  sigma = a + b |v|; valid only with bottom lock (a seabed at an altitude inside the range)
  and |v| <= the largest speed; its rate depends on the altitude (Water Linked DVL A50).
- Depth: z + per-run bias (uniform) + white noise (Bar30 class).
- Position fix: p + white noise (USBL class), optional.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uvms_model.errors import StateError
from uvms_model.kinematics import rot_ned_from_body
from uvms_model.nav_sensor_parameters import (
    DepthParameters,
    DvlParameters,
    ImuParameters,
    NavigationParameters,
    PositionFixParameters,
)

FloatArray = NDArray[np.float64]
GRAVITY_NED = np.array([0.0, 0.0, 9.81])
"""Gravity in map_ned (m/s^2), z down."""
_STREAMS = {'imu': 1, 'dvl': 2, 'depth': 3, 'position_fix': 4}


def _rng(seed: int, sensor: str) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([int(seed), _STREAMS[sensor]]))


def _vec(name: str, value: ArrayLike) -> FloatArray:
    array = np.asarray(value, dtype=float)
    if array.shape != (3,) or not np.isfinite(array).all():
        raise StateError(f'{name} must be 3 finite numbers, got {array.tolist()!r}')
    return array


@dataclass(frozen=True)
class NavigationTruth:
    """The true motion the sensors measure.

    Attributes:
        p_ned: Vehicle origin in map_ned (m).
        rpy: Roll, pitch, yaw of base_link_frd in map_ned (rad).
        v_body: Linear velocity of the vehicle origin in base_link_frd (m/s).
        w_body: Angular velocity in base_link_frd (rad/s).
        a_ned: Linear acceleration of the vehicle origin in map_ned (m/s^2).
    """

    p_ned: FloatArray
    rpy: FloatArray
    v_body: FloatArray
    w_body: FloatArray
    a_ned: FloatArray

    @classmethod
    def of(cls, p_ned: ArrayLike, rpy: ArrayLike, v_body: ArrayLike = (0.0, 0.0, 0.0),
           w_body: ArrayLike = (0.0, 0.0, 0.0),
           a_ned: ArrayLike = (0.0, 0.0, 0.0)) -> NavigationTruth:
        """Checked truth from array-likes (3 finite numbers each)."""
        return cls(_vec('p_ned', p_ned), _vec('rpy', rpy), _vec('v_body', v_body),
                   _vec('w_body', w_body), _vec('a_ned', a_ned))


@dataclass(frozen=True)
class ImuReading:
    """One IMU sample: rate and specific force in base_link_frd, AHRS roll, pitch, yaw."""

    t_ns: int
    w_body: FloatArray
    f_body: FloatArray
    rpy: FloatArray
    rpy_sigma: FloatArray


@dataclass(frozen=True)
class DvlReading:
    """One DVL sample; ``v_dvl`` is NaN when ``valid`` is False (no bottom lock, too fast)."""

    t_ns: int
    valid: bool
    v_dvl: FloatArray
    sigma_m_s: float
    altitude_m: float


@dataclass(frozen=True)
class DepthReading:
    """One depth sample (m, positive down) and its white noise std (m)."""

    t_ns: int
    depth_m: float
    sigma_m: float


@dataclass(frozen=True)
class PositionFixReading:
    """One position fix in map_ned (m) and its standard deviation per axis (m)."""

    t_ns: int
    p_ned: FloatArray
    sigma_m: FloatArray


Reading = ImuReading | DvlReading | DepthReading | PositionFixReading


class GaussMarkov:
    """First-order Gauss-Markov process, exact discretisation (module docstring).

    Args:
        walk: Density K of the driving noise (unit/s/sqrt(Hz)).
        tau_s: Correlation time (s).
        dt_s: Sample period (s).
        size: Number of independent components.
        rng: Noise generator; the start is drawn from the stationary law, std K sqrt(tau/2).
    """

    def __init__(self, walk: float, tau_s: float, dt_s: float, size: int,
                 rng: np.random.Generator) -> None:
        self.phi = math.exp(-dt_s / tau_s)
        self.step_sigma = walk * math.sqrt(0.5 * tau_s * (1.0 - self.phi ** 2))
        self.stationary_sigma = walk * math.sqrt(0.5 * tau_s)
        self._rng = rng
        self.value = rng.standard_normal(size) * self.stationary_sigma

    def step(self) -> FloatArray:
        """Advance one sample and return the new value."""
        self.value = self.phi * self.value + self.step_sigma * self._rng.standard_normal(
            self.value.shape[0])
        return self.value


class Imu:
    """Gyro, accelerometer and AHRS with white noise and Gauss-Markov biases and errors."""

    def __init__(self, params: ImuParameters, seed: int) -> None:
        self.params = params
        self.period_ns = round(1e9 / params.rate_hz)
        dt = self.period_ns * 1e-9
        self._rng = _rng(seed, 'imu')
        self.gyro_sigma = params.gyro_noise_density / math.sqrt(dt)
        self.accel_sigma = params.accel_noise_density / math.sqrt(dt)
        self.gyro_bias = GaussMarkov(params.gyro_bias_random_walk,
                                     params.gyro_bias_time_constant_s, dt, 3, self._rng)
        self.accel_bias = GaussMarkov(params.accel_bias_random_walk,
                                      params.accel_bias_time_constant_s, dt, 3, self._rng)
        self.ahrs_sigma = np.array([params.roll_pitch_sigma_rad, params.roll_pitch_sigma_rad,
                                    params.yaw_sigma_rad])
        tau = params.ahrs_time_constant_s
        # Unit walk then scaled per axis: stationary std 1 needs K = sqrt(2 / tau).
        self._ahrs = GaussMarkov(math.sqrt(2.0 / tau), tau, dt, 3, self._rng)

    def measure(self, t_ns: int, truth: NavigationTruth) -> ImuReading:
        """One sample at ``t_ns`` of the given truth; the biases advance one period."""
        rot = rot_ned_from_body(*truth.rpy)
        b_g = self.gyro_bias.step()
        b_a = self.accel_bias.step()
        noise = self._rng.standard_normal(6)
        w = truth.w_body + b_g + self.gyro_sigma * noise[:3]
        f = rot.T @ (truth.a_ned - GRAVITY_NED) + b_a + self.accel_sigma * noise[3:]
        rpy = truth.rpy + self.ahrs_sigma * self._ahrs.step()
        rpy[2] = math.remainder(rpy[2], 2.0 * math.pi)
        return ImuReading(t_ns, w, f, rpy, self.ahrs_sigma.copy())


class Dvl:
    """Bottom-track DVL: valid with bottom lock only, sigma = a + b |v|, rate by altitude."""

    def __init__(self, params: DvlParameters, seed: int) -> None:
        self.params = params
        self._rng = _rng(seed, 'dvl')
        self.rot_body_from_dvl = rot_ned_from_body(*params.orientation_rpy)
        self.r_body = np.array(params.position_m)

    def altitude_m(self, truth: NavigationTruth, seabed_depth_m: float) -> float:
        """Height of the DVL above a flat seabed (m), NaN without a seabed (depth 0)."""
        if seabed_depth_m <= 0.0:
            return math.nan
        z = truth.p_ned[2] + float(rot_ned_from_body(*truth.rpy)[2] @ self.r_body)
        return float(seabed_depth_m - z)

    def rate_hz(self, altitude_m: float) -> float:
        """Output rate at this altitude (the last band's without bottom lock)."""
        breaks = self.params.rate_altitude_breaks_m
        rates = self.params.rate_by_altitude_hz
        if not math.isfinite(altitude_m):
            return rates[-1]
        return rates[int(np.searchsorted(np.array(breaks), altitude_m, side='right'))]

    def sigma_m_s(self, speed_m_s: float) -> float:
        """Velocity noise std per axis at this speed (m/s)."""
        return self.params.sigma_base_m_s + self.params.sigma_per_speed * speed_m_s

    def measure(self, t_ns: int, truth: NavigationTruth, seabed_depth_m: float) -> DvlReading:
        """One sample; invalid (NaN velocity) without bottom lock or beyond the top speed."""
        v_true = self.rot_body_from_dvl.T @ (truth.v_body + np.cross(truth.w_body, self.r_body))
        speed = float(np.linalg.norm(v_true))
        altitude = self.altitude_m(truth, seabed_depth_m)
        sigma = self.sigma_m_s(speed)
        noise = self._rng.standard_normal(3)
        p = self.params
        valid = bool(math.isfinite(altitude) and p.min_altitude_m <= altitude <= p.max_altitude_m
                 and speed <= p.max_speed_m_s)
        v = v_true + sigma * noise if valid else np.full(3, math.nan)
        return DvlReading(t_ns, valid, v, sigma, altitude)


class DepthSensor:
    """Pressure depth: z + a per-run bias + white noise."""

    def __init__(self, params: DepthParameters, seed: int) -> None:
        self.params = params
        self.period_ns = round(1e9 / params.rate_hz)
        self._rng = _rng(seed, 'depth')
        self.bias_m = float(self._rng.uniform(-params.bias_max_m, params.bias_max_m))

    def measure(self, t_ns: int, truth: NavigationTruth) -> DepthReading:
        """One sample of the vehicle origin's depth."""
        noise = float(self._rng.standard_normal())
        depth = float(truth.p_ned[2]) + self.bias_m + self.params.sigma_m * noise
        return DepthReading(t_ns, depth, self.params.sigma_m)


class PositionFix:
    """USBL-class position fix in map_ned with white noise."""

    def __init__(self, params: PositionFixParameters, seed: int) -> None:
        self.params = params
        self.period_ns = round(1e9 / params.rate_hz)
        self._rng = _rng(seed, 'position_fix')
        self.sigma = np.array([params.sigma_horizontal_m, params.sigma_horizontal_m,
                               params.sigma_vertical_m])

    def measure(self, t_ns: int, truth: NavigationTruth) -> PositionFixReading:
        """One fix of the vehicle origin."""
        p = truth.p_ned + self.sigma * self._rng.standard_normal(3)
        return PositionFixReading(t_ns, p, self.sigma.copy())


def _next(due_ns: int, period_ns: int, t_ns: int) -> int:
    """The instant after ``due_ns``; one period after ``t_ns`` if the grid skipped past it."""
    nxt = due_ns + period_ns
    return nxt if nxt > t_ns else t_ns + period_ns


class NavigationSensors:
    """Every navigation sensor of a robot, sampled on its own schedule of simulated time.

    Example:
        >>> sensors = NavigationSensors(NavigationParameters(), seed=7)
        >>> truth = NavigationTruth.of([0.0, 0.0, 2.0], [0.0, 0.0, 0.0])
        >>> [type(r).__name__ for r in sensors.sample(0, truth)]
        ['ImuReading', 'DvlReading', 'DepthReading']
    """

    def __init__(self, params: NavigationParameters, seed: int) -> None:
        self.params = params
        self.imu = Imu(params.imu, seed)
        self.dvl = Dvl(params.dvl, seed)
        self.depth = DepthSensor(params.depth, seed)
        self.position_fix = (PositionFix(params.position_fix, seed)
                             if params.position_fix.enabled else None)
        self._next_ns = {'imu': 0, 'dvl': 0, 'depth': 0, 'position_fix': 0}

    def sample(self, t_ns: int, truth: NavigationTruth) -> list[Reading]:
        """The readings due at ``t_ns`` (each sensor at most once per call), in a fixed order.

        A sensor is due when ``t_ns`` reaches its next instant; the next instant advances by
        its period from the previous instant (not from ``t_ns``), so the mean rate holds on
        any publishing grid.
        """
        out: list[Reading] = []
        due = self._next_ns
        seabed = self.params.world.seabed_depth_m
        if t_ns >= due['imu']:
            out.append(self.imu.measure(t_ns, truth))
            due['imu'] = _next(due['imu'], self.imu.period_ns, t_ns)
        if t_ns >= due['dvl']:
            reading = self.dvl.measure(t_ns, truth, seabed)
            out.append(reading)
            period = round(1e9 / self.dvl.rate_hz(reading.altitude_m))
            due['dvl'] = _next(due['dvl'], period, t_ns)
        if t_ns >= due['depth']:
            out.append(self.depth.measure(t_ns, truth))
            due['depth'] = _next(due['depth'], self.depth.period_ns, t_ns)
        if self.position_fix is not None and t_ns >= due['position_fix']:
            out.append(self.position_fix.measure(t_ns, truth))
            due['position_fix'] = _next(due['position_fix'], self.position_fix.period_ns, t_ns)
        return out
