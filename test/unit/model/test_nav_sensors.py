"""Navigation sensors: noise statistics match their configuration; dropouts; determinism."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from uvms_model.errors import ParameterError
from uvms_model.nav_sensor_parameters import (
    NAVIGATION_PARAMETER_SPECS,
    DvlParameters,
    ImuParameters,
    NavigationParameters,
)
from uvms_model.nav_sensors import (
    GRAVITY_NED,
    DepthSensor,
    Dvl,
    DvlReading,
    Imu,
    NavigationSensors,
    NavigationTruth,
)

from uvms_description.robots import robot_names, robot_parameters

AT_REST = NavigationTruth.of([0.0, 0.0, 2.0], [0.0, 0.0, 0.0])


def allan_deviation(samples: np.ndarray, dt_s: float, cluster_s: float) -> np.ndarray:
    """Non-overlapping Allan deviation per column (IEEE Std 952-1997, eq. C.2)."""
    m = round(cluster_s / dt_s)
    n = samples.shape[0] // m
    means = samples[:n * m].reshape(n, m, -1).mean(axis=1)
    return np.sqrt(0.5 * np.mean(np.diff(means, axis=0) ** 2, axis=0))


def _imu_series(params: ImuParameters, seconds: float, seed: int = 3) -> tuple[np.ndarray, ...]:
    imu = Imu(params, seed)
    n = round(seconds * params.rate_hz)
    gyro, accel, rpy = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        reading = imu.measure(k * imu.period_ns, AT_REST)
        gyro[k], accel[k], rpy[k] = reading.w_body, reading.f_body, reading.rpy
    return gyro, accel, rpy


def test_white_noise_density_from_allan_deviation() -> None:
    """Without bias, the Allan deviation at T is N / sqrt(T) for gyro and accelerometer."""
    params = ImuParameters(gyro_bias_random_walk=0.0, accel_bias_random_walk=0.0)
    gyro, accel, _ = _imu_series(params, 200.0)
    for cluster in (0.05, 0.5):
        np.testing.assert_allclose(allan_deviation(gyro, 1 / 200, cluster),
                                   params.gyro_noise_density / math.sqrt(cluster), rtol=0.15)
        np.testing.assert_allclose(allan_deviation(accel, 1 / 200, cluster),
                                   params.accel_noise_density / math.sqrt(cluster), rtol=0.15)


def test_bias_random_walk_from_allan_deviation() -> None:
    """With a long correlation time the bias walks: Allan deviation K sqrt(T / 3) for T >> 1 s."""
    params = ImuParameters(rate_hz=10.0, gyro_bias_time_constant_s=1e7,
                           accel_bias_time_constant_s=1e7)
    gyro, accel, _ = _imu_series(params, 20000.0)
    cluster = 100.0
    white_g = params.gyro_noise_density / math.sqrt(cluster)
    walk_g = params.gyro_bias_random_walk * math.sqrt(cluster / 3)
    assert white_g < 0.05 * walk_g
    np.testing.assert_allclose(allan_deviation(gyro, 0.1, cluster), walk_g, rtol=0.2)
    walk_a = params.accel_bias_random_walk * math.sqrt(cluster / 3)
    np.testing.assert_allclose(allan_deviation(accel, 0.1, cluster), walk_a, rtol=0.2)


def test_bias_time_constant_bounds_the_bias() -> None:
    """A Gauss-Markov bias keeps the stationary std K sqrt(tau / 2) and decorrelates at tau."""
    params = ImuParameters(rate_hz=10.0, gyro_noise_density=0.0, accel_noise_density=0.0,
                           gyro_bias_time_constant_s=20.0)
    gyro, _, _ = _imu_series(params, 8000.0)
    expected = params.gyro_bias_random_walk * math.sqrt(20.0 / 2)
    np.testing.assert_allclose(gyro.std(axis=0), expected, rtol=0.2)
    lag = 200  # 20 s at 10 Hz: correlation e^-1
    corr = np.mean([np.corrcoef(gyro[:-lag, i], gyro[lag:, i])[0, 1] for i in range(3)])
    assert corr == pytest.approx(math.exp(-1), abs=0.12)


def test_accelerometer_reads_minus_gravity_at_rest_and_rotates_with_attitude() -> None:
    """Specific force f = R^T (a - g): -9.81 along body z level; along body x pitched 90 deg up."""
    params = ImuParameters(accel_noise_density=0.0, accel_bias_random_walk=0.0)
    level = Imu(params, 1).measure(0, AT_REST)
    np.testing.assert_allclose(level.f_body, -GRAVITY_NED, atol=1e-12)
    pitched = NavigationTruth.of([0.0, 0.0, 0.0], [0.0, 0.5 * math.pi - 1e-9, 0.0])
    np.testing.assert_allclose(Imu(params, 1).measure(0, pitched).f_body, [9.81, 0.0, 0.0],
                               atol=1e-6)


def test_ahrs_yaw_error_is_larger_than_roll_and_pitch_errors() -> None:
    """The AHRS errors have the configured std per axis, yaw's the largest."""
    params = ImuParameters(rate_hz=10.0, ahrs_time_constant_s=1.0)
    _, _, rpy = _imu_series(params, 2000.0)
    std = rpy.std(axis=0)
    np.testing.assert_allclose(std, [params.roll_pitch_sigma_rad] * 2 + [params.yaw_sigma_rad],
                               rtol=0.1)
    assert std[2] > 3 * std[0]


