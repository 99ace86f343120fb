"""Tests of the contact-task supervisor on a real controller and model, without ROS."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from uvms_control.core.law.unified_controller import ControllerResult, UnifiedForceController
from uvms_control.core.parameters import ControllerParameters
from uvms_control.core.task.contact_task import ContactTaskGoal, SafetyLimits, TaskCode
from uvms_control.core.task.task_supervisor import TaskEvent, TaskState, TaskSupervisor

from uvms_model import UvmsModel

MODEL = UvmsModel()
Q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.477, -1.511])  # fixed configuration
W_REST = np.zeros(9)
X = MODEL.ee_position(Q)
ROT_NED_FROM_EE = MODEL.ee_rotation(Q)
NORMAL = np.array([0.6, 0.0, 0.8])  # unit normal of the tilted surface, map_ned
DT = 0.01  # control period (s)
LIMITS = SafetyLimits(
    max_contact_force_n=150.0,
    sensor_range_n=1000.0,
    retreat_m=0.05,
    retreat_time_s=1.0,
    max_target_speed_m_s=0.1,
)


def goal(start_time_s: float | None = None, force_n: float = 100.0) -> ContactTaskGoal:
    """Press along NORMAL: 2 cm into the surface over 1 s, F_d ramping over 0.5 s at contact."""
    return ContactTaskGoal(
        path=np.array([X, X + 0.02 * NORMAL]),
        times=np.array([0.0, 1.0]),
        velocities=None,
        accelerations=None,
        normal=5.0 * NORMAL,  # not unit: the supervisor normalizes it
        force_n=force_n,
        force_ramp_s=0.5,
        start_time_s=start_time_s,
    )


def sensor(force_normal_n: float) -> np.ndarray:
    """Wrist-sensor reading (ee axes) of a contact force force_normal_n along NORMAL (N)."""
    return ROT_NED_FROM_EE.T @ (force_normal_n * NORMAL)  # type: ignore[no-any-return]


class Run:
    """A supervisor on a fresh controller stepped at DT with synthetic sensor values."""

    def __init__(self) -> None:
        controller = UnifiedForceController(ControllerParameters.from_flat_dict(), UvmsModel())
        self.supervisor = TaskSupervisor(controller, LIMITS)
        self.k = 0
        self.events: list[tuple[float, TaskEvent]] = []
        self.last: ControllerResult | None = None

    @property
    def t(self) -> float:
        """Time of the next step (s)."""
        return self.k * DT

    def step(self, force_normal_n: float = 0.0) -> ControllerResult:
        """One step at (Q, 0) with the given contact force along NORMAL."""
        t = self.t
        self.last, events = self.supervisor.step(t, Q, W_REST, sensor(force_normal_n))
        self.events += [(t, event) for event in events]
        self.k += 1
        return self.last

    def run(self, duration_s: float, force_normal_n: float = 0.0) -> list[ControllerResult]:
        """Step for duration_s (s); return the results."""
        return [self.step(force_normal_n) for _ in range(round(duration_s / DT))]


def test_goal_waits_for_its_start_time() -> None:
    """Until start_time_s X_d holds X at rest; from then on it follows the path."""
    run = Run()
    run.step()
    assert run.supervisor.submit('a', goal(start_time_s=1.0), run.t) == []
    waiting = run.run(0.99)
    progress = run.supervisor.progress()
    assert progress is not None and progress.state == TaskState.WAITING
    for result in waiting:
        np.testing.assert_allclose(result.X_d, X, atol=1e-12)
        np.testing.assert_allclose(result.X_dot_d, 0.0, atol=1e-12)
    assert run.t == pytest.approx(1.0)
    following = run.run(0.51)  # up to t = 1.5 s, half way along the 1 s path
    progress = run.supervisor.progress()
    assert progress is not None and progress.state == TaskState.FOLLOWING
    # From rest to rest in 1 s the path is the quintic 10σ³ - 15σ⁴ + 6σ⁵: half way at σ = 1/2.
    assert float(NORMAL @ (following[-1].X_d - X)) == pytest.approx(0.01, abs=1e-9)


def test_preempted_goal_releases_its_force_at_the_measured_position() -> None:
    """A new valid goal ends the running one PREEMPTED; X_d holds X at rest, F_d ramps down."""
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(), run.t)
    pressing = run.run(0.7, force_normal_n=100.0)[-1]
    assert float(NORMAL @ pressing.F_d) == pytest.approx(100.0)
    events = run.supervisor.submit('b', goal(start_time_s=run.t + 5.0, force_n=60.0), run.t)
    assert [(event.goal_id, event.result.code) for event in events] == [('a', TaskCode.PREEMPTED)]
    assert run.supervisor.goal_id == 'b'
    released = run.run(LIMITS.retreat_time_s + DT, force_normal_n=100.0)
    for result in released:
        np.testing.assert_allclose(result.X_d, X, atol=1e-12)  # the measured position
        np.testing.assert_allclose(result.X_dot_d, 0.0, atol=1e-12)
    forces = [float(NORMAL @ result.F_d) for result in released]
    assert all(later <= earlier + 1e-9 for earlier, later in itertools.pairwise(forces))
    assert forces[0] > 90.0 and forces[-1] == pytest.approx(0.0, abs=1e-9)
    progress = run.supervisor.progress()
    assert progress is not None and progress.state == TaskState.WAITING


def test_cancel_releases_the_force_and_ends_after_the_retreat() -> None:
    """Cancel: F_d ramps to zero while X_d backs off retreat_m along -n; CANCELED after it."""
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(), run.t)
    pressing = run.run(0.7, force_normal_n=100.0)
    np.testing.assert_allclose(pressing[-1].F_d, 100.0 * NORMAL, atol=1e-9)
    assert run.supervisor.cancel('a')
    t_cancel = run.t
    retreat = [pressing[-1]]
    while not run.events and run.t < t_cancel + 3.0:
        # The surface lets go once X_d has backed off 2 cm from the (fixed) end effector.
        backed_off = float(NORMAL @ (retreat[-1].X_d - X)) < -0.02
        retreat.append(run.step(force_normal_n=0.0 if backed_off else 100.0))
    retreat = retreat[1:]
    [(t_end, event)] = run.events
    assert event.goal_id == 'a'
    assert event.result.code == TaskCode.CANCELED
    t_retreat_end = t_cancel + LIMITS.retreat_time_s
    assert t_retreat_end - 1e-9 <= t_end <= t_retreat_end + 1.5 * DT
    forces = [float(NORMAL @ result.F_d) for result in retreat]
    assert forces[-1] == pytest.approx(0.0, abs=1e-9)
    assert all(later <= earlier + 1e-9 for earlier, later in itertools.pairwise(forces))
    np.testing.assert_allclose(retreat[-1].X_d, X - LIMITS.retreat_m * NORMAL, atol=1e-9)
    assert run.supervisor.goal_id is None


def test_force_beyond_the_limit_ends_force_limit_and_retreats_along_minus_n() -> None:
    """n·F_e above safety.max_contact_force_n: the task backs off along -n, ends FORCE_LIMIT."""
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(), run.t)
    run.run(0.3, force_normal_n=100.0)
    breach = run.step(force_normal_n=160.0)
    progress = run.supervisor.progress()
    assert progress is not None and progress.state == TaskState.RETREATING
    path = run.supervisor.controller.task.path
    assert path is not None
    np.testing.assert_allclose(path.points[-1], breach.X - LIMITS.retreat_m * NORMAL, atol=1e-12)
    halfway = run.run(0.5, force_normal_n=160.0)[-1]
    offset = halfway.X_d - breach.X_d
    assert float(NORMAL @ offset) < -0.01
    np.testing.assert_allclose(offset - float(NORMAL @ offset) * NORMAL, 0.0, atol=1e-9)
    run.run(0.6)
    [(_, event)] = run.events
    assert event.result.code == TaskCode.FORCE_LIMIT
    assert 'safety.max_contact_force_n' in event.result.message
    assert event.result.peak_force_n == pytest.approx(160.0)


def test_goal_submitted_before_the_first_step_is_checked_at_it() -> None:
    """Before any state there is no X to check against: the goals wait for the first step."""
    run = Run()
    assert run.supervisor.submit('bad', goal(force_n=-1.0), 0.0) == []
    assert run.supervisor.submit('good', goal(), 0.0) == []
    run.step()
    [(t, event)] = run.events
    assert (t, event.goal_id, event.result.code) == (0.0, 'bad', TaskCode.INVALID_GOAL)
    assert event.result.message.startswith('force_n = ')
    assert run.supervisor.goal_id == 'good'
    run.run(0.5)
    progress = run.supervisor.progress()
    assert progress is not None and progress.state == TaskState.FOLLOWING


def test_streamed_target_moves_the_hold_point_at_the_speed_limit() -> None:
    """set_target moves X_d toward the target at most max_target_speed_m_s, then holds it."""
    run = Run()
    run.step()
    target = X + np.array([0.08, 0.0, -0.06])  # 0.1 m away
    assert run.supervisor.set_target(target.tolist())
    results = run.run(1.5)
    steps = np.linalg.norm(np.diff([X, *[result.X_d for result in results]], axis=0), axis=1)
    assert float(steps.max()) <= LIMITS.max_target_speed_m_s * DT + 1e-12
    np.testing.assert_allclose(results[49].X_d, X + 0.5 * (target - X), atol=1e-9)
    np.testing.assert_allclose(results[-1].X_d, target, atol=1e-12)
    np.testing.assert_allclose(results[-1].X_dot_d, 0.0)


def test_streamed_target_is_refused_while_a_task_runs() -> None:
    """A task owns X_d: set_target returns False and leaves the path alone."""
    run = Run()
    run.step()
    run.supervisor.submit('a', goal(), run.t)
    run.step()
    assert not run.supervisor.set_target((X + 0.05).tolist())
