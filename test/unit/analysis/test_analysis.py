"""uvms_analysis.series and .metrics: metrics of known signals, and recording loading."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from analysis_recordings import (
    DRIFT_END,
    DT,
    ERROR_CONTACT,
    ERROR_FREE,
    ERROR_STARTUP,
    F_D,
    F_PEAK,
    LOG_OFFSET_NS,
    SETTLING_S,
    T0,
    T_CONTACT,
    T_RELEASE_END,
    TAU,
    YAW_MAX,
)
from scipy.spatial.transform import Rotation
from uvms_analysis.metrics import (
    compute_metrics,
    contact_duration,
    contact_intervals,
    hold,
    overshoot_percent,
    peak,
    rms,
    rotation_angle_from,
    settling_time,
)
from uvms_analysis.series import (
    AnalysisError,
    ContactSeries,
    ControllerSeries,
    Run,
    load_run,
    quaternion_to_rpy,
)


def make_run(
    t: np.ndarray, force_x: np.ndarray, in_contact: np.ndarray, offset: float = 0.0
) -> Run:
    """A Run with ground-truth force ``force_x`` and measured force ``force_x + offset``."""
    n = t.size
    zeros = np.zeros((n, 3))
    force = np.stack([force_x, np.zeros(n), np.zeros(n)], axis=1)
    controller = ControllerSeries(
        t=t,
        W=np.ones(n),
        phase=np.zeros(n, np.uint8),
        F_e=force + np.array([offset, 0.0, 0.0]),
        F_d=np.tile([F_D, 0.0, 0.0], (n, 1)),
        X=zeros,
        X_d=zeros,
        X_dot=zeros,
        X_dot_d=zeros,
        v_e=np.zeros(n),
        F_c=zeros,
        F_IP=zeros,
        F_H=zeros,
    )
    contact = ContactSeries(
        t=t,
        in_contact=in_contact,
        force=force,
        penetration=np.zeros(n),
        wall_position=np.zeros(n),
        wall_velocity=np.zeros(n),
    )
    return Run(name='arrays', controller=controller, contact=contact)


def test_contact_intervals_are_runs_of_consecutive_contact_samples() -> None:
    """Each run of True samples is one half-open index range."""
    flags = np.array([0, 1, 1, 0, 0, 1, 0, 1], dtype=bool)
    assert contact_intervals(flags) == [(1, 3), (5, 6), (7, 8)]


def test_contact_duration_lasts_until_first_sample_out_of_contact() -> None:
    """A bounce counts separately, and contact up to the end lasts to the last sample."""
    t = np.arange(10) * 0.1
    flags = np.array([0, 1, 1, 1, 0, 0, 0, 1, 1, 1], dtype=bool)
    assert contact_duration(t, flags) == pytest.approx(0.3 + 0.2)


@pytest.mark.parametrize('zeta', [0.2, 0.4, 0.6])
def test_overshoot_of_second_order_step_matches_damping_formula(zeta: float) -> None:
    """The peak of an underdamped step overshoots by exp(-π ζ / √(1 - ζ²))."""
    omega = 20.0
    t = np.arange(0.0, 3.0, 1e-4)
    omega_d = omega * math.sqrt(1.0 - zeta**2)
    response = F_D * (
        1.0
        - np.exp(-zeta * omega * t)
        * (np.cos(omega_d * t) + zeta / math.sqrt(1.0 - zeta**2) * np.sin(omega_d * t))
    )
    result = peak(t, response)
    assert result is not None
    expected = 100.0 * math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta**2))
    assert overshoot_percent(result[1], F_D) == pytest.approx(expected, abs=1e-3)
    assert result[0] == pytest.approx(math.pi / omega_d, abs=2e-4)


def test_overshoot_is_zero_when_peak_stays_below_reference() -> None:
    """An overdamped response has no overshoot, not a negative one."""
    assert overshoot_percent(140.0, F_D) == 0.0


@pytest.mark.parametrize('tau', [0.05, 0.3, 1.0])
def test_settling_time_of_first_order_step_is_tau_ln_20(tau: float) -> None:
    """F_d (1 - exp(-t/τ)) enters the 5 % band at τ ln 20 and stays."""
    t = np.arange(0.0, 10.0 * tau + 1.0, 1e-4)
    response = F_D * (1.0 - np.exp(-t / tau))
    result = settling_time(t, response, F_D, 0.0, float(t[-1]))
    assert result == pytest.approx(tau * math.log(20.0), abs=2e-4)


def test_settling_time_is_measured_from_the_start_time() -> None:
    """A response delayed by the time of first contact settles as long after it."""
    t = np.arange(0.0, 8.0, 1e-3)
    response = np.where(t < 3.0, 0.0, F_D * (1.0 - np.exp(-(t - 3.0) / 0.5)))
    result = settling_time(t, response, F_D, 3.0, float(t[-1]))
    assert result == pytest.approx(0.5 * math.log(20.0), abs=1e-3)


def test_settling_time_is_none_when_force_ends_outside_band() -> None:
    """A response that leaves the band at the end of the window has not settled."""
    t = np.arange(0.0, 2.0, 1e-3)
    response = np.where(t < 1.5, F_D, 1.2 * F_D)
    assert settling_time(t, response, F_D, 0.0, float(t[-1])) is None


def test_settling_ignores_a_stay_shorter_than_min_hold() -> None:
    """Crossing the band on the way down during release is not settling."""
    t = np.arange(0.0, 2.0, 1e-3)
    response = np.where(t < 1.95, 1.3 * F_D, F_D)
    assert settling_time(t, response, F_D, 0.0, float(t[-1]), min_hold_s=0.2) is None
    assert settling_time(t, response, F_D, 0.0, float(t[-1]), min_hold_s=0.01) == pytest.approx(
        1.95, abs=1e-3
    )


def test_rms_of_sinusoidal_ripple_is_amplitude_over_root_two() -> None:
    """Whole periods of A sin(ωt) have an RMS of A/√2."""
    t = np.arange(0.0, 2.0, 1e-3)
    assert rms(3.0 * np.sin(2.0 * math.pi * 5.0 * t)) == pytest.approx(3.0 / math.sqrt(2.0))


def test_force_rms_error_covers_the_settled_constrained_phase() -> None:
    """A ripple of amplitude A about F_d from first contact gives an RMS error of A/√2."""
    t = np.arange(0.0, 5.0, 1e-3)
    in_contact = (t >= 1.0) & (t < 4.0)
    ripple = 3.0 * np.sin(2.0 * math.pi * 5.0 * (t - 1.0))
    metrics = compute_metrics(make_run(t, np.where(in_contact, F_D + ripple, 0.0), in_contact))
    assert metrics.settling_time == pytest.approx(0.0)
    assert metrics.force_rms_error == pytest.approx(3.0 / math.sqrt(2.0), rel=1e-3)


def test_impact_peak_is_the_largest_force_within_half_a_second_of_first_contact() -> None:
    """A later, larger peak counts as the run's peak but not as the impact peak."""
    t = np.arange(0.0, 5.0, 1e-3)
    in_contact = t >= 1.0
    force = np.where(in_contact, F_D, 0.0)
    force[np.isclose(t, 1.2)] = 250.0
    force[np.isclose(t, 3.0)] = 280.0
    metrics = compute_metrics(make_run(t, force, in_contact))
    assert metrics.impact_peak_force == pytest.approx(250.0)
    assert metrics.peak_force == pytest.approx(280.0)
    assert metrics.first_contact_time == pytest.approx(1.0)


