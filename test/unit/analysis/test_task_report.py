"""A task's result and its row of `uvms report` are the same figures (one function, one trace)."""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from rclpy.serialization import serialize_message
from uvms_analysis.metrics import task_metrics
from uvms_analysis.series import load_run
from uvms_control.core.task.contact_task import ContactTaskGoal, TaskCode, TaskFigures, TaskResult
from uvms_control.task_conversions import contact_task_record, unit_normal
from uvms_recording.mcap_writer import McapRecorder
from uvms_recording.typestore import uvms_typestore

from uvms_analysis import report

DT = 0.002  # control period (s)
T0_NS = 50 * 10**9  # stamp of the first controller state (ns)
THRESHOLD_N = 5.0  # the controller's contact threshold (N)
RAMP_S = 1.0


@dataclass(frozen=True)
class SyntheticTask:
    """A task over steps [first, last] of the trace: contact at t_contact, release at t_release."""

    goal_id: bytes
    force_n: float
    normal: tuple[float, float, float]
    first: int
    last: int
    t_contact: float
    t_release: float
    bounce: bool


TASKS = (
    SyntheticTask(bytes(range(16)), 150.0, (1.0, 0.0, 0.0), 0, 2999, 1.0, 4.5, False),
    SyntheticTask(bytes(range(100, 116)), 80.0, (1.0, 0.0, 0.2), 3500, 6499, 8.0, 11.5, True),
)
STEPS = 7000


def normal_force(task: SyntheticTask, t: float, rng: np.random.Generator) -> float:
    """Force along the normal (N): an impact overshoot decaying onto F_d, noise, a release."""
    s = t - task.t_contact
    if s < 0.0 or t >= task.t_release + 0.5:
        return 0.0
    if task.bounce and 0.1 <= s < 0.15:
        return 0.0  # the end effector bounces off once
    if s < 0.05:
        return 1.2 * task.force_n * s / 0.05
    noise = rng.normal(0.0, 0.005 * task.force_n)
    force = task.force_n * (1.0 + 0.2 * np.exp(-(s - 0.05) / 0.1)) + noise
    if t >= task.t_release:
        force *= 1.0 - (t - task.t_release) / 0.5
    return float(force)


def goal(task: SyntheticTask) -> ContactTaskGoal:
    """The task as the controller's goal (only force and normal matter to the figures)."""
    return ContactTaskGoal(np.zeros((2, 3)), np.array([0.0, 1.0]), None, None,
                           np.array(task.normal), task.force_n, RAMP_S)


