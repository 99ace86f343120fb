"""A pilot session: keys and gamepad merged, actions acted on, what is published per tick."""

from __future__ import annotations

from pathlib import Path

import pytest
from evdev import ecodes
from uvms_pilot.command import PilotCommand, PilotLimits
from uvms_pilot.gamepad_mapping import load_mapping
from uvms_pilot.gamepad_state import EV_ABS, EV_KEY, EV_SYN, GamepadState
from uvms_pilot.keys import KeyboardDemand
from uvms_pilot.session import PilotSession, describe_command

SHIPPED = Path(__file__).resolve().parents[3] / 'config' / 'pilot' / 'xbox.yaml'
LIMITS = PilotLimits(vehicle_m_s=(0.4, 0.4, 0.2), yaw_rad_s=0.4, ee_m_s=(0.1, 0.1, 0.1),
                     jaw_m_s=0.02)
RANGES = {ecodes.ABS_X: (-100, 100), ecodes.ABS_Y: (-100, 100), ecodes.ABS_RX: (-100, 100),
          ecodes.ABS_RY: (-100, 100), ecodes.ABS_Z: (0, 100), ecodes.ABS_RZ: (0, 100)}


class FakeLink:
    """Records what a session sends to the graph."""

    def __init__(self, fail: str | None = None) -> None:
        self.published: list[tuple[tuple[str, ...], PilotCommand]] = []
        self.joy: list[tuple[list[float], list[int]]] = []
        self.calls: list[str] = []
        self.notes: list[str] = []
        self.fail = fail

    def publish(self, parts: tuple[str, ...], cmd: PilotCommand) -> None:
        """Keep a publication."""
        self.published.append((parts, cmd))

    def publish_joy(self, axes: list[float], buttons: list[int], frame_id: str) -> None:
        """Keep a /joy message."""
        self.joy.append((axes, buttons))

    def _call(self, name: str) -> None:
        if name == self.fail:
            raise RuntimeError(f'{name} broke')
        self.calls.append(name)

    def hold(self) -> None:
        """Keep a hold request."""
        self._call('hold')

    def start_task(self) -> None:
        """Keep a task start."""
        self._call('start_task')

    def cancel_task(self) -> None:
        """Keep a cancel."""
        self._call('cancel_task')

    def note(self, text: str) -> None:
        """Keep a note."""
        self.notes.append(text)


@pytest.fixture
def session() -> tuple[PilotSession, FakeLink]:
    """Keys and the shipped gamepad mapping on a fake link."""
    link = FakeLink()
    pad = GamepadState(load_mapping(SHIPPED), RANGES)
    return PilotSession(link, LIMITS, KeyboardDemand(), pad), link


def test_keys_win_over_the_gamepad_on_their_axis(session: tuple[PilotSession, FakeLink]
                                                 ) -> None:
    """Stick back and w held: surge forward (the key); the stick's yaw still goes through."""
    pilot, link = session
    pilot.gamepad_event(EV_ABS, ecodes.ABS_Y, 100)  # stick back: surge -1
    pilot.gamepad_event(EV_ABS, ecodes.ABS_RX, 100)  # right stick right: yaw +1
    pilot.press('w', 0.0)
    assert pilot.tick(0.01) == ('vehicle',)
    u, _, _, _, _, r = link.published[-1][1].vehicle_twist
    assert (u, r) == (pytest.approx(0.1), pytest.approx(0.1))  # gear 25 % of 0.4


def test_gamepad_actions_act_at_the_next_tick_and_joy_at_each_report(
        session: tuple[PilotSession, FakeLink]) -> None:
    """A press queues its action for the tick; SYN_REPORT publishes /joy."""
    pilot, link = session
    pilot.gamepad_event(EV_KEY, ecodes.BTN_START, 1)
    assert link.calls == [] and link.joy == []
    pilot.gamepad_event(EV_SYN, 0, 0)
    assert len(link.joy) == 1
    pilot.tick(0.0)
    assert link.calls == ['start_task']


def test_key_actions_reach_the_link_and_gears_change_the_scale(
        session: tuple[PilotSession, FakeLink]) -> None:
    """h, t, c call the link; 3 is full scale."""
    pilot, link = session
    for key in 'htc':
        pilot.press(key, 0.0)
    assert link.calls == ['hold', 'start_task', 'cancel_task']
    pilot.press('3', 0.0)
    pilot.press('i', 0.0)
    pilot.tick(0.01)
    assert link.published[-1][1].ee_velocity_m_s == (0.1, 0.0, 0.0)
    assert describe_command(link.published[-1][1]) == 'arm x +0.100 m/s'


def test_a_failing_action_is_a_note_not_a_crash() -> None:
    """A link that raises on hold: the session says so and goes on."""
    link = FakeLink(fail='hold')
    pilot = PilotSession(link, LIMITS, KeyboardDemand())
    pilot.press('h', 0.0)
    assert link.notes == ['hold failed: RuntimeError: hold broke']
    pilot.press('w', 0.1)
    assert pilot.tick(0.2) == ('vehicle',)


def test_unplugged_pad_and_session_end_leave_zeros(session: tuple[PilotSession, FakeLink]
                                                   ) -> None:
    """Pad lost mid-stick: the next tick publishes one zero; at the end nothing still moves."""
    pilot, link = session
    pilot.gamepad_event(EV_ABS, ecodes.ABS_X, 100)
    pilot.tick(0.0)
    pilot.gamepad_lost()
    assert pilot.tick(0.05) == ('vehicle',)
    assert link.published[-1][1].vehicle_twist == (0.0,) * 6
    assert pilot.parts_to_stop() == ()
