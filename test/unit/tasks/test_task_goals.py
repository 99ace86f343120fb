"""Tasks become ContactTask goals in map_ned; results and feedback read as one line."""

from __future__ import annotations

import math

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from uvms_tasks.errors import TaskGoalError
from uvms_tasks.goals import (
    TaskOutcome,
    describe_feedback,
    describe_result,
    describe_task,
    goal_from_task,
    goal_waypoints,
    stamp_from_seconds,
)
from uvms_tasks.task_file import parse_task_document

from uvms_msgs.action import ContactTask

PATH_TASK = {'path': [[1.6, 0, 0.2], [1.7, 0.1, 0.2], [1.7, 0.1, 0.3]],
             'time_from_start_s': [0.5, 2, 4], 'normal': [2, 0, 0], 'force_n': 80,
             'force_ramp_s': 0.5, 'require_contact': True}


def test_path_task_becomes_the_goal_field_by_field() -> None:
    """Waypoints, times, normal (as given), force, ramp, contact; frame map_ned, stamp zero."""
    (task,) = parse_task_document(PATH_TASK, 'test.yaml')
    goal = goal_from_task(task)
    assert goal.header.frame_id == 'map_ned'
    assert (goal.header.stamp.sec, goal.header.stamp.nanosec) == (0, 0)
    np.testing.assert_array_equal(goal_waypoints(goal), PATH_TASK['path'])
    assert list(goal.time_from_start_s) == [0.5, 2.0, 4.0]
    assert (goal.normal.x, goal.normal.y, goal.normal.z) == (2.0, 0.0, 0.0)
    assert goal.force_n == 80.0 and goal.force_ramp_s == 0.5 and goal.require_contact
    assert list(goal.velocity) == [] and list(goal.acceleration) == []


@pytest.mark.parametrize(('t_s', 'sec', 'nanosec'),
                         [(2.5, 2, 500_000_000), (0.0, 0, 0), (12.000000001, 12, 1)])
def test_start_time_is_the_header_stamp(t_s: float, sec: int, nanosec: int) -> None:
    """start_time_s (s on the controller's clock) becomes the stamp, to the nanosecond."""
    (task,) = parse_task_document({**PATH_TASK, 'start_time_s': t_s}, 'test.yaml')
    stamp = goal_from_task(task).header.stamp
    assert (stamp.sec, stamp.nanosec) == (sec, nanosec)
    assert stamp_from_seconds(None).sec == 0


def test_half_circle_goal_starts_at_x0_with_velocities() -> None:
    """A half circle is expanded from X0 with one velocity and acceleration per waypoint."""
    (task,) = parse_task_document(
        {'half_circle': {'duration_s': 20}, 'normal': [1, 0, 0], 'force_n': 150}, 'test.yaml')
    with pytest.raises(TaskGoalError, match='X0'):
        goal_from_task(task)
    goal = goal_from_task(task, (1.6, 0.0, 0.2))
    path = goal_waypoints(goal)
    assert len(path) == len(goal.time_from_start_s) == len(goal.velocity) == 81
    assert len(goal.acceleration) == 81
    np.testing.assert_allclose(path[0], [1.6, 0.0, 0.2])
    np.testing.assert_allclose(path[40], [1.7, 0.0, 0.3])
    assert goal.time_from_start_s[-1] == 20.0


def result(code: int, **fields: float | str) -> ContactTask.Result:
    """A result with the given code and fields."""
    values: dict[str, float | str] = {'contact_time_s': 12.3, 'peak_force_n': 151.24,
                                      'rms_force_error_n': 1.5, 'settling_time_s': 0.8}
    values.update(fields)
    return ContactTask.Result(error_code=code, **values)


def test_success_line_gives_contact_time_peak_rms_and_settling() -> None:
    """SUCCEEDED with the numbers, and an outcome that succeeded."""
    outcome = TaskOutcome('press', GoalStatus.STATUS_SUCCEEDED, result(0))
    assert outcome.succeeded
    assert outcome.describe() == ('press: SUCCEEDED; contact 12.30 s, peak 151.2 N, '
                                  'RMS error 1.50 N, settled in 0.80 s')


def test_failure_line_names_the_status_code_and_reason() -> None:
    """ABORTED (FORCE_LIMIT) with the server's error string; NaN reads as none."""
    line = describe_result(GoalStatus.STATUS_ABORTED, result(
        ContactTask.Result.FORCE_LIMIT, error_string='force 412.0 N > 400.0 N',
        rms_force_error_n=math.nan, settling_time_s=math.nan))
    assert line.startswith('ABORTED (FORCE_LIMIT): force 412.0 N > 400.0 N;')
    assert 'RMS error none' in line and 'settled in none' in line
    assert not TaskOutcome('x', GoalStatus.STATUS_ABORTED, result(3)).succeeded


def test_rejected_and_canceled_goals_read_as_such() -> None:
    """A rejected goal has no result; a canceled one says CANCELED."""
    assert 'REJECTED' in TaskOutcome('x', GoalStatus.STATUS_UNKNOWN, rejected=True).describe()
    canceled = describe_result(GoalStatus.STATUS_CANCELED, result(ContactTask.Result.CANCELED))
    assert canceled.startswith('CANCELED;')


def test_feedback_line_shows_state_phase_weight_force_and_progress() -> None:
    """One line with the names of state and phase."""
    feedback = ContactTask.Feedback(
        phase=ContactTask.Feedback.PHASE_CONSTRAINED, weight=0.04, force_n=149.6,
        force_desired_n=150.0, progress=0.625, state=ContactTask.Feedback.STATE_FOLLOWING)
    line = describe_feedback(feedback)
    for part in ('following', 'constrained', 'W 0.04', '149.6 /  150.0 N', '62.5 %'):
        assert part in line, line


def test_task_summary_line() -> None:
    """What a task asks, in a line of the log."""
    (task,) = parse_task_document({**PATH_TASK, 'start_time_s': 2}, 'test.yaml')
    assert describe_task(task) == 'task: 3 waypoints over 4 s, F_d 80 N, starting at t = 2 s'


def test_client_reads_the_controllers_rejection_line_without_importing_the_controller() -> None:
    """The client's REJECTED_PREFIX is the server's; importing the client loads no core."""
    import os
    import subprocess
    import sys

    from uvms_control.task_server import REJECTED_PREFIX as SERVER_PREFIX
    from uvms_tasks.client import REJECTED_PREFIX

    assert REJECTED_PREFIX == SERVER_PREFIX
    code = ('import sys, uvms_tasks.cli, uvms_tasks.client; heavy = ("uvms_control.task", '
            '"scipy"); print(sorted(m for m in sys.modules if m.startswith(heavy)))')
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join(p for p in sys.path if p)}
    loaded = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                            check=True, env=env)
    assert loaded.stdout.strip() == '[]', loaded.stdout
