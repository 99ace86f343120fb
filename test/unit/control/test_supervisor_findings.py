"""Regression tests of issue 28's findings in the task supervisor (core half), one or more each.

Closed-loop tests run the supervisor on the real controller and the paper's UVMS against the
Case I wall (K_e = 1e4 N/m) at 500 Hz (``closed_loop_plant.Loop``); the others feed a fixed
configuration with chosen sensor values, as test_task_supervisor.py does.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pytest
from closed_loop_plant import Loop, press_goal
from uvms_control.core.law.unified_controller import ControllerResult, UnifiedForceController
from uvms_control.core.parameters import ControllerParameters
from uvms_control.core.task.contact_task import ContactTaskGoal, SafetyLimits, TaskCode
from uvms_control.core.task.task_supervisor import SupervisorState, TaskEvent, TaskSupervisor

from uvms_model import UvmsModel

MODEL = UvmsModel()
Q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.477, -1.511])  # fixed configuration
X = MODEL.ee_position(Q)
ROT_NED_FROM_EE = MODEL.ee_rotation(Q)
N = np.array([1.0, 0.0, 0.0])
DT = 0.01
LIMITS = SafetyLimits(max_contact_force_n=150.0, sensor_range_n=1000.0)
THRESHOLD_N = 5.0  # the paper robot's force.contact_threshold_n


def goal(start_time_s: float | None = None, force_n: float = 100.0,
         normal: np.ndarray = N, distance_m: float = 0.02,
         duration_s: float = 1.0) -> ContactTaskGoal:
    """Move distance_m along normal over duration_s, pressing force_n (ramp 0.5 s)."""
    return ContactTaskGoal(path=np.array([X, X + distance_m * normal]),
                           times=np.array([0.0, duration_s]), velocities=None,
                           accelerations=None, normal=normal, force_n=force_n,
                           force_ramp_s=0.5, start_time_s=start_time_s)


class Run:
    """A supervisor stepped at DT at the fixed Q with a chosen force (N, map_ned)."""

    def __init__(self, limits: SafetyLimits = LIMITS) -> None:
        controller = UnifiedForceController(ControllerParameters.from_flat_dict(), UvmsModel())
        self.supervisor = TaskSupervisor(controller, limits)
        self.k = 0
        self.q = Q
        self.events: list[tuple[float, TaskEvent]] = []

    @property
    def t(self) -> float:
        """Time of the next step (s)."""
        return self.k * DT

    def step(self, force_ned: np.ndarray | None = None) -> ControllerResult:
        """One step with this contact force (map_ned)."""
        force = np.zeros(3) if force_ned is None else force_ned
        rot = MODEL.ee_rotation(self.q)
        result, events = self.supervisor.step(self.t, self.q, np.zeros(9), rot.T @ force)
        self.events += [(self.t, event) for event in events]
        self.k += 1
        return result

    def run(self, duration_s: float, force_ned: np.ndarray | None = None
            ) -> list[ControllerResult]:
        """Step for duration_s (s)."""
        return [self.step(force_ned) for _ in range(round(duration_s / DT))]

    def codes(self) -> list[tuple[object, TaskCode]]:
        """(goal id, code) of every result so far."""
        return [(event.goal_id, event.result.code) for _, event in self.events]


# ---------------------------------------------------------------------------- finding 1


def test_f1_preemption_by_a_waiting_goal_releases_the_pressing_goal() -> None:
    """Finding 1: the preempted goal's force ramps down and the contact is let go.

    A 100 N press preempted by a goal stamped 20 s ahead kept pressing 100 N; now F_d is zero
    after retreat_time_s and the wall force falls under the contact threshold, while the new
    goal waits; its cancel ends it at the next step.
    """
    loop = Loop(LIMITS)
    loop.step()
    loop.supervisor.submit('press', press_goal(), loop.t)
    loop.run(4.0)
    assert loop.contact_force() > 80.0
    events = loop.supervisor.submit('later', press_goal(start_time_s=loop.t + 20.0), loop.t)
    assert [(e.goal_id, e.result.code) for e in events] == [('press', TaskCode.PREEMPTED)]
    after = loop.run(LIMITS.retreat_time_s + 1.0)
    assert after[-1].F_d.tolist() == [0.0, 0.0, 0.0]
    assert loop.contact_force() < THRESHOLD_N
    assert loop.supervisor.state == SupervisorState.WAITING
    assert loop.supervisor.cancel('later')
    loop.step()
    assert [(e.goal_id, e.result.code) for _, e in loop.events] == [('later', TaskCode.CANCELED)]


def test_f1_stamp_too_far_ahead_is_refused_naming_header_stamp() -> None:
    """Finding 1: a wall-clock stamp against a sim-time controller (54 years ahead) is refused."""
    run = Run()
    run.step()
    [event] = run.supervisor.submit('a', goal(start_time_s=1.7e9), run.t)
    assert event.result.code == TaskCode.INVALID_GOAL
    assert event.result.message.startswith('header.stamp = ')
    assert 'safety.max_goal_delay_s = 60.0 s' in event.result.message
    assert run.supervisor.submit('b', goal(start_time_s=run.t + 59.0), run.t) == []


def test_f1_force_limit_applies_while_a_goal_waits() -> None:
    """Finding 1: 400 N against a 150 N limit while a goal waits ends it FORCE_LIMIT."""
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(start_time_s=run.t + 10.0), run.t)
    run.step(400.0 * N)
    assert run.supervisor.controller.task.path is not None  # backing off, not waiting
    run.run(LIMITS.retreat_time_s + 2 * DT)
    assert run.codes() == [('a', TaskCode.FORCE_LIMIT)]
    assert run.supervisor.state == SupervisorState.HOLD


# ---------------------------------------------------------------------------- finding 2


def test_f2_goal_before_the_first_step_after_reactivation_is_queued() -> None:
    """Finding 2: deactivate, activate and a goal before the first step raised in the step."""
    run = Run()
    run.run(0.1)
    run.supervisor.abort_all(TaskCode.INACTIVE, 'deactivated')
    run.supervisor.controller.reset()
    assert run.supervisor.reset() == []
    assert run.supervisor.submit('a', goal(), run.t) == []
    run.run(0.2)
    assert run.codes() == []
    assert run.supervisor.state == SupervisorState.FOLLOWING


def test_f2_contact_threshold_raised_above_a_waiting_goals_force() -> None:
    """Finding 2: a threshold above a waiting goal's force ends it INVALID_GOAL, no exception."""
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(start_time_s=run.t + 0.2), run.t)
    run.supervisor.controller.task.set_contact_threshold(150.0)
    run.run(0.4)
    [(goal_id, code)] = run.codes()
    assert (goal_id, code) == ('a', TaskCode.INVALID_GOAL)
    assert 'force_n = 100.0' in run.events[0][1].result.message


