"""A task's result code says whether it did its job (issue 42, item 1).

The supervisor runs at a fixed configuration with chosen sensor forces (as
test_supervisor_findings.py does): a press whose force never enters its band ends
FORCE_NOT_SETTLED with its figures; one that settles ends SUCCEEDED.
"""

from __future__ import annotations

import math

import numpy as np
from test_supervisor_findings import DT, N, Run, goal
from uvms_control.core.task.contact_task import TaskCode
from uvms_control.core.task.task_states import TaskEvent


def press(force_n: float, seconds: float = 3.0) -> TaskEvent:
    """F_d = 100 N over a 1 s path; the sensor reads force_n along N until the path's end."""
    run = Run()
    run.step()
    run.supervisor.submit('press', goal(force_n=100.0), run.t)
    run.run(0.1)
    run.run(1.0, force_n * N)
    for _ in range(round(seconds / DT)):
        run.step()
        if run.events:
            break
    assert len(run.events) == 1, run.codes()
    return run.events[0][1]


def test_press_whose_force_never_enters_its_band_ends_force_not_settled() -> None:
    """60 N against F_d = 100 N: contact made, never within 5 %: not SUCCEEDED."""
    result = press(60.0).result
    assert result.code == TaskCode.FORCE_NOT_SETTLED, result.message
    assert 'never stayed within 5% of F_d = 100 N' in result.message
    assert math.isnan(result.settling_time_s)
    assert result.contact_time_s > 0.9
    np.testing.assert_allclose(result.peak_force_n, 60.0)


def test_press_whose_force_settles_succeeds() -> None:
    """100 N from first contact: settled at once, SUCCEEDED."""
    result = press(100.0).result
    assert result.code == TaskCode.SUCCEEDED, result.message
    assert result.settling_time_s == 0.0


def test_motion_only_task_with_contact_succeeds_without_settling() -> None:
    """force_n = 0: no band to settle in; a path done is the task done."""
    run = Run()
    run.step()
    run.supervisor.submit('move', goal(force_n=0.0), run.t)
    run.run(1.2, 20.0 * N)
    run.run(2.0)
    assert run.codes() == [('move', TaskCode.SUCCEEDED)]


def test_a_task_waiting_for_its_stamp_counts_no_figures_before_it_starts() -> None:
    """A goal stamped 1 s ahead, sent while the arm still presses: its figures start at t0.

    The force of the task it preempts (still on while it waits) is not its contact: its
    contact time and settling count from its own start (issue 42: a preempting task
    reported "settled in 7.70 s").
    """
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(force_n=100.0, duration_s=3.0), run.t)
    run.run(1.0, 100.0 * N)
    t0 = run.t + 1.0
    [preempted] = run.supervisor.submit('b', goal(start_time_s=t0, force_n=100.0), run.t)
    assert (preempted.goal_id, preempted.result.code) == ('a', TaskCode.PREEMPTED)
    run.run(1.0, 100.0 * N)  # b waits for its stamp; a's force is still measured
    run.run(1.0, 100.0 * N)  # b follows its path, pressing from its start
    for _ in range(round(3.0 / DT)):
        run.step()
        if run.events:
            break
    [(_, b)] = run.events
    assert (b.goal_id, b.result.code) == ('b', TaskCode.SUCCEEDED), b.result.message
    assert b.result.start_s >= t0 - 1e-9
    assert b.result.contact_time_s < 1.0 + 2 * DT
