"""BlueROV2 Heavy + Reach Alpha 5: Case I scaled to the arm, and free motion (issue 21).

The whole graph runs with ``robot: bluerov2_alpha5``: a half circle of r = 0.05 m into a wall
of K_e = 1e4 N/m, 20 N tracked along the wall (``bluerov2_alpha5_contact``), and the same path
without a wall (``bluerov2_alpha5_free_motion``). Metrics are those of ``uvms report``, the
force is the simulator's ground truth. The bounds are the issue's acceptance figures.

The claims are made at ideal devices, the simulator's default for now (the robot's
device_timing.yaml holds ``devices.ideal: true``: with the controller's held-slot keys the twin
stand's default launch aborts, docs/hardware.md "Making it the default"). With the robot's
device timing and the controller's device-timing file issue 49's acceptance is checked: on the
contact (noise-free wrist sensor, as the scenario's) one contact, mid-contact RMS force error
at most 1.3x the ideal run's, the peak within 15 %; the free motion with the wrist sensor's
0.1 % noise within the same 5 mm as at ideal devices.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from scenario_runs import SCENARIO_DIR, SCENARIO_DOMAINS, ScenarioResult
from uvms_analysis.metrics import compute_metrics, contact_intervals, hold
from uvms_analysis.series import Run, load_run

from uvms_description import robots_directory

F_D_N = 20.0
#: Issue 21: the force settles within 5 % of F_d in under 2 s of the first contact.
SETTLING_BOUND_S = 2.0
#: Issue 21: RMS of F - F_d after settling below 5 % of F_d.
RMS_BOUND_N = 0.05 * F_D_N
#: Issue 21: end-effector errors along the wall below 5 mm.
ALONG_WALL_BOUND_M = 5e-3
#: Issue 49: with device timing the peak force within 15 % of the ideal devices' run.
PEAK_BOUND = 0.15
#: Issue 49: with device timing the mid-contact RMS force error at most 1.3x the ideal run's.
RMS_RATIO_BOUND = 1.3
#: The robot's device timing applied: a ROS 2 parameter file for every simulator.
DEVICE_TIMING = '/**/simulator:\n  ros__parameters:\n    devices:\n      ideal: false\n'
#: The controller at the devices' rates (arm.command_rate_hz, arm.force_latency_s).
CONTROLLER_TIMING = robots_directory() / 'bluerov2_alpha5' / 'controller_device_timing.yaml'
#: ROS domain of the device-timed run: the last of the lane's (scenario_runs counts up from the
#: first; domains above 100 have their ports in Linux's ephemeral range).
DOMAIN = SCENARIO_DOMAINS[1]
RUN_TIMEOUT_S = 600.0


def test_one_contact_at_the_set_point(bluerov2_alpha5_contact: ScenarioResult) -> None:
    """The end effector touches the wall once (no bounce) and the set-point is 20 N."""
    metrics = bluerov2_alpha5_contact.metrics
    assert metrics.contact_count == 1
    assert metrics.desired_force is not None
    assert abs(metrics.desired_force - F_D_N) < 0.1


def test_force_settles_within_5_percent_in_under_2_s(
    bluerov2_alpha5_contact: ScenarioResult,
) -> None:
    """From the first touch the force enters F_d ± 5 % within 2 s and stays until release."""
    settling = bluerov2_alpha5_contact.metrics.settling_time
    assert settling is not None
    assert settling < SETTLING_BOUND_S, f'settling {settling:.3f} s'


def test_force_rms_error_after_settling_is_under_5_percent(
    bluerov2_alpha5_contact: ScenarioResult,
) -> None:
    """RMS of F - F_d from settling to release is below 1 N (5 % of 20 N)."""
    rms = bluerov2_alpha5_contact.metrics.force_rms_error
    assert rms is not None
    assert rms < RMS_BOUND_N, f'RMS {rms:.3f} N'


def test_end_effector_errors_along_the_wall_are_under_5_mm(
    bluerov2_alpha5_contact: ScenarioResult,
) -> None:
    """|Y_d - Y| and |Z_d - Z| stay below 5 mm while in contact."""
    metrics = bluerov2_alpha5_contact.metrics
    assert metrics.max_error_y_contact is not None and metrics.max_error_z_contact is not None
    assert metrics.max_error_y_contact < ALONG_WALL_BOUND_M
    assert metrics.max_error_z_contact < ALONG_WALL_BOUND_M


def test_free_motion_tracks_the_half_circle_within_5_mm(
    bluerov2_alpha5_free_motion: ScenarioResult,
) -> None:
    """Without a wall the end effector follows the scaled half circle within 5 mm."""
    metrics = bluerov2_alpha5_free_motion.metrics
    assert metrics.contact_count == 0
    assert metrics.tracking_error is not None
    assert metrics.tracking_error < ALONG_WALL_BOUND_M, f'{metrics.tracking_error * 1e3:.2f} mm'


def run_device_timed(name: str, directory: Path) -> ScenarioResult:
    """Scenario ``name`` with the robot's device timing and the controller's file."""
    params = directory / 'device_timing.yaml'
    params.write_text(DEVICE_TIMING, encoding='utf-8')
    path = directory / f'{name}.mcap'
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join(p for p in sys.path if p),
           'ROS_DOMAIN_ID': str(DOMAIN)}
    result = subprocess.run(
        [sys.executable, '-m', 'uvms_cli.cli', 'run',
         str(SCENARIO_DIR / f'{name}.yaml'), '--output', str(path), '--quiet',
         '--params-file', str(params), '--params-file', str(CONTROLLER_TIMING)],
        capture_output=True, text=True, env=env, timeout=RUN_TIMEOUT_S, check=False)
    if result.returncode != 0:
        pytest.fail(f'uvms run {name} (device timing) exited {result.returncode}:\n'
                    f'{(result.stdout + result.stderr)[-2000:]}')
    run = load_run(path)
    return ScenarioResult(name, path, run, compute_metrics(run))


@pytest.fixture(scope='module')
def contact_device_timed(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ScenarioResult]:
    """bluerov2_alpha5_contact with the robot's device timing and the controller's file."""
    yield run_device_timed('bluerov2_alpha5_contact',
                           tmp_path_factory.mktemp('bluerov2_device_timing'))


@pytest.fixture(scope='module')
def free_motion_device_timed(
    tmp_path_factory: pytest.TempPathFactory,
) -> Iterator[ScenarioResult]:
    """bluerov2_alpha5_free_motion (0.1 % wrist noise) with the robot's device timing."""
    yield run_device_timed('bluerov2_alpha5_free_motion',
                           tmp_path_factory.mktemp('bluerov2_device_timing_free'))