def test_force_source_controller_uses_the_measured_force() -> None:
    """With force_source='controller' the peak is that of the measured F_e, not ground truth."""
    t = np.arange(0.0, 3.0, 1e-3)
    in_contact = t >= 1.0
    run = make_run(t, np.where(in_contact, F_D, 0.0), in_contact, offset=5.0)
    assert compute_metrics(run, 'contact').peak_force == pytest.approx(F_D)
    assert compute_metrics(run, 'controller').peak_force == pytest.approx(F_D + 5.0)


def test_without_ground_truth_contact_is_measured_force_above_threshold() -> None:
    """With no /uvms/contact, F_e,x > 1 N marks contact and the measured force is used."""
    t = np.arange(0.0, 3.0, 1e-3)
    in_contact = t >= 1.5
    run = replace(make_run(t, np.where(in_contact, F_D, 0.0), in_contact), contact=None)
    metrics = compute_metrics(run)
    assert metrics.force_source == 'controller'
    assert metrics.first_contact_time == pytest.approx(1.5)


def test_negative_set_point_is_measured_in_its_own_direction() -> None:
    """F_d,x = -150 N with F_e,x reaching -180 N is a 20 % overshoot, not a negative one."""
    t = np.arange(0.0, 3.0, 1e-3)
    in_contact = t >= 1.0
    run = make_run(t, np.where(in_contact, -F_D, 0.0), in_contact)
    assert run.contact is not None and run.controller is not None
    run.contact.force[np.isclose(t, 1.1), 0] = -F_PEAK
    run = replace(run, controller=replace(run.controller, F_d=-run.controller.F_d))
    metrics = compute_metrics(run)
    assert metrics.desired_force == pytest.approx(-F_D)
    assert metrics.overshoot == pytest.approx(20.0)


