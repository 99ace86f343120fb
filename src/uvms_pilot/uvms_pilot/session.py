"""One pilot session: keys and a gamepad merged, actions acted on, commands published per tick.

The input loop (the terminal UI, or the headless gamepad loop) calls ``press`` for each key
and ``tick`` at the publish rate; a gamepad reader thread calls ``gamepad_event``. Keys win
over the gamepad on an axis where both ask for motion. No ROS here: ``link`` is a
``uvms_pilot.link.PilotLink`` (or a stand-in in tests).
"""

from __future__ import annotations

import queue
import threading
from typing import Protocol

from uvms_pilot.command import (
    GEARS,
    INPUT_AXES,
    Demand,
    PilotCommand,
    PilotLimits,
    PublishGate,
    command,
    gear_after,
)
from uvms_pilot.gamepad_state import EV_SYN, GamepadState
from uvms_pilot.keys import KeyboardDemand


class Link(Protocol):
    """What a session needs of the graph (``PilotLink``)."""

    def publish(self, parts: tuple[str, ...], cmd: PilotCommand) -> None:
        """Publish the command's parts ('vehicle', 'arm', 'jaw')."""

    def publish_joy(self, axes: list[float], buttons: list[int], frame_id: str) -> None:
        """Publish a gamepad's state on /joy."""

    def hold(self) -> None:
        """Ask the controller to hold the present pose."""

    def start_task(self) -> None:
        """Start the task file."""

    def cancel_task(self) -> None:
        """Cancel the running task."""

    def note(self, text: str) -> None:
        """Show one line of what just happened."""


class PilotSession:
    """Keys, gamepad, gear and publish gate of one pilot.

    Args:
        link: Where commands go and actions are sent.
        limits: The robot's pilot limits.
        keys: The keyboard's demand (None: no keyboard).
        gamepad: The gamepad's state (None: no gamepad).
    """

    def __init__(self, link: Link, limits: PilotLimits, keys: KeyboardDemand | None = None,
                 gamepad: GamepadState | None = None) -> None:
        self.link = link
        self.limits = limits
        self.keys = keys
        self.gamepad = gamepad
        self.gear_index = 0
        self.last_command = command(Demand(), limits, GEARS[0])
        self._gate = PublishGate()
        self._pad_lock = threading.Lock()
        self._pad_actions: queue.SimpleQueue[str] = queue.SimpleQueue()

    @property
    def gear(self) -> float:
        """The speed gear in use (a fraction of the limits)."""
        return GEARS[self.gear_index]

    def press(self, key: str, t_s: float) -> None:
        """A key pressed at t_s (s, monotonic); its action, if any, is acted on now."""
        if self.keys is None:
            return
        action = self.keys.press(key, t_s)
        if action is not None:
            self.act(action)

    def act(self, action: str) -> None:
        """Act on a key's or a button's action; a failure is a note, never the loop's end."""
        try:
            self._act(action)
        except Exception as exc:  # a callback boundary: the input loop must go on
            self.link.note(f'{action} failed: {type(exc).__name__}: {exc}')

    def _act(self, action: str) -> None:
        if action == 'stop':
            if self.keys is not None:
                self.keys.release_all()
            self.last_command = command(Demand(), self.limits, self.gear)
            self.link.publish(self._gate.stop_all(), self.last_command)
        elif action == 'hold':
            self.link.hold()
        elif action == 'start_task':
            self.link.start_task()
        elif action == 'cancel_task':
            self.link.cancel_task()
        elif action.startswith('gear_'):
            self.gear_index = gear_after(self.gear_index, action)
            self.link.note(f'gear {self.gear:.0%} of the pilot limits')

    def gamepad_event(self, ev_type: int, code: int, value: int, frame_id: str = '') -> None:
        """One event of the gamepad (reader thread): state updated, /joy at each report."""
        if self.gamepad is None:
            return
        with self._pad_lock:
            for action in self.gamepad.apply(ev_type, code, value):
                self._pad_actions.put(action)
            joy = (self.gamepad.joy_axes, self.gamepad.joy_buttons) if ev_type == EV_SYN else None
        if joy is not None:
            self.link.publish_joy(joy[0], joy[1], frame_id)

    def gamepad_lost(self) -> None:
        """The gamepad went away: its axes and buttons read zero from now on."""
        if self.gamepad is not None:
            with self._pad_lock:
                self.gamepad.release_all()

    def demand(self, t_s: float) -> Demand:
        """Keys and gamepad merged: the keys' value where a key is held, else the pad's."""
        keys = self.keys.demand(t_s) if self.keys is not None else Demand()
        if self.gamepad is None:
            return keys
        with self._pad_lock:
            pad = self.gamepad.demand()
        return Demand.from_values({axis: getattr(keys, axis) or getattr(pad, axis)
                                   for axis in INPUT_AXES})

    def tick(self, t_s: float) -> tuple[str, ...]:
        """Act on the gamepad's pending actions, then publish this tick; the parts published."""
        while True:
            try:
                self.act(self._pad_actions.get_nowait())
            except queue.Empty:
                break
        demand = self.demand(t_s)
        self.last_command = command(demand, self.limits, self.gear)
        parts = self._gate.parts_to_publish(demand)
        if parts:
            self.link.publish(parts, self.last_command)
        return parts

    def parts_to_stop(self) -> tuple[str, ...]:
        """The parts still moving (to publish one zero each when the session ends)."""
        return self._gate.parts_to_publish(Demand())


def describe_command(cmd: PilotCommand) -> str:
    """The command as one line (only the moving parts), for the screen."""
    u, v, w, _, _, r = cmd.vehicle_twist
    words: list[str] = []
    for name, value, unit in (('surge', u, 'm/s'), ('sway', v, 'm/s'), ('heave', w, 'm/s'),
                              ('yaw', r, 'rad/s')):
        if value:
            words.append(f'{name} {value:+.3f} {unit}')
    for name, value in zip(('arm x', 'arm y', 'arm z'), cmd.ee_velocity_m_s, strict=True):
        if value:
            words.append(f'{name} {value:+.3f} m/s')
    if cmd.jaw_m_s:
        words.append(f'jaw {cmd.jaw_m_s:+.4f} m/s')
    return ', '.join(words) if words else 'zero'

