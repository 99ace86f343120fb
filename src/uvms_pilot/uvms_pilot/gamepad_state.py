"""A gamepad's state from its Linux input events, read through a mapping file.

``GamepadState.apply`` takes each event as the kernel delivers it (type, code, value: an
evdev ``InputEvent``'s fields); the state then gives the sensor_msgs/Joy arrays (axes
normalized, buttons 0/1, both in the mapping's order), the pilot demand, and the actions of
the buttons pressed since the last call. No device, no ROS: tests feed it synthetic events.

Example::

    >>> state = GamepadState(mapping, {ABS_Y: (-32768, 32767)})
    >>> state.apply(EV_ABS, ABS_Y, -32768)   # left stick fully up
    []
    >>> state.demand().surge                 # with drive.surge {axis: left_y, invert: true}
    1.0
"""

from __future__ import annotations

from collections.abc import Mapping

from uvms_pilot.command import Demand
from uvms_pilot.gamepad_mapping import GamepadMapping

#: Event types of linux/input-event-codes.h (the kernel's ABI: fixed).
EV_SYN, EV_KEY, EV_ABS = 0x00, 0x01, 0x03


def normalize(raw: int, minimum: int, maximum: int, dead_zone: float, unipolar: bool) -> float:
    """A raw axis reading as -1..1 (0..1 unipolar), the dead zone cut out and the rest stretched.

    Raises:
        ValueError: maximum <= minimum.
    """
    if maximum <= minimum:
        msg = f'axis range: max {maximum} must exceed min {minimum}'
        raise ValueError(msg)
    fraction = (min(max(raw, minimum), maximum) - minimum) / (maximum - minimum)
    value = fraction if unipolar else 2.0 * fraction - 1.0
    magnitude = abs(value)
    if magnitude <= dead_zone:
        return 0.0
    stretched = min(1.0, (magnitude - dead_zone) / (1.0 - dead_zone))
    return stretched if value > 0.0 else -stretched


class GamepadState:
    """Axes and buttons of one gamepad, as its events left them.

    Args:
        mapping: The mapping file's content.
        device_ranges: Axis code -> (min, max) the device reports (evdev's absinfo); a
            mapping's own min/max win. An axis with neither is refused.

    Raises:
        ValueError: An axis of the mapping has no range (named).
    """

    def __init__(self, mapping: GamepadMapping,
                 device_ranges: Mapping[int, tuple[int, int]] | None = None) -> None:
        self.mapping = mapping
        ranges = dict(device_ranges or {})
        self._ranges: dict[str, tuple[int, int]] = {}
        for spec in mapping.axes:
            device = ranges.get(spec.code)
            low = spec.minimum if spec.minimum is not None else (device or (None, None))[0]
            high = spec.maximum if spec.maximum is not None else (device or (None, None))[1]
            if low is None or high is None:
                msg = (f'{mapping.source}: axis {spec.name}: no min/max in the file and the '
                       f'device reports no range for code {spec.code}')
                raise ValueError(msg)
            self._ranges[spec.name] = (low, high)
        self._axis_by_code = {spec.code: spec for spec in mapping.axes}
        self._button_by_code = {spec.code: spec.name for spec in mapping.buttons}
        self._action_of = {button: action for action, button in mapping.actions.items()}
        # Before its first event an axis reads centered (a trigger: released).
        self._axis_values = dict.fromkeys((spec.name for spec in mapping.axes), 0.0)
        self._pressed = dict.fromkeys((spec.name for spec in mapping.buttons), False)

    def apply(self, ev_type: int, code: int, value: int) -> list[str]:
        """Take one input event; the actions of the buttons it pressed (usually none)."""
        if ev_type == EV_ABS and code in self._axis_by_code:
            spec = self._axis_by_code[code]
            low, high = self._ranges[spec.name]
            self._axis_values[spec.name] = normalize(value, low, high, spec.dead_zone,
                                                     spec.unipolar)
        elif ev_type == EV_KEY and code in self._button_by_code:
            name = self._button_by_code[code]
            was = self._pressed[name]
            self._pressed[name] = value != 0  # 1 pressed, 2 auto-repeat, 0 released
            if self._pressed[name] and not was and name in self._action_of:
                return [self._action_of[name]]
        return []

    def release_all(self) -> None:
        """Every axis centered and every button up (the device went away)."""
        self._axis_values = dict.fromkeys(self._axis_values, 0.0)
        self._pressed = dict.fromkeys(self._pressed, False)

    @property
    def joy_axes(self) -> list[float]:
        """sensor_msgs/Joy axes: normalized, in the mapping's order."""
        return [self._axis_values[spec.name] for spec in self.mapping.axes]

    @property
    def joy_buttons(self) -> list[int]:
        """sensor_msgs/Joy buttons: 1 pressed, 0 not, in the mapping's order."""
        return [int(self._pressed[spec.name]) for spec in self.mapping.buttons]

    def _input(self, name: str | None) -> float:
        if name is None:
            return 0.0
        if name in self._pressed:
            return 1.0 if self._pressed[name] else 0.0
        return self._axis_values[name]

    def demand(self) -> Demand:
        """The pilot demand of the present state, through the mapping's drive entries."""
        values = {}
        for target, spec in self.mapping.drive.items():
            if spec.axis is not None:
                value = self._axis_values[spec.axis]
                values[target] = -value if spec.invert else value
            else:
                values[target] = self._input(spec.positive) - self._input(spec.negative)
        return Demand.from_values(values)
