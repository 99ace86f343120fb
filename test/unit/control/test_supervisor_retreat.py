"""Retreats and releases never end with the arm pressing, whatever the goal's normal says.

Found by the property test (test_supervisor_properties.py, ``random`` profile): a goal whose
normal is reversed (the wall at +x, n = -x) canceled before contact retreated along -n, into
the wall, and its CANCELED result came with ~43-100 N on the wall, held for good. Out of
contact a normal is not verified, so a back-off now turns against the measured force as soon
as it meets a contact on its way, and a retreat still in contact when its time is up backs off
on before its result.

The closed-loop test runs the supervisor on the real controller and the paper's UVMS against
the K_e = 1e4 N/m wall at 100 Hz (``closed_loop_plant.Loop``, as the property test does); the
others feed a fixed configuration with chosen sensor values.
"""

from __future__ import annotations

import numpy as np
from closed_loop_plant import X_A, Loop
from uvms_control.core.law.unified_controller import ControllerResult, UnifiedForceController
from uvms_control.core.parameters import ControllerParameters
from uvms_control.core.task.contact_task import ContactTaskGoal, SafetyLimits, TaskCode
from uvms_control.core.task.task_supervisor import SupervisorState, TaskEvent, TaskSupervisor

from uvms_model import UvmsModel

MODEL = UvmsModel()
Q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.477, -1.511])  # fixed configuration
X = MODEL.ee_position(Q)
N = np.array([1.0, 0.0, 0.0])  # the wall's true normal (into it)
DT = 0.01
LIMITS = SafetyLimits(max_contact_force_n=250.0, sensor_range_n=1000.0)
THRESHOLD_N = 5.0  # the paper robot's force.contact_threshold_n
RELEASED_N = 0.5 * THRESHOLD_N


def reversed_goal(start: np.ndarray, start_time_s: float | None = None,
                  force_n: float = 0.0) -> ContactTaskGoal:
    """5 cm toward the wall (+x) in 1 s, with the normal reversed (-x)."""
    return ContactTaskGoal(path=np.array([start, start + 0.05 * N]), times=np.array([0.0, 1.0]),
                           velocities=None, accelerations=None, normal=-N, force_n=force_n,
                           force_ramp_s=0.5, require_contact=force_n > 0.0,
                           start_time_s=start_time_s)


class Run:
    """A supervisor stepped at DT at the fixed Q with a chosen force (N, map_ned)."""

    def __init__(self) -> None:
        controller = UnifiedForceController(ControllerParameters.from_flat_dict(), UvmsModel())
        self.supervisor = TaskSupervisor(controller, LIMITS)
        self.k = 0
        self.events: list[tuple[float, TaskEvent]] = []

    @property
    def t(self) -> float:
        """Time of the next step (s)."""
        return self.k * DT

    def step(self, force_ned: np.ndarray | None = None) -> ControllerResult:
        """One step with this contact force (map_ned)."""
        force = np.zeros(3) if force_ned is None else force_ned
        rot = MODEL.ee_rotation(Q)
        result, events = self.supervisor.step(self.t, Q, np.zeros(9), rot.T @ force)
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


def canceled_out_of_contact(before_cancel_s: float = 0.2, after_cancel_s: float = 0.2) -> Run:
    """A Run whose reversed goal was canceled before any contact, backing off along -n."""
    run = Run()
    run.step()
    run.supervisor.submit('a', reversed_goal(X), run.t)
    run.run(before_cancel_s)
    run.supervisor.cancel('a')
    run.run(after_cancel_s)
    return run


def test_cancel_before_contact_with_a_reversed_normal_ends_released() -> None:
    """The property test's sequence: CANCELED comes with the contact gone, and it stays gone.

    Before: the retreat backed off 5 cm along -n = +x, into the wall 2 cm ahead; CANCELED came
    with 68 N on the wall and the hold kept pressing (70 N 2.5 s later).
    """
    loop = Loop(LIMITS, dt=DT)
    loop.wall_x = float(X_A[0]) + 0.02
    loop.step()
    loop.supervisor.submit('a', reversed_goal(loop.last.X_d, force_n=100.0), loop.t)
    loop.run(0.1)
    assert loop.contact_force() == 0.0  # no contact at the cancel: n is not verified
    assert loop.supervisor.cancel('a')
    during = loop.run_until_event(LIMITS.retreat_time_s + 2.0)
    [(_, event)] = loop.events
    assert event.result.code == TaskCode.CANCELED
    assert float(np.linalg.norm(during[-1].F_e)) < RELEASED_N  # the step that gave the result
    assert max(float(np.linalg.norm(r.F_e)) for r in during) < LIMITS.max_contact_force_n
    after = loop.run(2.0)
    assert max(float(np.linalg.norm(r.F_e)) for r in after) < THRESHOLD_N
    assert loop.contact_force() < THRESHOLD_N
    assert loop.supervisor.state == SupervisorState.HOLD