# ---------------------------------------------------------------------------- finding 3


@pytest.mark.parametrize(('normal', 'force_ned'), [
    (-N, 600.0 * N),  # a reversed normal: n·F_e = -600 N
    (N, 900.0 * np.array([0.0, 1.0, 0.0])),  # sideways
    (N, -600.0 * N),  # pulling
])
def test_f3_force_limit_on_the_magnitude_of_f_e(normal: np.ndarray,
                                                force_ned: np.ndarray) -> None:
    """Finding 3: |F_e| beyond the limit ends the task FORCE_LIMIT whatever its direction.

    The retreat moves against the measured force (off the surface actually pressed), not along
    -n: with the reversed normal the old cancel 'backed off' into the hull.
    """
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(normal=normal, force_n=0.0), run.t)
    run.run(0.2)
    breach = run.step(force_ned)
    assert run.supervisor.breach is not None and '|F_e|' in run.supervisor.breach
    assert run.supervisor.state == SupervisorState.RETREATING
    path = run.supervisor.controller.task.path
    assert path is not None
    away = -force_ned / np.linalg.norm(force_ned)
    np.testing.assert_allclose(path.points[-1], breach.X + LIMITS.retreat_m * away, atol=1e-12)
    run.run(LIMITS.retreat_time_s + 2 * DT)
    assert run.codes() == [('a', TaskCode.FORCE_LIMIT)]


# ---------------------------------------------------------------------------- finding 4


def test_f4_retreat_is_protected_and_keeps_its_code() -> None:
    """Finding 4: a goal during a FORCE_LIMIT retreat is refused; the breach code survives."""
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(), run.t)
    run.run(0.3, 100.0 * N)
    run.step(160.0 * N)
    [refused] = run.supervisor.submit('b', goal(), run.t)
    assert refused.result.code == TaskCode.INVALID_GOAL
    assert refused.result.message.startswith('refused: the arm is retreating')
    run.run(LIMITS.retreat_time_s + 2 * DT)
    assert run.codes() == [('a', TaskCode.FORCE_LIMIT)]


