"""The arm held in joint space while the vehicle is moved (``arm.hold_in_joint_space``).

What an identification plan needs (docs/identification.md, "Why the vehicle tumbles"): the
planned thrusts push the vehicle, and the arm must stay as it was instead of reaching for the
world-fixed hold point. The closed loop of the supervisor tests (the paper's robot, its own
model as the plant) with a surge force of 40 N on the vehicle for 2 s, as stuck thrusters
would give, the controller's vehicle forces not applied (the plan's thrusters ignore them).
"""

from __future__ import annotations

import numpy as np
import pytest
from closed_loop_plant import Loop, press_goal
from uvms_control.core.pilot.supervisor import PilotedSupervisor
from uvms_control.core.task.contact_task import SafetyLimits
from uvms_control.core.task.joint_hold import JointHold, joint_hold_from
from uvms_control.core.task.task_supervisor import SupervisorState

#: The push on the vehicle (N, base_link_frd surge) and how long (s).
PUSH_N, PUSH_S = 40.0, 2.0


class PushedLoop(Loop):
    """The closed loop whose vehicle obeys a planned force, not the controller's."""

    def __init__(self, joint_hold: JointHold | None) -> None:
        super().__init__(SafetyLimits(max_position_error_m=0.1), wall_x=10.0)
        self.supervisor = PilotedSupervisor(self.controller, SafetyLimits(
            max_position_error_m=0.1), joint_hold)
        self.vehicle_force = np.zeros(6)

    def advance(self, tau_b: np.ndarray) -> None:
        """The arm's torques from the controller, the vehicle's from the plan."""
        planned = tau_b.copy()
        planned[:6] = self.vehicle_force
        super().advance(planned)


def pushed(joint_hold: JointHold | None) -> tuple[PushedLoop, float]:
    """0.5 s of hold, then the push; the loop and the largest joint excursion (rad)."""
    loop = PushedLoop(joint_hold)
    loop.run(0.5)
    q_arm = loop.q[6:].copy()
    loop.vehicle_force[0] = PUSH_N
    excursion = 0.0
    for _ in range(round(PUSH_S / loop.dt)):
        loop.step()
        excursion = max(excursion, float(np.abs(loop.q[6:] - q_arm).max()))
    return loop, excursion


def test_the_joints_stay_where_they_were_while_the_vehicle_is_pushed() -> None:
    """Pushed 2 s forward: the joints within 0.01 rad, no breach, the vehicle rows zero.

    The end-effector hold of the paper (the default) swings the arm after the receding point
    until the tracking limit stops it in the safe hold (asserted too, so the test shows the
    difference it makes).
    """
    held, excursion = pushed(JointHold(frequency_hz=2.0, damping_ratio=1.0))
    assert held.q[0] > 0.1  # the vehicle did move
    assert excursion < 0.01
    assert held.supervisor.state == SupervisorState.HOLD and held.supervisor.breach is None
    assert np.all(held.last.tau_b[:6] == 0.0)
    reaching, excursion = pushed(None)
    assert excursion > 0.2 or reaching.supervisor.state == SupervisorState.SAFE_HOLD


def test_a_task_releases_the_hold_and_the_next_hold_begins_where_the_joints_are() -> None:
    """A goal runs the task law; after it the joints are held where the goal left them."""
    hold = JointHold(frequency_hz=2.0, damping_ratio=1.0)
    loop = PushedLoop(hold)
    loop.wall_x = 1.7771
    loop.run(0.2)
    assert hold.q_hold is not None
    loop.supervisor.submit('press', press_goal(force_n=20.0), loop.t)
    loop.run(0.1)
    assert hold.q_hold is None and np.any(loop.last.tau_b[:6] != 0.0)


@pytest.mark.parametrize(('on', 'expected'), [(False, None), (True, (5.0, 0.5))])
def test_the_node_parameters_make_the_hold(on: bool, expected: tuple[float, float] | None
                                           ) -> None:
    """arm.hold_in_joint_space with its gains; off: None, the paper's hold."""
    hold = joint_hold_from({'arm.hold_in_joint_space': on, 'arm.joint_hold_frequency_hz': 5.0,
                            'arm.joint_hold_damping_ratio': 0.5})
    assert (None if hold is None else (hold.omega_rad_s / (2 * np.pi), hold.damping_ratio)) \
        == pytest.approx(expected)
