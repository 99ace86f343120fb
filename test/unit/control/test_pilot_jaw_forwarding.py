"""The jaw command the controller forwards (``command/jaw``): the pilot's, in pilot mode only.

The paper's robot in closed loop (``closed_loop_plant``), the hand-over stepped before the
supervisor as the node does; after each step the node publishes ``jaw_command_m_s()``.
"""

from __future__ import annotations

import pytest
from closed_loop_plant import Loop, press_goal
from uvms_control.core.pilot.handover import PilotHandover, PilotMode
from uvms_control.core.pilot.inputs import jaw_speed
from uvms_control.core.pilot.limits import PilotLimits
from uvms_control.core.pilot.supervisor import PilotedSupervisor
from uvms_control.core.task.contact_task import SafetyLimits

LIMITS = PilotLimits(jaw_speed_m_s=0.02, deadman_s=0.3)
FAR = 10.0  # a wall out of reach


class JawLoop(Loop):
    """The closed loop; ``commands`` is what the node would publish after each step."""

    def __init__(self, wall_x: float = FAR) -> None:
        super().__init__(SafetyLimits(), wall_x=wall_x)
        self.supervisor = PilotedSupervisor(self.controller, SafetyLimits())
        self.pilot = PilotHandover(self.supervisor, LIMITS)
        self.commands: list[tuple[float, float]] = []

    def step(self):  # type: ignore[no-untyped-def]
        """The hand-over, the forwarded jaw speed, the supervisor and the plant."""
        self.pilot.before_step(self.t)
        self.pilot.take_switches()
        self.commands.append((self.t, self.pilot.jaw_command_m_s()))
        return super().step()

    def jaw(self, duration_s: float, speed_m_s: float) -> None:
        """The pilot's jaw message every step for duration_s, bounded as the node does."""
        bounded, _ = jaw_speed('pilot/jaw', speed_m_s, LIMITS.jaw_speed_m_s)
        for _ in range(round(duration_s / self.dt)):
            self.pilot.jaw(self.t, bounded)
            self.step()


def test_in_pilot_mode_the_jaw_speed_is_forwarded_within_the_limit() -> None:
    """0.05 m/s asked (over the 0.02 limit): 0.02 forwarded once ramped (0.1 s), mode pilot."""
    loop = JawLoop()
    loop.run(0.2)
    assert loop.commands[-1][1] == 0.0  # hold: zero
    loop.jaw(0.5, 0.05)
    assert loop.pilot.mode == PilotMode.PILOT
    after_ramp = [c for t, c in loop.commands if t >= 0.2 + 0.1]
    assert after_ramp and all(c == pytest.approx(0.02) for c in after_ramp)
    assert max(c for _, c in loop.commands) <= 0.02 + 1e-12


def test_closing_is_forwarded_negative() -> None:
    """-0.01 m/s (closes) comes out as -0.01."""
    loop = JawLoop()
    loop.run(0.2)
    loop.jaw(0.3, -0.01)
    assert loop.commands[-1][1] == pytest.approx(-0.01)


def test_the_deadman_zeroes_the_jaw_and_hold_keeps_it_zero() -> None:
    """Messages stop: within the deadman (0.3 s) the mode is hold and the command exactly 0."""
    loop = JawLoop()
    loop.run(0.2)
    loop.jaw(0.4, 0.02)
    last_message_s = loop.t
    loop.run(1.0)
    assert loop.pilot.mode == PilotMode.HOLD
    late = [(t, c) for t, c in loop.commands if t > last_message_s + LIMITS.deadman_s + 0.01]
    assert late and all(c == 0.0 for _, c in late)
    nonzero = [t for t, c in loop.commands if c != 0.0]
    assert max(nonzero) <= last_message_s + LIMITS.deadman_s + 1e-9


def test_the_hold_service_zeroes_the_jaw_at_once() -> None:
    """hold() while the pilot opens the jaw: the next command is 0."""
    loop = JawLoop()
    loop.run(0.2)
    loop.jaw(0.3, 0.02)
    assert loop.commands[-1][1] == pytest.approx(0.02)
    ok, _ = loop.pilot.hold()
    assert ok
    loop.step()
    assert loop.pilot.mode == PilotMode.HOLD
    assert loop.commands[-1][1] == 0.0


def test_a_task_takes_the_jaw_to_zero_and_keeps_it_there() -> None:
    """A goal takes control mid-opening: zero from its first step, through the task."""
    loop = JawLoop(wall_x=1.7771)
    loop.run(0.2)
    loop.jaw(0.3, 0.02)
    assert loop.commands[-1][1] == pytest.approx(0.02)
    loop.supervisor.submit('press', press_goal(), loop.t)
    start = len(loop.commands)
    loop.run(1.0)
    assert loop.pilot.mode == PilotMode.TASK
    assert all(c == 0.0 for _, c in loop.commands[start:])