def test_hold_returns_the_latest_sample_at_or_before_each_query() -> None:
    """Zero-order hold, with queries before the first sample taking the first."""
    t = np.array([1.0, 2.0, 3.0])
    values = np.array([10.0, 20.0, 30.0])
    np.testing.assert_array_equal(
        hold(np.array([0.5, 1.0, 1.9, 2.0, 9.0]), t, values), [10.0, 10.0, 10.0, 20.0, 30.0]
    )


@pytest.mark.parametrize('rpy', [(0.0, 0.0, 0.0), (0.3, -0.2, 1.4), (-1.0, 0.5, -3.0)])
def test_quaternion_to_rpy_recovers_zyx_euler_angles(rpy: tuple[float, float, float]) -> None:
    """Roll, pitch, yaw match scipy's intrinsic ZYX Euler angles."""
    quaternion = Rotation.from_euler('ZYX', rpy[::-1]).as_quat()
    np.testing.assert_allclose(quaternion_to_rpy(quaternion)[0], rpy, atol=1e-12)


def test_rotation_angle_from_start_is_the_geodesic_angle() -> None:
    """The attitude excursion equals the magnitude of the relative rotation."""
    start = Rotation.from_euler('ZYX', [0.1, 0.2, -0.3])
    ends = Rotation.from_euler('ZYX', [[0.1, 0.2, -0.3], [0.5, -0.1, 0.2], [-2.0, 0.3, 1.0]])
    expected = (start.inv() * ends).magnitude()
    np.testing.assert_allclose(
        rotation_angle_from(start.as_quat(), ends.as_quat()), expected, atol=1e-9
    )


def test_loaded_series_run_on_header_stamps_from_zero(contact_recording: Path) -> None:
    """The first stamp is t = 0 and samples are DT apart, whatever the log times."""
    run = load_run(contact_recording)
    assert run.time_origin_ns == round(T0 * 1e9)
    assert run.controller is not None
    np.testing.assert_allclose(run.controller.t[:3], [0.0, DT, 2 * DT], atol=1e-12)


def test_log_time_source_uses_mcap_log_times(contact_recording: Path) -> None:
    """With time_source='log' the origin is the earliest log time of the analysis topics."""
    run = load_run(contact_recording, time_source='log')
    assert run.controller is not None
    assert run.time_origin_ns == LOG_OFFSET_NS + round(T0 * 1e9) + 37_000
    assert run.controller.t[0] == pytest.approx(1e-6)


def test_all_analysis_topics_are_loaded(contact_recording: Path) -> None:
    """Controller, contact, odometry, end-effector pose and thruster series are present."""
    run = load_run(contact_recording)
    assert run.contact is not None and run.odometry is not None and run.ee_pose is not None
    assert run.thrusters is not None
    assert run.thrusters.actual_thrust.shape == (run.thrusters.t.size, 8)
    np.testing.assert_allclose(run.odometry.rpy[:, 2].max(), YAW_MAX, rtol=1e-6)


CONTACT_RUN_EXPECTED = [
    ('force_source', 'contact', 0.0),
    ('desired_force', F_D, 1e-9),
    ('first_contact_time', T_CONTACT, 1e-9),
    ('contact_count', 1, 0.0),
    ('contact_duration', T_RELEASE_END - T_CONTACT, 1e-9),
    ('peak_force', F_PEAK, 1e-9),
    ('overshoot', 100.0 * (F_PEAK - F_D) / F_D, 1e-9),
    ('impact_peak_force', F_PEAK, 1e-9),
    ('settling_time', SETTLING_S, DT),
    ('max_error_y_contact', abs(ERROR_CONTACT[1]), 1e-12),
    ('max_error_z_contact', abs(ERROR_CONTACT[2]), 1e-12),
    ('max_error_y', abs(ERROR_STARTUP[1]), 1e-12),
    ('max_error_z', abs(ERROR_STARTUP[2]), 1e-12),
    ('tracking_error', float(np.linalg.norm(ERROR_FREE)), 1e-12),
    ('vehicle_displacement', float(np.linalg.norm(DRIFT_END)), 1e-12),
    ('vehicle_rotation', YAW_MAX, 1e-9),
]