def test_f4_breach_during_a_retreat_goes_to_safe_hold_until_reset() -> None:
    """Finding 4: a force growing during the retreat: SAFE_HOLD, F_d = 0, X_d = X at rest."""
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(), run.t)
    run.run(0.7, 100.0 * N)
    run.step(160.0 * N)
    run.run(0.1, 160.0 * N)
    run.step(250.0 * N)  # beyond 1.25 x 160 N: the back-off is not working
    assert run.supervisor.safe_hold
    assert run.codes() == [('a', TaskCode.FORCE_LIMIT)]
    assert run.events[0][1].result.message.startswith('safe hold: ')
    for result in run.run(1.0, 250.0 * N):  # from the step after the one that saw it
        assert result.F_d.tolist() == [0.0, 0.0, 0.0]
        assert result.X_dot_d.tolist() == [0.0, 0.0, 0.0]
    np.testing.assert_allclose(result.X_d, X, atol=1e-12)
    assert run.supervisor.breach is not None and run.supervisor.breach.startswith('safe hold')
    [refused] = run.supervisor.submit('b', goal(), run.t)
    assert 'safe hold' in refused.result.message
    assert 'clear it with `uvms lifecycle controller reset`' in refused.result.message
    run.supervisor.reset()
    run.step()
    assert run.supervisor.state == SupervisorState.HOLD and run.supervisor.breach is None


def test_f4_cancel_retreats_from_the_measured_position_at_rest() -> None:
    """Finding 4: a cancel at speed no longer carries X_d further along the path."""
    run = Run(replace(LIMITS, max_position_error_m=1.0))
    run.step()
    run.supervisor.submit('a', goal(force_n=0.0, distance_m=0.3, duration_s=2.0), run.t)
    moving = run.run(1.0)[-1]
    assert float(N @ moving.X_dot_d) > 0.2  # X_d runs ahead of the fixed X
    run.supervisor.cancel('a')
    retreat = run.run(LIMITS.retreat_time_s + 2 * DT)
    np.testing.assert_allclose(retreat[0].X_d, X, atol=1e-12)
    np.testing.assert_allclose(retreat[0].X_dot_d, 0.0, atol=1e-12)
    assert max(float(N @ (result.X_d - X)) for result in retreat) <= 1e-12
    assert run.codes() == [('a', TaskCode.CANCELED)]


def test_f4_tracking_limit_on_a_fast_path_does_not_swing_x_d() -> None:
    """Finding 4: after TRACKING_LIMIT X_d stays within retreat_m of the measured X."""
    run = Run(replace(LIMITS, max_position_error_m=0.05))
    run.step()
    run.supervisor.submit('a', goal(force_n=0.0, distance_m=0.4, duration_s=2.0), run.t)
    results = run.run(3.0)
    assert run.codes() == [('a', TaskCode.TRACKING_LIMIT)]
    error = [float(np.linalg.norm(result.X_d - X)) for result in results]
    assert max(error) <= 0.05 + 0.4 * 5.77 / 4.0 * DT  # one period past the limit at most


def test_f4_contact_during_the_back_off_does_not_rearm_the_force() -> None:
    """Finding 4: a cancel before contact, then a contact while backing off: F_d stays 0."""
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(), run.t)
    run.run(0.3)
    run.supervisor.cancel('a')
    retreat = run.run(LIMITS.retreat_time_s + 0.5, 50.0 * N)
    assert [result.F_d.tolist() for result in retreat] == [[0.0, 0.0, 0.0]] * len(retreat)


# ---------------------------------------------------------------------------- finding 5


def test_f5_released_means_released() -> None:
    """Finding 5: press_100n ends SUCCEEDED with the contact gone, and it stays gone.

    Before, it ended SUCCEEDED with 31 N on the wall, and the hold settled at 52.8 N.
    """
    loop = Loop(SafetyLimits())
    loop.step()
    loop.supervisor.submit('press', press_goal(), loop.t)
    loop.run_until_event(10.0)
    [(_, event)] = loop.events
    assert event.result.code == TaskCode.SUCCEEDED
    assert loop.contact_force() < THRESHOLD_N
    later = loop.run(3.0)
    assert loop.contact_force() < THRESHOLD_N
    assert max(float(np.linalg.norm(result.F_e)) for result in later) < THRESHOLD_N


# ---------------------------------------------------------------------------- finding 6


