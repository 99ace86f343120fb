"""Modes and hand-over in closed loop: the pilot drives, releases, hands over and takes back.

The paper's robot (controller and plant, ``closed_loop_plant``) with the null-space posture
holding the vehicle; the pilot hand-over runs before each supervisor step as in the node.
"""

from __future__ import annotations

import numpy as np
import pytest
from closed_loop_plant import WALL_X, X_A, Loop, press_goal
from uvms_control.core.pilot.handover import PilotHandover, PilotMode
from uvms_control.core.pilot.inputs import PilotTwist
from uvms_control.core.pilot.limits import PilotLimits
from uvms_control.core.pilot.supervisor import PilotedSupervisor
from uvms_control.core.task.contact_task import SafetyLimits, TaskCode
from uvms_control.core.task.task_supervisor import SupervisorState

#: A wall out of reach, for free driving.
FAR = 10.0

LIMITS = PilotLimits(vehicle_speed_m_s=(0.3, 0.3, 0.2), vehicle_rate_rad_s=(0.0, 0.0, 0.3),
                     vehicle_acceleration_m_s2=0.2, vehicle_angular_acceleration_rad_s2=0.3,
                     ee_speed_m_s=(0.05, 0.05, 0.05), ee_acceleration_m_s2=0.1)


class PilotLoop(Loop):
    """The closed loop with the hand-over stepped before the supervisor, as the node does."""

    def __init__(self, limits: PilotLimits = LIMITS, wall_x: float = WALL_X) -> None:
        super().__init__(SafetyLimits(), wall_x=wall_x)
        self.supervisor = PilotedSupervisor(self.controller, SafetyLimits())
        self.pilot = PilotHandover(self.supervisor, limits)
        self.modes: list[tuple[float, PilotMode]] = []
        self.notes: list[str] = []

    def step(self):
        """The hand-over, then the supervisor's step and the plant's period."""
        self.pilot.before_step(self.t)
        self.modes += [(self.t, s.mode) for s in self.pilot.take_switches()]
        self.notes += self.pilot.take_notes()
        return super().step()

    def drive(self, duration_s: float, vehicle=(0.0,) * 6, ee=None) -> None:
        """Send a vehicle twist (and an end-effector velocity) every step for duration_s."""
        for _ in range(round(duration_s / self.dt)):
            self.pilot.vehicle(self.t, PilotTwist(tuple(vehicle[:3]), tuple(vehicle[3:])))
            if ee is not None:
                self.pilot.ee(self.t, PilotTwist(tuple(ee), in_body=True))
            self.step()


def test_the_pilot_drives_the_vehicle_then_it_holds_where_released() -> None:
    """0.2 m/s forward for 2 s: the vehicle and the arm move together; release: hold, no drift."""
    loop = PilotLoop(wall_x=FAR)
    loop.run(0.5)
    x0 = loop.q[0]
    loop.drive(2.0, (0.2, 0.0, 0.0, 0.0, 0.0, 0.0))
    assert loop.pilot.mode == PilotMode.PILOT
    loop.run(3.0)
    assert [mode for _, mode in loop.modes] == [PilotMode.PILOT, PilotMode.HOLD]
    released = loop.controller.vehicle_reference
    assert released is not None
    # 1 s up to 0.2 m/s (0.1 m), 1 s and the 0.3 s deadman at it, 1 s down (0.1 m)
    assert released[0] - x0 == pytest.approx(0.1 + 0.2 * 1.3 + 0.1, abs=0.003)
    positions = []
    for _ in range(4):
        loop.run(1.0)
        positions.append(loop.q[:3].copy())
    np.testing.assert_allclose(positions, [released[:3]] * 4, atol=0.01)
    assert np.linalg.norm(loop.last.X - loop.last.X_d) < 0.01  # the arm rode along


def test_pilot_input_never_makes_the_reference_jump() -> None:
    """A huge step in the command: X_d moves at most max speed x dt per step."""
    loop = PilotLoop(wall_x=FAR)
    loop.run(0.2)
    results = []
    for _ in range(500):
        loop.pilot.vehicle(loop.t, PilotTwist((0.3, 0.0, 0.0)))
        results.append(loop.step())
    steps = np.linalg.norm(np.diff([r.X_d for r in results], axis=0), axis=1)
    assert np.max(steps) <= 0.3 * loop.dt + 1e-9