@pytest.mark.parametrize(('name', 'expected', 'tolerance'), CONTACT_RUN_EXPECTED)
def test_contact_run_metric_matches_known_signal(
    contact_recording: Path, name: str, expected: object, tolerance: float
) -> None:
    """Each metric of the recorded contact run equals its construction value."""
    value = getattr(compute_metrics(load_run(contact_recording)), name)
    if isinstance(expected, str):
        assert value == expected
    else:
        assert value == pytest.approx(expected, abs=tolerance)


def test_contact_run_rms_error_matches_integral_of_the_known_error(
    contact_recording: Path,
) -> None:
    """RMS of F_e - F_d from the settling instant to the last in-band sample of the release."""
    metrics = compute_metrics(load_run(contact_recording))
    # Decay 30 exp(-s/τ) from s0 (settled) to s1 (release starts), then the release ramp in
    # the band: the error falls linearly from 0 to -7.5 N in 7.5 N / (750 N/s) = 0.01 s.
    s0, s1 = TAU * math.log(4.0), 4.3 - T_CONTACT - 0.1
    decay = (F_PEAK - F_D) ** 2 * TAU / 2 * (math.exp(-2 * s0 / TAU) - math.exp(-2 * s1 / TAU))
    release = 7.5**2 * 0.01 / 3
    expected = math.sqrt((decay + release) / (s1 - s0 + 0.01))
    assert metrics.force_rms_error == pytest.approx(expected, rel=0.01)


def test_free_motion_run_has_no_force_metrics(free_motion_recording: Path) -> None:
    """Without contact, every force and contact metric is n/a (None)."""
    metrics = compute_metrics(load_run(free_motion_recording))
    assert metrics.contact_count == 0
    for name in (
        'first_contact_time',
        'contact_duration',
        'peak_force',
        'overshoot',
        'impact_peak_force',
        'settling_time',
        'force_rms_error',
        'max_error_y_contact',
        'max_error_z_contact',
    ):
        assert getattr(metrics, name) is None, name


def test_free_motion_run_reports_tracking_error_after_the_first_second(
    free_motion_recording: Path,
) -> None:
    """The start-up error before 1 s is left out of the tracking error."""
    metrics = compute_metrics(load_run(free_motion_recording))
    assert metrics.tracking_error == pytest.approx(float(np.linalg.norm(ERROR_FREE)), abs=1e-12)


def test_run_name_is_the_scenario_of_the_uvms_metadata(contact_recording: Path) -> None:
    """A recording with 'uvms' metadata is named after its scenario."""
    assert load_run(contact_recording).name == 'case1_synthetic'


def test_run_name_falls_back_to_the_file_stem(free_motion_recording: Path) -> None:
    """A recording without metadata is named after its file."""
    assert load_run(free_motion_recording).name == 'free_motion_run'


def test_truncated_recording_loads_the_messages_before_the_cut(
    contact_recording: Path, tmp_path: Path
) -> None:
    """A file cut short by a crash still yields the samples written before the cut."""
    data = contact_recording.read_bytes()
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(data[: len(data) // 2])
    run = load_run(cut)
    full = load_run(contact_recording)
    assert run.controller is not None and full.controller is not None
    assert 0 < run.controller.t.size < full.controller.t.size
    np.testing.assert_array_equal(run.controller.X, full.controller.X[: run.controller.t.size])


def test_truncated_recording_says_what_was_lost(contact_recording: Path, tmp_path: Path) -> None:
    """Run.problem of a cut file names it; a complete file has none."""
    data = contact_recording.read_bytes()
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(data[: len(data) // 2])
    problem = load_run(cut).problem
    assert problem is not None and 'cut.mcap' in problem
    assert load_run(contact_recording).problem is None


def test_file_that_is_not_mcap_raises_analysis_error(tmp_path: Path) -> None:
    """Garbage is reported as an unreadable recording, naming the file."""
    bad = tmp_path / 'bad.mcap'
    bad.write_bytes(b'this is not an mcap file at all')
    with pytest.raises(AnalysisError, match=r'bad\.mcap'):
        load_run(bad)


def test_missing_file_raises_analysis_error(tmp_path: Path) -> None:
    """A path that does not exist is reported as such."""
    with pytest.raises(AnalysisError, match='no such file'):
        load_run(tmp_path / 'absent.mcap')