FAST = ContactTaskGoal(path=np.array([X, X + np.array([0.0, 1.0, 0.0])]),
                       times=np.array([0.0, 0.05]), velocities=None, accelerations=None,
                       normal=N, force_n=0.0, force_ramp_s=0.0)


@pytest.mark.parametrize(('changes', 'limits', 'field', 'limit_name'), [
    ({}, LIMITS, 'time_from_start_s[1]', 'safety.max_path_speed_m_s'),  # 1 m in 0.05 s
    ({'path': np.array([X, X + 0.5 * N]), 'times': np.array([0.0, 0.1])}, LIMITS,
     'time_from_start_s[1]', 'safety.max_path_speed_m_s'),  # 0.5 m in 0.1 s
    ({'path': np.array([X, X + 0.02 * N]), 'times': np.array([0.0, 0.2])}, LIMITS,
     'time_from_start_s[1]', 'safety.max_path_acceleration_m_s2'),
    ({'path': np.array([X, X + 0.1 * N, X]), 'times': np.array([0.0, 1.0, 2.0]),
      'velocities': np.array([[0.0, 0, 0], [0.0, 0, 30.0], [0.0, 0, 0]])},
     replace(LIMITS, max_path_speed_m_s=1e3, max_path_acceleration_m_s2=1e4),
     'path[1]', 'safety.max_path_distance_m'),  # waypoints near, the path 8 m away
    ({'path': np.array([X, X + 0.1 * N]), 'times': np.array([0.0, 2.0]),
      'velocities': np.array([[0.0, 0, 0], [0.1, 0, 0]])}, LIMITS, 'velocity[1]',
     'the path ends at rest'),
    ({'force_n': 100.0, 'force_ramp_s': 1e-6}, LIMITS, 'force_ramp_s', 'safety.min_ramp_s'),
])
def test_f6_path_limits_refuse_the_goal_naming_field_and_limit(
        changes: dict[str, object], limits: SafetyLimits, field: str, limit_name: str) -> None:
    """Finding 6: goals beyond the path limits are refused naming the field and the limit."""
    run = Run(limits)
    run.step()
    unsafe = replace(FAST, **changes)  # type: ignore[arg-type]
    if 'path' in changes and 'times' not in changes:
        unsafe = replace(unsafe, path=np.asarray(changes['path']))
    [event] = run.supervisor.submit('a', unsafe, run.t)
    assert event.result.code == TaskCode.INVALID_GOAL
    assert event.result.message.startswith(f'{field} = ')
    assert limit_name in event.result.message


def test_f6_retreat_time_under_the_minimum_ramp_is_refused() -> None:
    """Finding 6: retreat_time_s = 1 ms is refused naming it and safety.min_ramp_s."""
    with pytest.raises(ValueError, match=r'safety\.retreat_time_s = 0\.001 s.*safety\.min_ramp_s'):
        SafetyLimits(retreat_time_s=0.001)


def test_f6_streamed_target_far_away_is_refused() -> None:
    """Finding 6: a target 1 km away is refused naming safety.max_path_distance_m."""
    run = Run()
    run.step()
    assert not run.supervisor.set_target((X + 1000.0 * N).tolist())
    assert run.supervisor.refusal is not None
    assert 'safety.max_path_distance_m' in run.supervisor.refusal
    run.run(0.5)
    np.testing.assert_allclose(run.step().X_d, X, atol=1e-12)


# ---------------------------------------------------------------------------- finding 8


def test_f8_tracking_limit_applies_while_holding() -> None:
    """Finding 8: 2 s of zero thrust, then the hold: a retreat from X, not a 16 kN pull back."""
    loop = Loop(SafetyLimits())
    loop.run(0.5)
    loop.tau_b = np.zeros(9)
    loop.gap(2.0)
    loop.step()
    assert loop.supervisor.breach is not None and 'max_position_error_m' in loop.supervisor.breach
    after = loop.run(0.5)
    assert max(float(np.linalg.norm(r.X_d - r.X)) for r in after) < SafetyLimits().retreat_m
    assert loop.supervisor.state == SupervisorState.RETREATING


