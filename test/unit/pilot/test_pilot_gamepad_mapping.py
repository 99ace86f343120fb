"""Gamepad mapping: the shipped file, refusals naming the field, events to Joy and demand."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from evdev import InputEvent, ecodes
from uvms_pilot.errors import MappingError
from uvms_pilot.gamepad_mapping import load_mapping, parse_mapping
from uvms_pilot.gamepad_state import EV_ABS, EV_KEY, GamepadState, normalize

SHIPPED = Path(__file__).resolve().parents[3] / 'config' / 'pilot' / 'xbox.yaml'
#: What xpad reports for an Xbox 360 pad's axes (evdev absinfo min, max).
XPAD_RANGES = {
    ecodes.ABS_X: (-32768, 32767), ecodes.ABS_Y: (-32768, 32767),
    ecodes.ABS_RX: (-32768, 32767), ecodes.ABS_RY: (-32768, 32767),
    ecodes.ABS_Z: (0, 255), ecodes.ABS_RZ: (0, 255),
}


def feed(state: GamepadState, *events: InputEvent) -> list[str]:
    """Events as evdev delivers them, through the state; the actions they triggered."""
    actions: list[str] = []
    for event in events:
        actions += state.apply(event.type, event.code, event.value)
    return actions


def abs_event(code: int, value: int) -> InputEvent:
    """An EV_ABS event as python-evdev builds it from the kernel's struct input_event."""
    return InputEvent(0, 0, ecodes.EV_ABS, code, value)


def key_event(code: int, value: int) -> InputEvent:
    """An EV_KEY event (1 pressed, 0 released, 2 auto-repeat)."""
    return InputEvent(0, 0, ecodes.EV_KEY, code, value)


@pytest.fixture
def xbox() -> GamepadState:
    """The shipped mapping on an xpad device's ranges."""
    return GamepadState(load_mapping(SHIPPED), XPAD_RANGES)


def test_shipped_mapping_drives_every_input_axis_and_action() -> None:
    """The shipped Xbox file parses and covers all eight axes and the issue's actions."""
    mapping = load_mapping(SHIPPED)
    assert set(mapping.drive) == {'surge', 'sway', 'heave', 'yaw', 'arm_x', 'arm_y', 'arm_z',
                                  'jaw'}
    assert {'stop', 'hold', 'start_task', 'cancel_task', 'gear_up', 'gear_down'} <= set(
        mapping.actions)
    assert EV_ABS == ecodes.EV_ABS and EV_KEY == ecodes.EV_KEY


def test_stick_forward_is_full_surge_and_centered_stick_is_zero(xbox: GamepadState) -> None:
    """Left stick fully up: surge +1; back to center (within the dead zone): exactly zero."""
    feed(xbox, abs_event(ecodes.ABS_Y, -32768))
    assert xbox.demand().surge == 1.0
    feed(xbox, abs_event(ecodes.ABS_Y, 1500))  # a worn stick's rest, 4.6 % off center
    assert xbox.demand().surge == 0.0


def test_dead_zone_is_cut_and_the_rest_stretched() -> None:
    """Within the dead zone 0; at its edge still 0; halfway beyond it 0.5; full travel 1."""
    assert normalize(0, -100, 100, 0.2, False) == 0.0
    assert normalize(20, -100, 100, 0.2, False) == 0.0
    assert normalize(60, -100, 100, 0.2, False) == pytest.approx(0.5)
    assert normalize(-100, -100, 100, 0.2, False) == -1.0
    assert normalize(500, -100, 100, 0.2, False) == 1.0  # beyond the range: clipped
    assert normalize(128, 0, 255, 0.0, True) == pytest.approx(128 / 255)


def test_sticks_dpad_bumpers_and_triggers_drive_their_axes(xbox: GamepadState) -> None:
    """Each control of the shipped layout moves the input axis docs/piloting.md names."""
    feed(xbox, abs_event(ecodes.ABS_X, 32767), abs_event(ecodes.ABS_RY, -32768),
         abs_event(ecodes.ABS_RX, -32768), abs_event(ecodes.ABS_HAT0Y, -1),
         abs_event(ecodes.ABS_HAT0X, 1), key_event(ecodes.BTN_TL, 1),
         abs_event(ecodes.ABS_RZ, 255))
    demand = xbox.demand()
    assert (demand.sway, demand.heave, demand.yaw) == (1.0, -1.0, -1.0)
    assert (demand.arm_x, demand.arm_y, demand.arm_z, demand.jaw) == (1.0, 1.0, -1.0, 1.0)