def test_a_goal_takes_control_and_pilot_input_cancels_it_as_a_cancel_does() -> None:
    """press_100n takes over; pilot input mid-task: CANCELED, force released, the arm backs off."""
    loop = PilotLoop()
    loop.run(0.2)
    loop.supervisor.submit('press', press_goal(), loop.t)
    loop.run(0.1)
    assert loop.pilot.mode == PilotMode.TASK
    loop.run(3.5)  # in contact, pressing
    assert loop.contact_force() > 20.0
    loop.drive(0.1, (0.1, 0.0, 0.0, 0.0, 0.0, 0.0))
    assert loop.supervisor.state == SupervisorState.RETREATING
    loop.run_until_event(3.0)
    (_, event), = loop.events
    assert event.result.code == TaskCode.CANCELED
    assert loop.contact_force() == 0.0
    loop.run(0.1)
    assert loop.pilot.mode == PilotMode.HOLD
    assert [mode for _, mode in loop.modes] == [PilotMode.TASK, PilotMode.HOLD]
    assert any('canceled as a cancel does' in note for note in loop.notes)


def test_a_contact_refuses_the_pilot_when_the_robot_says_so() -> None:
    """refuse_during_contact: pilot input while pressing is refused, named, the task goes on."""
    loop = PilotLoop(PilotLimits(refuse_during_contact=True))
    loop.run(0.2)
    loop.supervisor.submit('press', press_goal(), loop.t)
    loop.run(3.6)
    assert loop.pilot._in_contact()
    loop.drive(0.2, (0.1, 0.0, 0.0, 0.0, 0.0, 0.0))
    assert loop.supervisor.state == SupervisorState.FOLLOWING
    assert loop.events == []
    assert sum('task holds a contact' in note for note in loop.notes) == 1


def test_an_unused_pilot_changes_no_command() -> None:
    """With no pilot input, every command is bit for bit the one without a pilot."""
    plain, piloted = Loop(SafetyLimits()), PilotLoop()
    for loop in (plain, piloted):
        loop.run(0.2)
        loop.supervisor.submit('press', press_goal(), loop.t)
    for _ in range(1500):
        a, b = plain.step(), piloted.step()
        np.testing.assert_array_equal(a.tau_b, b.tau_b)
    assert piloted.modes == [(pytest.approx(0.2), PilotMode.TASK)]


def test_the_hold_request_stops_the_pilot_and_cancels_a_task() -> None:
    """hold: the pilot is released at once; with a task, the task is canceled."""
    loop = PilotLoop()
    loop.run(0.2)
    loop.drive(0.5, (-0.2, 0.0, 0.0, 0.0, 0.0, 0.0))
    assert loop.pilot.hold() == (True, 'holding')
    assert loop.pilot.mode == PilotMode.HOLD
    loop.run(2.0)
    assert not loop.pilot.motion.moving
    loop.supervisor.submit('press', press_goal(), loop.t)
    loop.run(0.1)
    ok, message = loop.pilot.hold()
    assert ok and 'canceled' in message
    loop.run_until_event(3.0)
    assert loop.events[-1][1].result.code == TaskCode.CANCELED


def test_the_end_effector_moves_relative_to_the_vehicle() -> None:
    """5 cm down (body z) at 2.5 cm/s: X_d and X go 5 cm deeper, the vehicle stays."""
    loop = PilotLoop(wall_x=FAR)
    loop.run(0.5)
    z0, vehicle0 = loop.last.X[2], loop.q[:3].copy()
    loop.drive(1.7, ee=(0.0, 0.0, 0.025))
    loop.run(3.0)
    assert loop.last.X[2] - z0 == pytest.approx(0.05, abs=0.005)
    np.testing.assert_allclose(loop.q[:3], vehicle0, atol=0.01)
    assert X_A[2] == pytest.approx(z0, abs=0.01)