def test_a_back_off_along_an_unverified_normal_turns_at_the_first_contact() -> None:
    """Cancel out of contact: X_d backs off along -n; a contact ahead turns it against F_e."""
    run = canceled_out_of_contact(after_cancel_s=0.3)
    path = run.supervisor.controller.task.path
    assert path is not None
    np.testing.assert_allclose(path.points[-1], X + LIMITS.retreat_m * N, atol=1e-12)  # -n
    turn = run.step(20.0 * N)  # the wall: pressed on by the back-off
    path = run.supervisor.controller.task.path
    assert path is not None
    np.testing.assert_allclose(path.points[-1], X - LIMITS.retreat_m * N, atol=1e-12)
    later = run.run(0.5)  # the contact let go at once: the turned back-off runs on
    assert float(N @ (later[-1].X_d - turn.X)) < -0.02
    assert run.codes() == []  # a whole retreat_time_s from the turn
    run.run(LIMITS.retreat_time_s - 0.5 + 2 * DT)
    assert run.codes() == [('a', TaskCode.CANCELED)]
    assert run.supervisor.state == SupervisorState.HOLD


def test_a_second_contact_along_the_back_off_latches_the_safe_hold() -> None:
    """After one turn, a back-off that meets a contact again yields in the safe hold."""
    run = canceled_out_of_contact()
    run.step(20.0 * N)  # turns: now backing off along -x
    run.run(0.2)
    run.step(-20.0 * N)  # a surface behind, pressed on by the turned back-off
    assert run.supervisor.safe_hold
    [(_, event)] = run.events
    assert event.result.code == TaskCode.CANCELED
    assert 'met a contact along its way again' in event.result.message


def test_the_result_waits_while_the_retreat_is_still_in_contact() -> None:
    """Time up with |F_e| still measured: X_d backs off on against it; the result after."""
    run = canceled_out_of_contact()
    run.step(20.0 * N)  # the turn: a retreat_time_s from here
    pressed = run.run(LIMITS.retreat_time_s + 0.5, 20.0 * N)  # the wall follows the arm
    assert run.codes() == []
    assert run.supervisor.state == SupervisorState.RETREATING
    beyond = float(N @ (pressed[-1].X_d - X))
    assert beyond < -LIMITS.retreat_m - 0.015  # backing off on, against the force
    [refused] = run.supervisor.submit('b', reversed_goal(X), run.t)
    assert refused.result.code == TaskCode.INVALID_GOAL  # still protected
    run.step()  # the contact let go
    assert run.codes() == [('a', TaskCode.CANCELED)]
    assert run.supervisor.state == SupervisorState.HOLD


def test_a_retreat_that_cannot_let_go_ends_after_its_whole_distance_saying_so() -> None:
    """A contact that never goes: the result after retreat_m more, naming the force left."""
    run = canceled_out_of_contact()
    run.run(2 * LIMITS.retreat_time_s + 0.5, 20.0 * N)
    [(_, event)] = run.events
    assert event.result.code == TaskCode.CANCELED
    assert 'N left after backing off the whole retreat distance' in event.result.message


def test_preemption_backs_off_against_the_measured_force_not_along_the_normal() -> None:
    """Preempted out of contact with n reversed, a contact at once: the hold point moves off it.

    Before: the release kept the direction taken at the preemption (-n = +x without contact)
    and backed the hold point 5 cm into the wall (115 N held in the closed loop).
    """
    run = Run()
    run.step()
    run.supervisor.submit('a', reversed_goal(X), run.t)
    run.run(0.3)
    run.supervisor.submit('b', reversed_goal(X, start_time_s=run.t + 20.0), run.t)
    pressed = run.run(0.3, 20.0 * N)  # the contact comes at the step after the preemption
    np.testing.assert_allclose(pressed[0].X_d, X, atol=1e-12)  # held at the measured X
    assert float(N @ (pressed[-1].X_d - X)) < -0.01
    assert run.supervisor.state == SupervisorState.WAITING


def test_preemption_as_the_contact_starts_with_a_reversed_normal_lets_it_go() -> None:
    """Closed loop: preempted at the first period in contact, which no step has measured yet.

    Before: the release took -n = +x (no contact at the last step) and backed the hold point
    into the wall once the contact showed: 115 N held while the new goal waited.
    """
    loop = Loop(LIMITS, dt=DT)
    loop.wall_x = float(X_A[0]) + 0.01
    loop.step()
    start = loop.last.X_d
    goal = ContactTaskGoal(path=np.array([start, start + 0.05 * N]), times=np.array([0.0, 0.8]),
                           velocities=None, accelerations=None, normal=-N, force_n=0.0,
                           force_ramp_s=0.5)
    assert loop.supervisor.submit('a', goal, loop.t) == []
    while loop.contact_force() == 0.0 and loop.t < 2.0:
        loop.step()
    assert loop.contact_force() > 0.0
    assert float(np.linalg.norm(loop.last.F_e)) == 0.0
    [event] = loop.supervisor.submit('b', reversed_goal(start, start_time_s=loop.t + 20.0),
                                     loop.t)
    assert event.result.code == TaskCode.PREEMPTED
    loop.run(LIMITS.retreat_time_s + 1.0)
    assert loop.contact_force() < THRESHOLD_N
    assert loop.supervisor.state == SupervisorState.WAITING