def run_tasks(path: Path) -> list[TaskResult]:
    """Feed each task's steps to its figures as the supervisor does; record states and records.

    Returns each task's result; the recording holds /uvms/controller/state at every step and
    each task's /uvms/controller/task_record, as the graph records them.
    """
    ts = uvms_typestore()
    T = ts.types
    rng = np.random.default_rng(3)
    recorder = McapRecorder(path)
    recorder.add_topic('/uvms/controller/state', 'uvms_msgs/msg/ControllerState')
    recorder.add_topic('/uvms/controller/task_record', 'uvms_msgs/msg/ContactTaskRecord')
    zero = T['geometry_msgs/msg/Vector3'](x=0.0, y=0.0, z=0.0)
    point = T['geometry_msgs/msg/Point'](x=1.7, y=0.0, z=0.0)
    figures = [TaskFigures(task.force_n) for task in TASKS]
    results: list[TaskResult] = []
    for k in range(STEPS):
        t_ns = T0_NS + k * DT * 1e9
        t_ns = round(t_ns)
        t = t_ns * 1e-9  # as the controller node turns a stamp into its time
        running = next((i for i, task in enumerate(TASKS) if task.first <= k <= task.last), None)
        f_e = np.zeros(3)
        if running is not None:
            task = TASKS[running]
            n = unit_normal(goal(task))
            # along the normal, plus a tangential push that the normal force must leave out
            f_e = normal_force(task, t - T0_NS * 1e-9, rng) * n + np.array([0.0, 3.0, 0.0])
            f_normal = float(n @ f_e)
            rel = t - T0_NS * 1e-9 - task.t_contact
            figures[running].update(t, DT, f_normal, f_normal >= THRESHOLD_N,
                                    RAMP_S <= rel < task.t_release - task.t_contact)
        header = T['std_msgs/msg/Header'](
            stamp=T['builtin_interfaces/msg/Time'](sec=t_ns // 10**9, nanosec=t_ns % 10**9),
            frame_id='map_ned')
        state = T['uvms_msgs/msg/ControllerState'](
            header=header, weight=1.0, phase=0,
            contact_force=T['geometry_msgs/msg/Vector3'](x=f_e[0], y=f_e[1], z=f_e[2]),
            desired_force=zero, position=point, desired_position=point, velocity=zero,
            desired_velocity=zero, normal_velocity=0.0, impedance_force=zero,
            hybrid_force=zero, command_force=zero)
        recorder.write('/uvms/controller/state',
                       bytes(ts.serialize_cdr(state, state.__msgtype__)), t_ns)
        if running is not None and k == TASKS[running].last:
            task = TASKS[running]
            result = figures[running].result(TaskCode.SUCCEEDED, 'path done')
            results.append(result)
            record = contact_task_record(task.goal_id, goal(task), result, THRESHOLD_N)
            assert record is not None
            recorder.write('/uvms/controller/task_record', serialize_message(record), t_ns)
    recorder.close()
    return results


@pytest.fixture(scope='module')
def two_tasks(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[TaskResult]]:
    """A recording of two tasks and their results."""
    path = tmp_path_factory.mktemp('tasks') / 'two_tasks.mcap'
    return path, run_tasks(path)


def test_recording_of_two_tasks_gives_one_report_row_per_task(
    two_tasks: tuple[Path, list[TaskResult]], capsys: pytest.CaptureFixture[str]
) -> None:
    """Two task records: two rows, each with the task's goal id and its force_n as F_d."""
    path, _ = two_tasks
    assert report.main([str(path), '--format', 'csv']) == 0
    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert [row['task'] for row in rows] == [task.goal_id.hex() for task in TASKS]
    assert [float(row['desired_force_N']) for row in rows] == [task.force_n for task in TASKS]
    assert [row['force_source'] for row in rows] == ['controller', 'controller']
    assert [row['contact_count'] for row in rows] == ['1', '2']


def test_each_report_row_has_its_tasks_result_figures_to_the_digit(
    two_tasks: tuple[Path, list[TaskResult]], capsys: pytest.CaptureFixture[str]
) -> None:
    """Contact time, peak, settling time and RMS error of each row print as its result's."""
    path, results = two_tasks
    assert report.main([str(path), '--format', 'csv']) == 0
    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    for row, result in zip(rows, results, strict=True):
        assert row['contact_duration_s'] == f'{result.contact_time_s:.6g}'
        assert row['peak_force_N'] == f'{result.peak_force_n:.6g}'
        assert row['settling_time_s'] == f'{result.settling_time_s:.6g}'
        assert row['force_rms_error_N'] == f'{result.rms_force_error_n:.6g}'


def test_task_metrics_equal_the_result_beyond_the_printed_digits(
    two_tasks: tuple[Path, list[TaskResult]]
) -> None:
    """The same samples through the same function: equal up to the time base's rounding.

    The settling is not bounded below by the 1 s ramp: the force is in the band 0.1 to 0.3 s
    after first contact.
    """
    path, results = two_tasks
    run = load_run(path)
    assert len(run.tasks) == 2
    for record, result in zip(run.tasks, results, strict=True):
        metrics = task_metrics(run, record)
        assert metrics.contact_duration == pytest.approx(result.contact_time_s, rel=1e-12)
        assert metrics.peak_force == result.peak_force_n
        assert metrics.settling_time == pytest.approx(result.settling_time_s, rel=1e-9)
        assert metrics.force_rms_error == pytest.approx(result.rms_force_error_n, rel=1e-12)
        assert 0.05 < result.settling_time_s < RAMP_S


def test_task_row_takes_the_ground_truth_by_default_as_the_figures_do(
    two_tasks: tuple[Path, list[TaskResult]]
) -> None:
    """Ground truth recorded: 'auto' is 'contact' (one set of figures); 'controller' = result."""
    from dataclasses import replace

    from uvms_analysis.series import ContactSeries

    path, results = two_tasks
    run = load_run(path)
    t = run.controller.t
    # A wall that measures 10 % more than the controller's F_e: a figure tells them apart.
    force = 1.1 * run.controller.F_e
    contact = ContactSeries(t, force[:, 0] >= THRESHOLD_N, force, np.zeros(t.size),
                            np.zeros(t.size), np.zeros(t.size))
    run = replace(run, contact=contact)
    for record, result in zip(run.tasks, results, strict=True):
        default = task_metrics(run, record)
        truth = task_metrics(run, record, 'contact')
        assert (default.force_source, default.peak_force) == ('contact', truth.peak_force)
        assert default.peak_force == pytest.approx(1.1 * result.peak_force_n)
        controller = task_metrics(run, record, 'controller')
        assert (controller.force_source, controller.peak_force) == ('controller',
                                                                    result.peak_force_n)