def test_f8_stale_inputs_end_the_goal_and_resume_holds_the_measured_position() -> None:
    """Finding 8: abort_all(INPUTS_STALE) then recapture_hold: X_d = X at the first step back."""
    loop = Loop(SafetyLimits())
    loop.step()
    loop.supervisor.submit('press', press_goal(), loop.t)
    loop.run(1.0)
    events = loop.supervisor.abort_all(TaskCode.INPUTS_STALE, 'inputs stale')
    assert [(e.goal_id, e.result.code) for e in events] == [('press', TaskCode.INPUTS_STALE)]
    loop.tau_b = np.zeros(9)
    loop.gap(2.0)
    loop.supervisor.recapture_hold()
    first = loop.step()
    np.testing.assert_allclose(first.X_d, first.X, atol=1e-12)
    assert first.F_d.tolist() == [0.0, 0.0, 0.0]
    assert loop.supervisor.state == SupervisorState.HOLD


def test_f8_resume_in_contact_lets_the_contact_go() -> None:
    """Finding 8: a hold re-captured while pressing backs off instead of pressing on (~20 N)."""
    loop = Loop(SafetyLimits())
    loop.step()
    loop.supervisor.submit('press', press_goal(), loop.t)
    loop.run(4.0)
    assert loop.contact_force() > 50.0
    loop.supervisor.abort_all(TaskCode.INPUTS_STALE, 'inputs stale')
    loop.gap(0.02)
    loop.supervisor.recapture_hold()
    loop.run(2.0)
    assert loop.contact_force() < THRESHOLD_N
    assert loop.supervisor.state == SupervisorState.HOLD


# ---------------------------------------------------------------------------- finding 9


def test_f9_reset_forgets_the_streamed_target() -> None:
    """Finding 9: a streamed target survived deactivate/activate."""
    run = Run()
    run.step()
    assert run.supervisor.set_target((X + 0.1 * N).tolist())
    run.run(0.2)
    run.supervisor.abort_all(TaskCode.INACTIVE, 'deactivated')
    run.supervisor.controller.reset()
    run.supervisor.reset()
    first = run.step()
    results = [first, *run.run(0.5)]
    for result in results:
        np.testing.assert_allclose(result.X_d, X, atol=1e-12)


def test_f9_goals_queued_before_the_first_step_end_at_deactivation() -> None:
    """Finding 9: a goal queued before the first step ends INACTIVE when deactivated."""
    run = Run()
    assert run.supervisor.submit('a', goal(), 0.0) == []
    events = run.supervisor.abort_all(TaskCode.INACTIVE, 'deactivated')
    assert [(e.goal_id, e.result.code) for e in events] == [('a', TaskCode.INACTIVE)]
    run.run(0.1)
    assert run.codes() == []
    assert run.supervisor.submit('b', goal(), 0.0) == []
    assert [(e.goal_id, e.result.code) for e in run.supervisor.reset()] == [
        ('b', TaskCode.INACTIVE)]


def test_f9_goal_is_checked_against_the_fresh_position_after_a_stale_period() -> None:
    """Finding 9: after abort_all the stale X is not used for max_path_distance_m."""
    run = Run(replace(LIMITS, max_path_distance_m=0.1))
    run.step()
    run.supervisor.abort_all(TaskCode.INPUTS_STALE, 'inputs stale')
    run.q = Q + np.array([0.3, 0, 0, 0, 0, 0, 0, 0, 0])  # the vehicle moved 0.3 m meanwhile
    x_new = MODEL.ee_position(run.q)
    near_new = replace(goal(force_n=0.0), path=np.array([x_new, x_new + 0.02 * N]))
    assert run.supervisor.submit('a', near_new, run.t) == []
    run.run(0.2)
    assert run.codes() == []
    assert run.supervisor.state == SupervisorState.FOLLOWING


def test_results_are_one_per_goal_in_a_busy_sequence() -> None:
    """Every goal gets exactly one result through preemptions, cancels and a breach."""
    run = Run()
    run.step()
    sequence = ['a', 'b', 'c', 'd']
    for goal_id in sequence:
        ended = run.supervisor.submit(goal_id, goal(start_time_s=run.t + 0.1), run.t)
        run.events += [(run.t, event) for event in ended]
        run.run(0.2, 20.0 * N)
    run.supervisor.cancel('d')
    run.run(0.05, 20.0 * N)
    run.step(400.0 * N)
    run.run(LIMITS.retreat_time_s + 0.1)
    ids = [goal_id for goal_id, _ in run.codes()]
    assert sorted(ids) == sequence and len(set(ids)) == len(ids)
    assert all(math.isfinite(event.result.contact_time_s) for _, event in run.events)
    assert list(itertools.islice(run.codes(), 3)) == [(g, TaskCode.PREEMPTED) for g in 'abc']
