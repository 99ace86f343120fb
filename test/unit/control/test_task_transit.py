"""A goal whose first waypoint is away from X_d: a transit there, then the goal's own path."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uvms_control.core.law.unified_controller import UnifiedForceController
from uvms_control.core.parameters import ControllerParameters
from uvms_control.core.task.contact_task import ContactTaskGoal, SafetyLimits, TaskCode
from uvms_control.core.task.task_supervisor import TaskSupervisor

from uvms_model import UvmsModel

MODEL = UvmsModel()
Q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.477, -1.511])  # fixed configuration
X = MODEL.ee_position(Q)
DT = 0.002  # control period (s)
# The arm stays at X (fixed configuration): X_d may run far from it here.
LIMITS = SafetyLimits(max_path_speed_m_s=0.2, max_path_acceleration_m_s2=0.5,
                      max_position_error_m=1.0)
OFFSET = np.array([-0.12, 0.05, 0.15])  # path[0] from X (m): 0.198 m away
WAYPOINTS = X + OFFSET + np.array([[0.0, 0.0, 0.0], [0.03, 0.0, 0.0], [0.03, 0.0, 0.04]])
TIMES = np.array([0.0, 1.0, 2.5])
TOLERANCE_M = 1e-3  # below it, no transit (docs/interfaces.md)


def shortest_quintic_s(distance_m: float, speed_m_s: float, acceleration_m_s2: float) -> float:
    """Duration of the rest-to-rest quintic that just meets a speed or acceleration limit (s).

    s(σ) = 10σ³ - 15σ⁴ + 6σ⁵ peaks at 15/8 in ṡ and 10/√3 in s̈ (σ = t/T).
    """
    return max(15.0 / 8.0 * distance_m / speed_m_s,
               math.sqrt(10.0 / math.sqrt(3.0) * distance_m / acceleration_m_s2))


def motion_goal(times: np.ndarray = TIMES) -> ContactTaskGoal:
    """Three waypoints, the first away from X, motion only."""
    return ContactTaskGoal(path=WAYPOINTS, times=times, velocities=None, accelerations=None,
                           normal=np.array([1.0, 0.0, 0.0]), force_n=0.0, force_ramp_s=1.0)


def run(goal: ContactTaskGoal, duration_s: float) -> dict[str, list]:
    """Hold X, submit the goal at the first step, step for duration_s at rest and in free water.

    Returns:
        Per step: t (s), X_d (m), Ẋ_d (m/s), the feedback (TaskProgress or None); the events.
    """
    controller = UnifiedForceController(ControllerParameters.from_flat_dict(), UvmsModel(), DT)
    supervisor = TaskSupervisor(controller, LIMITS)
    seen: dict[str, list] = {'t': [], 'x_d': [], 'v_d': [], 'feedback': [], 'events': []}
    for k in range(round(duration_s / DT)):
        t = k * DT
        result, events = supervisor.step(t, Q, np.zeros(9), np.zeros(3))
        if k == 0:
            seen['events'] += supervisor.submit('goal', goal, t)
        seen['t'].append(t)
        seen['x_d'].append(result.X_d.copy())
        seen['v_d'].append(result.X_dot_d.copy())
        seen['feedback'].append(supervisor.progress())
        seen['events'] += events
    return seen


@pytest.mark.parametrize('first_time_s', [0.0, 0.5], ids=['path-at-time-0', 'path-at-0.5-s'])
def test_a_transit_reaches_the_first_waypoint_then_the_path_runs_shifted_by_it(
        first_time_s: float) -> None:
    """A transit to path[0] first, then every waypoint at its time plus the transit.

    X_d leaves X without a jump, reaches path[0] at rest within the speed limit, then passes
    each waypoint at its time shifted by the transit; the feedback and the result say so.
    """
    times = TIMES + first_time_s
    seen = run(motion_goal(times), 7.0)
    t = np.array(seen['t'])
    x_d, v_d = np.array(seen['x_d']), np.array(seen['v_d'])
    transit_s = shortest_quintic_s(float(np.linalg.norm(OFFSET)), LIMITS.max_path_speed_m_s,
                                   LIMITS.max_path_acceleration_m_s2)
    start = 1 * DT  # the goal starts at the step after its submission
    np.testing.assert_allclose(x_d[1], X, atol=1e-4)  # no jump: X_d starts at the hold point
    for k, time_s in enumerate(times):
        i = int(np.argmin(np.abs(t - (start + transit_s + time_s))))
        np.testing.assert_allclose(x_d[i], WAYPOINTS[k], atol=2e-4)
    end_of_transit = int(np.argmin(np.abs(t - (start + transit_s))))
    np.testing.assert_allclose(x_d[end_of_transit], WAYPOINTS[0], atol=2e-4)
    assert np.linalg.norm(v_d[end_of_transit]) < 1e-3  # at rest on path[0]
    speeds = np.linalg.norm(v_d[:end_of_transit], axis=1)
    assert 0.9 * LIMITS.max_path_speed_m_s < speeds.max() <= LIMITS.max_path_speed_m_s
    feedback = seen['feedback']
    assert feedback[end_of_transit - 5].in_transit
    assert not feedback[end_of_transit + 5].in_transit
    assert feedback[10].transit_s == pytest.approx(transit_s, rel=1e-5)
    (_, ended), = [(e.goal_id, e.result) for e in seen['events']]
    assert ended.code == TaskCode.SUCCEEDED
    assert ended.transit_s == pytest.approx(transit_s, rel=1e-5)


def test_a_first_waypoint_within_the_tolerance_gets_no_transit() -> None:
    """path[0] within 1 mm of X_d: the path starts from X_d at once, as before (no transit)."""
    near, end = X + 0.5 * TOLERANCE_M, X + np.array([0.05, 0.0, 0.0])
    goal = ContactTaskGoal(path=np.array([near, end]),
                           times=np.array([0.0, 2.0]), velocities=None, accelerations=None,
                           normal=np.array([1.0, 0.0, 0.0]), force_n=0.0, force_ramp_s=1.0)
    seen = run(goal, 3.0)
    t, x_d = np.array(seen['t']), np.array(seen['x_d'])
    i = int(np.argmin(np.abs(t - (DT + 2.0))))
    np.testing.assert_allclose(x_d[i], X + np.array([0.05, 0.0, 0.0]), atol=1e-6)
    assert seen['feedback'][10].transit_s == 0.0 and not seen['feedback'][10].in_transit
