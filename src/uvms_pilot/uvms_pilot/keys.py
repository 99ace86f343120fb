"""Terminal keys to a pilot demand: which key drives which axis, and how long a key counts as held.

A terminal reports key presses, never releases. A held key arrives as a press, then, after
the keyboard's auto-repeat delay (X11 660 ms, GNOME 500 ms by default), as repeats some 30 ms
apart. A key therefore counts as held for ``first_hold_s`` after its first press (to bridge
the auto-repeat delay) and for ``repeat_hold_s`` after each repeat: released, the demand is
zero within ``repeat_hold_s``, and a single tap moves for ``first_hold_s``. A key of the same
axis in the other direction takes over at once; the stop key (space) drops every key.

Layout (base_link_frd: x forward, y right, z down; the arm in the pilot's frame)::

    vehicle  w/s surge fwd/back   a/d sway left/right   r/f heave up/down   q/e yaw left/right
    arm      i/k x +/-            j/l y -/+             u/o z up/down (-z/+z)
    jaw      m opens, n closes
    gear     1 2 3 (25, 50, 100 % of the limits), - and + one down or up
    space stop (zero now)   h hold   t start the task file   c cancel the task
"""

from __future__ import annotations

from dataclasses import dataclass

from uvms_pilot.command import Demand

#: Key -> (input axis, direction).
KEY_AXES: dict[str, tuple[str, float]] = {
    'w': ('surge', 1.0), 's': ('surge', -1.0),
    'd': ('sway', 1.0), 'a': ('sway', -1.0),
    'f': ('heave', 1.0), 'r': ('heave', -1.0),
    'e': ('yaw', 1.0), 'q': ('yaw', -1.0),
    'i': ('arm_x', 1.0), 'k': ('arm_x', -1.0),
    'l': ('arm_y', 1.0), 'j': ('arm_y', -1.0),
    'o': ('arm_z', 1.0), 'u': ('arm_z', -1.0),
    'm': ('jaw', 1.0), 'n': ('jaw', -1.0),
}
#: Key -> action (``PilotActions`` names; the input tools act on them).
KEY_ACTIONS: dict[str, str] = {
    ' ': 'stop', 'h': 'hold', 't': 'start_task', 'c': 'cancel_task',
    '1': 'gear_1', '2': 'gear_2', '3': 'gear_3', '-': 'gear_down', '+': 'gear_up',
}
#: Default time a key counts as held after its first press (s): bridges the auto-repeat delay.
FIRST_HOLD_S = 0.45
#: Default time a key counts as held after a repeat (s): several auto-repeat intervals (a
#: loaded machine delivers them late), and with the 20 Hz tick still a zero within 0.3 s.
REPEAT_HOLD_S = 0.25


@dataclass
class _HeldKey:
    direction: float
    last_s: float
    repeated: bool


class KeyboardDemand:
    """The demand of the keys pressed lately, at any time.

    Args:
        first_hold_s: Held time after a key's first press (s), > 0.
        repeat_hold_s: Held time after an auto-repeat of the key (s), > 0.

    Example::

        >>> keys = KeyboardDemand()
        >>> keys.press('w', 0.0), keys.demand(0.1).surge, keys.demand(1.0).surge
        (None, 1.0, 0.0)
    """

    def __init__(self, first_hold_s: float = FIRST_HOLD_S,
                 repeat_hold_s: float = REPEAT_HOLD_S) -> None:
        if not first_hold_s > 0.0 or not repeat_hold_s > 0.0:
            msg = (f'key hold times must be > 0 s, got first {first_hold_s}, '
                   f'repeat {repeat_hold_s}')
            raise ValueError(msg)
        self.first_hold_s = first_hold_s
        self.repeat_hold_s = repeat_hold_s
        self._held: dict[str, _HeldKey] = {}

    def press(self, key: str, t_s: float) -> str | None:
        """Take a key press at time t_s (s, monotonic); the action it names, or None.

        An axis key returns None; an unknown key returns None and changes nothing; the stop
        key drops every held key and returns 'stop'.
        """
        if key in KEY_AXES:
            axis, direction = KEY_AXES[key]
            held = self._held.get(axis)
            if held is not None and held.direction == direction and self._is_held(held, t_s):
                held.last_s, held.repeated = t_s, True
            else:
                self._held[axis] = _HeldKey(direction, t_s, repeated=False)
            return None
        action = KEY_ACTIONS.get(key)
        if action == 'stop':
            self._held.clear()
        return action

    def release_all(self) -> None:
        """Drop every held key (focus lost, the stop key)."""
        self._held.clear()

    def demand(self, t_s: float) -> Demand:
        """The demand at time t_s (s, monotonic): +-1 on every axis whose key is held."""
        for axis in [a for a, held in self._held.items() if not self._is_held(held, t_s)]:
            del self._held[axis]
        return Demand.from_values({axis: held.direction for axis, held in self._held.items()})

    def _is_held(self, held: _HeldKey, t_s: float) -> bool:
        window = self.repeat_hold_s if held.repeated else self.first_hold_s
        return t_s - held.last_s <= window