def test_joy_holds_normalized_axes_and_buttons_in_mapping_order(xbox: GamepadState) -> None:
    """/joy axes and buttons follow the file's order, triggers 0..1, buttons 0/1."""
    feed(xbox, abs_event(ecodes.ABS_Z, 255), key_event(ecodes.BTN_EAST, 1))
    names = [spec.name for spec in xbox.mapping.axes]
    assert xbox.joy_axes[names.index('lt')] == 1.0
    assert len(xbox.joy_axes) == 8 and len(xbox.joy_buttons) == 11
    assert xbox.joy_buttons[1] == 1 and sum(xbox.joy_buttons) == 1


def test_button_action_fires_once_per_press(xbox: GamepadState) -> None:
    """A press triggers its action; auto-repeat and release do not."""
    assert feed(xbox, key_event(ecodes.BTN_SOUTH, 1)) == ['hold']
    assert feed(xbox, key_event(ecodes.BTN_SOUTH, 2), key_event(ecodes.BTN_SOUTH, 0)) == []
    assert feed(xbox, key_event(ecodes.BTN_START, 1), key_event(ecodes.BTN_SELECT, 1)) == [
        'start_task', 'cancel_task']


def test_release_all_returns_to_zero(xbox: GamepadState) -> None:
    """A device that goes away leaves no demand behind."""
    feed(xbox, abs_event(ecodes.ABS_Y, -32768), key_event(ecodes.BTN_TR, 1))
    xbox.release_all()
    assert not any(xbox.demand().as_tuple()) and not any(xbox.joy_buttons)


def test_axis_without_any_range_is_refused() -> None:
    """No min/max in the file and none from the device: the axis is named."""
    mapping = load_mapping(SHIPPED)
    with pytest.raises(ValueError, match='axis left_x: no min/max'):
        GamepadState(mapping, {})


def _shipped() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load(SHIPPED.read_text())
    return data


@pytest.mark.parametrize(('change', 'field'), [
    (lambda d: d['axes'][0].update(code='ABS_NOPE'), 'axes[0].code'),
    (lambda d: d['axes'][0].update(code='BTN_SOUTH'), 'axes[0].code'),
    (lambda d: d['axes'][1].update(dead_zone=1.5), 'axes[1].dead_zone'),
    (lambda d: d['axes'][6].update(max=-1), 'axes[6].max'),
    (lambda d: d['axes'][2].update(unipolar='yes'), 'axes[2].unipolar'),
    (lambda d: d['axes'][0].update(colour='red'), 'axes[0].colour'),
    (lambda d: d['buttons'][0].pop('code'), 'buttons[0].code'),
    (lambda d: d['buttons'][1].update(name='a'), 'names used twice'),
    (lambda d: d['drive'].update(roll={'axis': 'left_x'}), 'drive.roll'),
    (lambda d: d['drive'].update(surge={'axis': 'left_z'}), 'drive.surge.axis'),
    (lambda d: d['drive'].update(jaw={'negative': 'left_x'}), 'drive.jaw.negative'),
    (lambda d: d['drive']['yaw'].update(invert=1), 'drive.yaw.invert'),
    (lambda d: d['actions'].update(self_destruct='a'), 'actions.self_destruct'),
    (lambda d: d['actions'].update(hold='z'), 'actions.hold'),
    (lambda d: d.update(axis=[]), 'axis: unknown field'),
])
def test_bad_mapping_is_refused_naming_file_and_field(change: Any, field: str) -> None:
    """Every wrong field of a mapping file is one error naming the file and that field."""
    data = _shipped()
    change(data)
    with pytest.raises(MappingError) as info:
        parse_mapping(data, 'my_pad.yaml')
    assert str(info.value).startswith('my_pad.yaml: ')
    assert field in str(info.value)


def test_missing_and_broken_files_are_named(tmp_path: Path) -> None:
    """A missing file and a file that is not YAML are refused with the path."""
    with pytest.raises(MappingError, match=r'nope\.yaml: cannot read'):
        load_mapping(tmp_path / 'nope.yaml')
    broken = tmp_path / 'broken.yaml'
    broken.write_text('axes: [\n')
    with pytest.raises(MappingError, match=r'broken\.yaml: not YAML'):
        load_mapping(broken)


def test_integer_codes_are_taken_as_they_are() -> None:
    """A code given as a number (a pad with codes python-evdev has no name for) works."""
    mapping = parse_mapping({'axes': [{'name': 'x', 'code': 0, 'min': -1, 'max': 1}],
                             'drive': {'sway': {'axis': 'x'}}})
    state = GamepadState(mapping)
    state.apply(EV_ABS, 0, 1)
    assert state.demand().sway == 1.0
