"""Error-state EKF: consistent (NEES), converges from a wrong start, covariance follows the DVL."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest
from scipy.stats import chi2
from uvms_model.kinematics import euler_rate_matrix_inverse, rot_ned_from_body
from uvms_model.nav_sensor_parameters import NavigationParameters
from uvms_model.nav_sensors import (
    DepthReading,
    DvlReading,
    ImuReading,
    NavigationSensors,
    NavigationTruth,
    PositionFixReading,
)
from uvms_navigation.eskf import ErrorStateEkf, EstimatorSettings, exp_so3, wrap
from uvms_navigation.health import OK, WARN, HealthMonitor

STEP_NS = 10_000_000  # the test's sample grid: 100 Hz


def truth_at(t: float) -> NavigationTruth:
    """A smooth 3-D trajectory: an ellipse at 0.3 m/s, heave and roll/pitch/yaw oscillations."""
    w, wz, wa = 0.1, 0.3, 0.2
    p = np.array([3.0 * math.sin(w * t), 2.0 * (1.0 - math.cos(w * t)),
                  5.0 + 0.2 * math.sin(wz * t)])
    v = np.array([0.3 * math.cos(w * t), 0.2 * math.sin(w * t), 0.06 * math.cos(wz * t)])
    a = np.array([-0.03 * math.sin(w * t), 0.02 * math.cos(w * t), -0.018 * math.sin(wz * t)])
    rpy = np.array([0.05 * math.sin(wa * t), 0.04 * math.cos(wa * t), 0.5 + 0.3 * math.sin(w * t)])
    rpy_dot = np.array([0.01 * math.cos(wa * t), -0.008 * math.sin(wa * t),
                        0.03 * math.cos(w * t)])
    rot = rot_ned_from_body(*rpy)
    return NavigationTruth.of(p, rpy, rot.T @ v, euler_rate_matrix_inverse(rpy[0], rpy[1])
                              @ rpy_dot, a)


@dataclass
class Run:
    """Errors (truth - estimate) and covariances along one run."""

    t: np.ndarray
    error: np.ndarray  # (k, 9): position (map_ned), velocity (base_link_frd), attitude (local)
    cov: np.ndarray  # (k, 9, 9)
    start: np.ndarray  # (6,): position and velocity error of the start, before any update


def run_filter(seed: int, seconds: float, params: NavigationParameters,
               start_error: float = 0.0, dvl_off: tuple[float, float] = (
                   math.inf, math.inf), settings: dict[str, float] | None = None) -> Run:
    """Sensors and filter on the trajectory.

    The filter starts from the first AHRS reading (initial alignment) and from the true
    position and velocity plus errors drawn from its start covariance (plus ``start_error``
    metres north).
    """
    sensors = NavigationSensors(params, seed)
    ekf = ErrorStateEkf(EstimatorSettings(params, **(settings or {})))
    rng = np.random.default_rng(1000 + seed)
    t0 = truth_at(0.0)
    s = ekf.settings
    p0 = t0.p_ned + rng.standard_normal(3) * s.initial_position_sigma_m + [start_error, 0, 0]
    v0 = rot_ned_from_body(*t0.rpy) @ t0.v_body + rng.standard_normal(3) * \
        s.initial_velocity_sigma_m_s
    ts, errors, covs = [], [], []
    start = np.concatenate((t0.p_ned - p0, rot_ned_from_body(*t0.rpy) @ t0.v_body - v0))
    for k in range(round(seconds * 1e9 / STEP_NS)):
        t_ns = k * STEP_NS
        truth = truth_at(t_ns * 1e-9)
        for reading in sensors.sample(t_ns, truth):
            if isinstance(reading, ImuReading) and k == 0:
                ekf.reset_from_ahrs(t_ns, p0, reading.rpy, v0)
            elif isinstance(reading, ImuReading):
                ekf.predict(t_ns, reading.w_body, reading.f_body)
                ekf.update_attitude(reading.rpy)
            elif isinstance(reading, DvlReading):
                if reading.valid and not dvl_off[0] <= t_ns * 1e-9 < dvl_off[1]:
                    ekf.update_dvl(reading.v_dvl)
            elif isinstance(reading, DepthReading):
                ekf.update_depth(reading.depth_m)
            elif isinstance(reading, PositionFixReading):
                ekf.update_position(reading.p_ned)
        rot_true = rot_ned_from_body(*truth.rpy)
        d_theta = _log_so3(ekf.rot.T @ rot_true)
        errors.append(np.concatenate((truth.p_ned - ekf.p_ned,
                                      truth.v_body - ekf.v_body, d_theta)))
        covs.append(ekf.cov[:9, :9].copy())
        ts.append(t_ns * 1e-9)
    return Run(np.array(ts), np.array(errors), np.array(covs), start)


def _log_so3(rot: np.ndarray) -> np.ndarray:
    angle = math.acos(max(-1.0, min(1.0, (np.trace(rot) - 1.0) / 2.0)))
    axis = np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]])
    return axis * (0.5 if angle < 1e-8 else angle / (2.0 * math.sin(angle)))


def _params(seabed: float = 10.0, fix: bool = False, imu_hz: float = 100.0
            ) -> NavigationParameters:
    base = NavigationParameters()
    return replace(base, world=replace(base.world, seabed_depth_m=seabed),
                   imu=replace(base.imu, rate_hz=imu_hz),
                   position_fix=replace(base.position_fix, enabled=fix))


def test_exp_and_log_are_inverse() -> None:
    """Exp of a rotation vector is orthonormal and Log gives the vector back."""
    phi = np.array([0.3, -0.2, 1.1])
    rot = exp_so3(phi)
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(_log_so3(rot), phi, atol=1e-12)
    assert wrap(np.array([3.5]))[0] == pytest.approx(3.5 - 2 * math.pi)


def test_estimator_is_consistent_over_monte_carlo_runs() -> None:
    """Average NEES of position, velocity and attitude inside the 99 % chi-square bounds.

    Bar-Shalom, Li, Kirubarajan 2001, sec. 5.4.2: over M runs, M times the average NEES is
    chi-square with M n degrees of freedom. Checked at every second after a 5 s start.
    """
    runs = [run_filter(seed, 30.0, _params(fix=True)) for seed in range(12)]
    m, n = len(runs), 9
    lo, hi = chi2.ppf(0.005, m * n) / m, chi2.ppf(0.995, m * n) / m
    nees = np.mean([[e @ np.linalg.solve(c, e) for e, c in zip(r.error, r.cov, strict=True)]
                    for r in runs], axis=0)
    checked = nees[500::100]
    inside = np.mean((checked >= lo) & (checked <= hi))
    assert inside >= 0.9, (lo, hi, checked)
    assert lo < float(np.mean(checked)) < hi


def test_estimator_converges_from_a_wrong_start() -> None:
    """Started 3 m off (and up to 1 m/s), the estimate converges with the fixes and the DVL."""
    run = run_filter(3, 60.0, _params(fix=True), start_error=3.0,
                     settings={'initial_position_sigma_m': 4.0,
                               'initial_velocity_sigma_m_s': 1.0})
    last = np.abs(run.error[-500:])
    assert np.linalg.norm(run.start[:3]) > 2.5
    assert last[:, :3].max() < 0.3
    assert last[:, 3:6].max() < 0.05
    assert last[:, 8].max() < 0.1
    sigma = np.sqrt(np.diagonal(run.cov[-500:], axis1=1, axis2=2))
    assert (last < 4 * sigma).all()


def test_covariance_grows_without_the_dvl_and_recovers_with_it() -> None:
    """DVL lost 20-50 s: velocity and position sigma grow; back, velocity sigma falls again."""
    run = run_filter(5, 80.0, _params(), dvl_off=(20.0, 50.0))
    sigma = np.sqrt(np.diagonal(run.cov, axis1=1, axis2=2))
    at = {t: round(t * 100) for t in (19.9, 35.0, 49.9, 55.0, 79.9)}
    v_h = sigma[:, 3:5].max(axis=1)
    p_h = sigma[:, 0:2].max(axis=1)
    assert v_h[at[49.9]] > 5 * v_h[at[19.9]]
    assert p_h[at[49.9]] > p_h[at[35.0]] > p_h[at[19.9]]
    assert v_h[at[55.0]] < 0.3 * v_h[at[49.9]]
    # With the DVL back the horizontal position drifts again slowly only (no fix): its growth
    # over the last 25 s is a fraction of the growth over the 30 s without the DVL.
    assert p_h[at[79.9]] - p_h[at[55.0]] < 0.5 * (p_h[at[49.9]] - p_h[at[19.9]])


def test_position_fix_bounds_the_horizontal_position() -> None:
    """Without a seabed (no DVL) the fixes hold the horizontal sigma near their own sigma."""
    fix = run_filter(7, 60.0, _params(seabed=0.0, fix=True))
    drift = run_filter(7, 60.0, _params(seabed=0.0, fix=False))
    s_fix = np.sqrt(fix.cov[-1, 0, 0])
    s_drift = np.sqrt(drift.cov[-1, 0, 0])
    assert s_fix < 0.2
    assert s_drift > 3 * s_fix
    assert abs(fix.error[-1, 0]) < 4 * s_fix


def test_health_reports_dvl_lost_and_growing_covariance_then_recovers() -> None:
    """Diagnostics: DVL lost and covariance growing while the DVL is off; OK once it is back."""
    params = _params(fix=True)
    sensors = NavigationSensors(params, 11)
    ekf = ErrorStateEkf(EstimatorSettings(params))
    monitor = HealthMonitor()
    reports = {}
    for k in range(round(40e9 / STEP_NS)):
        t_ns = k * STEP_NS
        truth = truth_at(t_ns * 1e-9)
        for reading in sensors.sample(t_ns, truth):
            if isinstance(reading, ImuReading) and k == 0:
                ekf.reset_from_ahrs(0, truth.p_ned, reading.rpy)
            elif isinstance(reading, ImuReading):
                ekf.predict(t_ns, reading.w_body, reading.f_body)
                ekf.update_attitude(reading.rpy)
            elif isinstance(reading, DvlReading) and not 10.0 <= t_ns * 1e-9 < 25.0:
                ekf.update_dvl(reading.v_dvl)
            elif isinstance(reading, DepthReading):
                ekf.update_depth(reading.depth_m)
            elif isinstance(reading, PositionFixReading) and not 10.0 <= t_ns * 1e-9 < 25.0:
                ekf.update_position(reading.p_ned)
        if k % 100 == 50:  # 1 Hz, between fixes
            reports[round(t_ns * 1e-9 - 0.5)] = monitor.report(ekf)
    assert reports[8][0] == OK, reports[8]
    level, message, values = reports[20]
    assert level >= WARN and 'DVL lost' in message and 'covariance growing' in message
    assert values['dvl_lost'] and values['covariance_growing']
    assert reports[38][0] == OK


def test_published_covariances_are_those_of_the_filter_at_every_change() -> None:
    """The pose and twist covariances, cached per filter state, equal a fresh computation.

    The estimator publishes them each control period while the filter changes only with a
    reading: after a start from the AHRS (the covariance written in place), a prediction,
    each kind of update and a reset they must be recomputed, and not be writable (a caller
    changing them would change the next period's message).
    """
    ekf = ErrorStateEkf(EstimatorSettings(NavigationParameters()))

    def fresh() -> tuple[np.ndarray, np.ndarray]:
        return ekf._pose_covariance(), ekf._twist_covariance()

    steps = [lambda: ekf.reset(0, [0.0, 0.0, 2.0], [0.1, 0.2, 0.3]),
             lambda: ekf.reset_from_ahrs(0, [0.0, 0.0, 2.0], [0.2, -0.1, 1.0]),
             lambda: ekf.predict(5_000_000, [0.01, 0.02, 0.03], [0.1, 0.0, -9.8]),
             lambda: ekf.update_attitude([0.21, -0.11, 1.01]),
             lambda: ekf.update_depth(2.05),
             lambda: ekf.update_dvl([0.01, 0.0, 0.0]),
             lambda: ekf.update_position([0.1, 0.0, 2.0], [0.5, 0.5, 0.5]),
             lambda: ekf.predict(10_000_000, [0.0, 0.02, 0.0], [0.0, 0.1, -9.8])]
    for step in steps:
        first_pose, first_twist = ekf.pose_covariance(), ekf.twist_covariance()  # cached
        step()
        pose, twist = ekf.pose_covariance(), ekf.twist_covariance()
        want_pose, want_twist = fresh()
        assert np.array_equal(pose, want_pose) and np.array_equal(twist, want_twist)
        assert not np.array_equal(pose, first_pose) or not np.array_equal(twist, first_twist)
        assert ekf.pose_covariance() is pose  # the same period's second read: no work
        with pytest.raises(ValueError):
            pose[0, 0] = 1.0


def test_cross3_is_numpys_cross_bit_for_bit() -> None:
    """The filter's cross product gives the very doubles of ``np.cross`` (nothing reordered)."""
    from uvms_navigation.eskf import cross3

    rng = np.random.default_rng(7)
    for _ in range(20000):
        a = rng.normal(size=3) * 10.0 ** rng.uniform(-9, 4)
        b = rng.normal(size=3) * 10.0 ** rng.uniform(-9, 4)
        assert cross3(a, b).tobytes() == np.cross(a, b).tobytes()