@pytest.mark.parametrize('speed', [0.0, 0.5, 1.5])
def test_dvl_sigma_grows_with_speed(speed: float) -> None:
    """The DVL noise std per axis is a + b |v| at the true speed."""
    params = DvlParameters()
    dvl = Dvl(params, 5)
    truth = NavigationTruth.of([0.0, 0.0, 5.0], [0.0, 0.0, 0.0], v_body=[speed, 0.0, 0.0])
    errors = np.array([dvl.measure(0, truth, 10.0).v_dvl - [speed, 0.0, 0.0]
                       for _ in range(4000)])
    expected = params.sigma_base_m_s + params.sigma_per_speed * speed
    np.testing.assert_allclose(errors.std(axis=0), expected, rtol=0.06)
    np.testing.assert_allclose(errors.mean(axis=0), 0.0, atol=4 * expected / math.sqrt(4000))


def test_dvl_measures_lever_arm_velocity_in_its_own_frame() -> None:
    """A yawing vehicle moves a DVL mounted aft sideways: v + w x r, rotated into its frame."""
    params = DvlParameters(position_m=(-1.0, 0.0, 0.0), orientation_rpy=(0.0, 0.0, 0.5 * math.pi),
                           sigma_base_m_s=0.0, sigma_per_speed=0.0)
    truth = NavigationTruth.of([0.0, 0.0, 5.0], [0.0, 0.0, 0.0], v_body=[0.2, 0.0, 0.0],
                               w_body=[0.0, 0.0, 0.1])
    reading = Dvl(params, 1).measure(0, truth, 10.0)
    # body: v + w x r = (0.2, -0.1, 0); DVL x is body y, DVL y is body -x.
    np.testing.assert_allclose(reading.v_dvl, [-0.1, -0.2, 0.0], atol=1e-12)


@pytest.mark.parametrize(('depth', 'seabed', 'speed', 'valid'), [
    (5.0, 10.0, 0.5, True),
    (9.98, 10.0, 0.5, False),   # altitude 0.02 m < 0.05 m
    (5.0, 60.0, 0.5, False),    # altitude 55 m > 50 m
    (5.0, 0.0, 0.5, False),     # no seabed
    (5.0, 10.0, 2.5, False),    # faster than 2 m/s
])
def test_dvl_valid_only_with_bottom_lock(depth: float, seabed: float, speed: float,
                                         valid: bool) -> None:
    """Outside 0.05-50 m altitude, without a seabed or above 2 m/s the reading is invalid."""
    truth = NavigationTruth.of([0.0, 0.0, depth], [0.0, 0.0, 0.0], v_body=[speed, 0.0, 0.0])
    reading = Dvl(DvlParameters(), 1).measure(0, truth, seabed)
    assert reading.valid is valid
    assert bool(np.isfinite(reading.v_dvl).all()) is valid


