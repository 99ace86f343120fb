"""BlueROV2 Heavy + Reach Alpha 5: Case I scaled to the arm, and free motion (issue 21).

The whole graph runs with ``robot: bluerov2_alpha5``: a half circle of r = 0.05 m into a wall
of K_e = 1e4 N/m, 20 N tracked along the wall (``bluerov2_alpha5_contact``), and the same path
without a wall (``bluerov2_alpha5_free_motion``). Metrics are those of ``uvms report``, the
force is the simulator's ground truth. The bounds are the issue's acceptance figures, claims
made at ideal devices: since the robot declares its device timing (issue 49), these runs set
``devices.ideal`` (as ``--ideal-devices`` does). With the device timing (the default run),
what holds today is checked too: one contact, the peak within 15 % of the ideal run's
(docs/hardware.md, "Device timing": the force error does not hold yet).
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator

import pytest
from scenario_runs import SCENARIO_DIR, ScenarioResult
from uvms_analysis.metrics import compute_metrics
from uvms_analysis.series import load_run

F_D_N = 20.0
#: Issue 21: the force settles within 5 % of F_d in under 2 s of the first contact.
SETTLING_BOUND_S = 2.0
#: Issue 21: RMS of F - F_d after settling below 5 % of F_d.
RMS_BOUND_N = 0.05 * F_D_N
#: Issue 21: end-effector errors along the wall below 5 mm.
ALONG_WALL_BOUND_M = 5e-3
#: Issue 49: with device timing the peak force within 15 % of the ideal devices' run.
PEAK_BOUND = 0.15
#: Ideal devices: a ROS 2 parameter file for every simulator (rcl's /** matching).
IDEAL_DEVICES = '/**/simulator:\n  ros__parameters:\n    devices:\n      ideal: true\n'
#: ROS domains of these runs (scenario_runs uses 150 and up).
DOMAIN_BASE = 140
RUN_TIMEOUT_S = 600.0


@pytest.fixture(scope='module')
def ideal_runs(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, ScenarioResult]]:
    """The contact and free-motion scenarios with ideal devices, run side by side."""
    directory = tmp_path_factory.mktemp('bluerov2_ideal_devices')
    params = directory / 'ideal_devices.yaml'
    params.write_text(IDEAL_DEVICES, encoding='utf-8')
    names = ('bluerov2_alpha5_contact', 'bluerov2_alpha5_free_motion')
    processes = {}
    for index, name in enumerate(names):
        env = {**os.environ, 'PYTHONPATH': os.pathsep.join(p for p in sys.path if p),
               'ROS_DOMAIN_ID': str(DOMAIN_BASE + index)}
        log = (directory / f'{name}.log').open('wb')
        processes[name] = (subprocess.Popen(
            [sys.executable, '-m', 'uvms_cli.cli', 'run', str(SCENARIO_DIR / f'{name}.yaml'),
             '--output', str(directory / f'{name}.mcap'), '--quiet',
             '--params-file', str(params)],
            stdout=log, stderr=subprocess.STDOUT, env=env), log)
    results = {}
    try:
        for name, (process, log) in processes.items():
            status = process.wait(timeout=RUN_TIMEOUT_S)
            log.close()
            path = directory / f'{name}.mcap'
            if status != 0:
                text = path.with_suffix('.log').read_text(errors='replace')[-2000:]
                pytest.fail(f'uvms run {name} (ideal devices) exited {status}:\n{text}')
            run = load_run(path)
            results[name] = ScenarioResult(name, path, run, compute_metrics(run))
        yield results
    finally:
        for process, log in processes.values():
            if process.poll() is None:
                process.kill()
                process.wait()
            log.close()


@pytest.fixture(scope='module')
def contact_ideal(ideal_runs: dict[str, ScenarioResult]) -> ScenarioResult:
    """bluerov2_alpha5_contact with ideal devices."""
    return ideal_runs['bluerov2_alpha5_contact']


@pytest.fixture(scope='module')
def free_motion_ideal(ideal_runs: dict[str, ScenarioResult]) -> ScenarioResult:
    """bluerov2_alpha5_free_motion with ideal devices."""
    return ideal_runs['bluerov2_alpha5_free_motion']


def test_one_contact_at_the_set_point(contact_ideal: ScenarioResult) -> None:
    """The end effector touches the wall once (no bounce) and the set-point is 20 N."""
    metrics = contact_ideal.metrics
    assert metrics.contact_count == 1
    assert metrics.desired_force is not None
    assert abs(metrics.desired_force - F_D_N) < 0.1


def test_force_settles_within_5_percent_in_under_2_s(
    contact_ideal: ScenarioResult,
) -> None:
    """From the first touch the force enters F_d ± 5 % within 2 s and stays until release."""
    settling = contact_ideal.metrics.settling_time
    assert settling is not None
    assert settling < SETTLING_BOUND_S, f'settling {settling:.3f} s'


def test_force_rms_error_after_settling_is_under_5_percent(
    contact_ideal: ScenarioResult,
) -> None:
    """RMS of F - F_d from settling to release is below 1 N (5 % of 20 N)."""
    rms = contact_ideal.metrics.force_rms_error
    assert rms is not None
    assert rms < RMS_BOUND_N, f'RMS {rms:.3f} N'


def test_end_effector_errors_along_the_wall_are_under_5_mm(
    contact_ideal: ScenarioResult,
) -> None:
    """|Y_d - Y| and |Z_d - Z| stay below 5 mm while in contact."""
    metrics = contact_ideal.metrics
    assert metrics.max_error_y_contact is not None and metrics.max_error_z_contact is not None
    assert metrics.max_error_y_contact < ALONG_WALL_BOUND_M
    assert metrics.max_error_z_contact < ALONG_WALL_BOUND_M


def test_free_motion_tracks_the_half_circle_within_5_mm(
    free_motion_ideal: ScenarioResult,
) -> None:
    """Without a wall the end effector follows the scaled half circle within 5 mm."""
    metrics = free_motion_ideal.metrics
    assert metrics.contact_count == 0
    assert metrics.tracking_error is not None
    assert metrics.tracking_error < ALONG_WALL_BOUND_M, f'{metrics.tracking_error * 1e3:.2f} mm'


def test_with_device_timing_one_contact_and_the_peak_within_15_percent(
    bluerov2_alpha5_contact: ScenarioResult, contact_ideal: ScenarioResult,
) -> None:
    """Device timing (the default): one touch, the peak within 15 % of ideal devices'.

    Issue 49's acceptance; its RMS bound does not hold yet (docs/hardware.md).
    """
    timed, ideal = bluerov2_alpha5_contact.metrics, contact_ideal.metrics
    assert timed.contact_count == 1
    assert timed.peak_force is not None and ideal.peak_force is not None
    assert abs(timed.peak_force - ideal.peak_force) <= PEAK_BOUND * ideal.peak_force, (
        f'peak {timed.peak_force:.2f} N against {ideal.peak_force:.2f} N')