def test_with_device_timing_and_the_wrist_noise_free_motion_tracks_within_5_mm(
    free_motion_device_timed: ScenarioResult,
) -> None:
    """The held-slot prediction with the wrist sensor's 0.1 % noise: the path within 5 mm.

    Measured 3.38 mm (ideal devices 2.80 mm). The quadratic alone through the last three force
    samples (held_command before its noise weighting) amplified the noise 33 times: the arm
    diverged at 3.8 s; cancelling each noisy sample held over a slot: 7.09 mm.
    """
    metrics = free_motion_device_timed.metrics
    assert metrics.contact_count == 0
    assert metrics.tracking_error is not None
    assert metrics.tracking_error < ALONG_WALL_BOUND_M, f'{metrics.tracking_error * 1e3:.2f} mm'


def mid_contact_rms_error(run: Run) -> float:
    """RMS of F - F_d (N, ground truth) over the middle half of the first contact.

    The middle half leaves out the touch and the release: what is left is how the force loop
    holds between them.
    """
    contact = run.contact
    (start, end), *_ = contact_intervals(np.asarray(contact.in_contact, dtype=bool))
    t0, t1 = contact.t[start], contact.t[end - 1]
    middle = (contact.t >= t0 + 0.25 * (t1 - t0)) & (contact.t <= t0 + 0.75 * (t1 - t0))
    desired = hold(contact.t[middle], run.controller.t, run.controller.F_d[:, 0])
    return float(np.sqrt(np.mean((contact.force[middle, 0] - desired) ** 2)))


def test_with_device_timing_one_contact_rms_within_1_3x_and_peak_within_15_percent(
    contact_device_timed: ScenarioResult, bluerov2_alpha5_contact: ScenarioResult,
) -> None:
    """Issue 49's acceptance: the device-timed run against the ideal devices' run.

    One touch, mid-contact RMS force error at most 1.3x the ideal run's (measured 0.0123 N
    against 0.0113 N), the peak within 15 % (20.08 N against 20.10 N).
    """
    timed, ideal = contact_device_timed.metrics, bluerov2_alpha5_contact.metrics
    assert timed.contact_count == 1
    assert timed.peak_force is not None and ideal.peak_force is not None
    assert abs(timed.peak_force - ideal.peak_force) <= PEAK_BOUND * ideal.peak_force, (
        f'peak {timed.peak_force:.2f} N against {ideal.peak_force:.2f} N')
    rms_timed = mid_contact_rms_error(contact_device_timed.run)
    rms_ideal = mid_contact_rms_error(bluerov2_alpha5_contact.run)
    assert rms_timed <= RMS_RATIO_BOUND * rms_ideal, (
        f'mid-contact RMS {rms_timed:.4f} N against {rms_ideal:.4f} N')