def test_dvl_rate_follows_altitude_and_drops_out_above_range() -> None:
    """Sampled on a 2 ms grid, the DVL reports at 15 Hz near the bottom and stops locking high."""
    params = NavigationParameters(world=replace(NavigationParameters().world,
                                                seabed_depth_m=2.5))
    sensors = NavigationSensors(params, 2)
    readings: list[DvlReading] = []
    for k in range(5000):  # 10 s
        depth = 2.2 if k < 2500 else -60.0  # altitude 0.3 m, then 62.5 m
        truth = NavigationTruth.of([0.0, 0.0, depth], [0.0, 0.0, 0.0])
        readings += [r for r in sensors.sample(k * 2_000_000, truth) if isinstance(r, DvlReading)]
    low = [r for r in readings if r.t_ns < 5_000_000_000]
    high = [r for r in readings if r.t_ns >= 5_200_000_000]
    assert len(low) == pytest.approx(5 * 15, abs=2)
    assert all(r.valid for r in low)
    assert high and not any(r.valid for r in high)


def test_depth_has_one_bias_per_run_and_white_noise() -> None:
    """Mean error is the run's bias (inside +-bias_max_m, another per seed); std is sigma_m."""
    params = NavigationParameters().depth
    biases = []
    for seed in (1, 2, 3):
        sensor = DepthSensor(params, seed)
        errors = np.array([sensor.measure(0, AT_REST).depth_m - 2.0 for _ in range(4000)])
        assert abs(errors.mean()) <= params.bias_max_m + 4 * params.sigma_m / math.sqrt(4000)
        assert errors.mean() == pytest.approx(sensor.bias_m, abs=4 * params.sigma_m / 63)
        assert errors.std() == pytest.approx(params.sigma_m, rel=0.06)
        biases.append(sensor.bias_m)
    assert len(set(biases)) == 3


def test_same_seed_same_readings_other_seed_other_readings() -> None:
    """The readings are a function of the seed: a repeat is identical, another seed differs."""
    params = NavigationParameters(world=replace(NavigationParameters().world,
                                                seabed_depth_m=10.0))

    def run(seed: int) -> list[np.ndarray]:
        sensors = NavigationSensors(params, seed)
        out = []
        for k in range(300):
            for r in sensors.sample(k * 2_000_000, AT_REST):
                out.append(np.concatenate([np.ravel(v) for v in vars(r).values()
                                           if not isinstance(v, bool)]))
        return out

    first, again, other = run(4), run(4), run(5)
    assert len(first) == len(again) == len(other)
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(first, again, strict=True))
    assert not all(np.array_equal(a, b, equal_nan=True)
                   for a, b in zip(first, other, strict=True))


def test_position_fix_only_when_enabled_at_its_rate() -> None:
    """The USBL fix is off by default; enabled it reports at 1 Hz."""
    base = NavigationParameters()
    assert NavigationSensors(base, 1).position_fix is None
    fix = replace(base, position_fix=replace(base.position_fix, enabled=True))
    sensors = NavigationSensors(fix, 1)
    count = sum(type(r).__name__ == 'PositionFixReading'
                for k in range(2500) for r in sensors.sample(k * 2_000_000, AT_REST))
    assert count == 5


@pytest.mark.parametrize('robot', robot_names())
def test_every_robot_folder_gives_valid_navigation_figures(robot: str) -> None:
    """navigation.yaml gives the simulator and the estimator the same, valid figures."""
    names = {s.name for s in NAVIGATION_PARAMETER_SPECS}
    simulator = {k: v.value for k, v in robot_parameters(robot, 'simulator').items()
                 if k.startswith('navigation.')}
    estimator = {k: v.value for k, v in robot_parameters(robot, 'estimator').items()
                 if k.startswith('navigation.')}
    assert simulator and simulator == estimator
    assert set(simulator) <= names
    params = NavigationParameters.from_flat_dict(simulator)
    assert params.imu.yaw_sigma_rad > params.imu.roll_pitch_sigma_rad
    assert not robot_parameters(robot, 'controller').keys() & names


def test_bad_navigation_parameter_is_named() -> None:
    """A DVL rate table one value short names the parameter."""
    with pytest.raises(ParameterError, match='rate_by_altitude_hz has 4 values, expected 5'):
        NavigationParameters.from_flat_dict(
            {'navigation.dvl.rate_by_altitude_hz': [15.0, 10.0, 5.0, 3.0]})
