"""A gamepad mapping file: the device's axes and buttons, their dead zones, what each drives.

The file (YAML; config/pilot/xbox.yaml is the shipped one) names Linux input event codes
(``ABS_X``, ``BTN_SOUTH``: include/uapi/linux/input-event-codes.h, as python-evdev's
``ecodes`` spells them) or gives them as integers::

    name: Xbox-style gamepad
    axes:                       # sensor_msgs/Joy axes, in this order
      - {name: left_x, code: ABS_X, dead_zone: 0.1}   # min/max: the device's unless given
      - {name: lt, code: ABS_Z, dead_zone: 0.05, unipolar: true}
    buttons:                    # sensor_msgs/Joy buttons, in this order
      - {name: a, code: BTN_SOUTH}
    drive:                      # input axis -> a device axis, or a negative/positive pair
      surge: {axis: left_y, invert: true}
      jaw: {negative: lt, positive: rt}
    actions:                    # action -> a button, acted on when pressed
      stop: b

A bipolar axis reads -1 to 1 over [min, max], a unipolar one (a trigger) 0 to 1; within the
dead zone it reads 0, beyond it the rest of the travel is stretched back to full scale.
Every refusal is a ``MappingError`` naming the file and the field.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from uvms_pilot.command import INPUT_AXES
from uvms_pilot.errors import MappingError

#: Actions a button can trigger (the keys' names, ``uvms_pilot.keys.KEY_ACTIONS``).
ACTIONS = ('stop', 'hold', 'start_task', 'cancel_task', 'gear_up', 'gear_down',
           'gear_1', 'gear_2', 'gear_3')
#: Largest dead zone (fraction of the half travel): beyond it an axis would barely move.
MAX_DEAD_ZONE = 0.9


@dataclass(frozen=True)
class AxisSpec:
    """One device axis: its event code, range (None: the device's) and dead zone."""

    name: str
    code: int
    dead_zone: float = 0.0
    minimum: int | None = None
    maximum: int | None = None
    unipolar: bool = False


@dataclass(frozen=True)
class ButtonSpec:
    """One device button: its event code."""

    name: str
    code: int


@dataclass(frozen=True)
class DriveSpec:
    """What drives one input axis: a device axis (maybe inverted), or a negative/positive pair.

    The pair's members are buttons (0 or 1) or unipolar axes (0 to 1); the input is
    positive - negative.
    """

    axis: str | None = None
    invert: bool = False
    negative: str | None = None
    positive: str | None = None


@dataclass(frozen=True)
class GamepadMapping:
    """A parsed mapping file."""

    name: str
    axes: tuple[AxisSpec, ...]
    buttons: tuple[ButtonSpec, ...]
    drive: dict[str, DriveSpec]
    actions: dict[str, str]
    source: str = '<mapping>'


def evdev_codes() -> dict[str, int]:
    """Linux input event code names -> codes, as python-evdev has them."""
    from evdev import ecodes

    return dict(ecodes.ecodes)


def load_mapping(path: str | Path, codes: Mapping[str, int] | None = None) -> GamepadMapping:
    """Read and check a mapping file.

    Args:
        path: The YAML file.
        codes: Event code names -> codes (None: python-evdev's).

    Raises:
        MappingError: The file is missing, not YAML, or a field is wrong (named).
    """
    source = str(path)
    try:
        data = yaml.safe_load(Path(path).read_text())
    except OSError as exc:
        msg = f'{source}: cannot read the gamepad mapping: {exc.strerror or exc}'
        raise MappingError(msg) from None
    except yaml.YAMLError as exc:
        msg = f'{source}: not YAML: {exc}'
        raise MappingError(msg) from None
    return parse_mapping(data, source, codes)


def parse_mapping(data: Any, source: str = '<mapping>',
                  codes: Mapping[str, int] | None = None) -> GamepadMapping:
    """Check a mapping read from YAML (see the module docstring); ``source`` names it.

    Raises:
        MappingError: A field is missing or wrong; the message names it.
    """
    def fail(field: str, problem: str) -> MappingError:
        return MappingError(f'{source}: {field}: {problem}')

    if not isinstance(data, dict):
        raise fail('top level', 'expected a mapping with axes, buttons, drive, actions')
    unknown = set(data) - {'name', 'axes', 'buttons', 'drive', 'actions'}
    if unknown:
        raise fail(', '.join(sorted(unknown)),
                   'unknown field(s); known: name, axes, buttons, drive, actions')
    code_of = _code_lookup(codes if codes is not None else evdev_codes(), fail)
    axes = tuple(_axis(entry, f'axes[{i}]', code_of, fail)
                 for i, entry in enumerate(_list(data, 'axes', fail)))
    buttons = tuple(_button(entry, f'buttons[{i}]', code_of, fail)
                    for i, entry in enumerate(_list(data, 'buttons', fail)))
    names = [spec.name for spec in axes] + [spec.name for spec in buttons]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise fail('axes/buttons', f'names used twice: {", ".join(twice)}')
    axis_names = {spec.name for spec in axes}
    pair_names = {spec.name for spec in buttons} | {s.name for s in axes if s.unipolar}
    drive = _drive(data.get('drive', {}), axis_names, pair_names, fail)
    actions = _actions(data.get('actions', {}), {spec.name for spec in buttons}, fail)
    name = data.get('name', Path(source).stem)
    if not isinstance(name, str):
        raise fail('name', f'expected text, got {name!r}')
    return GamepadMapping(name, axes, buttons, drive, actions, source)


Fail = Callable[[str, str], MappingError]


def _code_lookup(codes: Mapping[str, int], fail: Fail) -> Callable[[Any, str, str], int]:
    def code_of(value: Any, field: str, prefix: str) -> int:
        if isinstance(value, bool):
            raise fail(field, f'expected an event code name ({prefix}...) or a number')
        if isinstance(value, int):
            if not 0 <= value < 0x300:
                raise fail(field, f'event code {value} is out of range 0..0x2ff')
            return value
        if isinstance(value, str) and value.startswith(prefix) and value in codes:
            return int(codes[value])
        raise fail(field, f'unknown event code {value!r} (expected {prefix}... as in '
                          'linux/input-event-codes.h, or a number)')
    return code_of


def _list(data: dict[str, Any], key: str, fail: Fail) -> list[Any]:
    value = data.get(key, [])
    if not isinstance(value, list):
        raise fail(key, f'expected a list, got {type(value).__name__}')
    return value


def _fields(entry: Any, field: str, allowed: set[str], fail: Fail) -> dict[str, Any]:
    if not isinstance(entry, dict):
        raise fail(field, f'expected a mapping with {", ".join(sorted(allowed))}')
    unknown = set(entry) - allowed
    if unknown:
        raise fail(f'{field}.{sorted(unknown)[0]}',
                   f'unknown field; known: {", ".join(sorted(allowed))}')
    name = entry.get('name')
    if not isinstance(name, str) or not name:
        raise fail(f'{field}.name', 'expected a name (text)')
    if 'code' not in entry:
        raise fail(f'{field}.code', 'missing (an event code name or number)')
    return entry


def _axis(entry: Any, field: str, code_of: Callable[[Any, str, str], int],
          fail: Fail) -> AxisSpec:
    entry = _fields(entry, field,
                    {'name', 'code', 'dead_zone', 'min', 'max', 'unipolar'}, fail)
    dead_zone = entry.get('dead_zone', 0.0)
    if isinstance(dead_zone, bool) or not isinstance(dead_zone, int | float) or not (
            0.0 <= dead_zone <= MAX_DEAD_ZONE):
        raise fail(f'{field}.dead_zone',
                   f'expected a fraction 0 to {MAX_DEAD_ZONE}, got {dead_zone!r}')
    bounds: list[int | None] = []
    for key in ('min', 'max'):
        value = entry.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, int)):
            raise fail(f'{field}.{key}', f'expected an integer (raw device units), got {value!r}')
        bounds.append(value)
    if bounds[0] is not None and bounds[1] is not None and bounds[1] <= bounds[0]:
        raise fail(f'{field}.max', f'must exceed min ({bounds[0]}), got {bounds[1]}')
    unipolar = entry.get('unipolar', False)
    if not isinstance(unipolar, bool):
        raise fail(f'{field}.unipolar', f'expected true or false, got {unipolar!r}')
    return AxisSpec(entry['name'], code_of(entry['code'], f'{field}.code', 'ABS_'),
                    float(dead_zone), bounds[0], bounds[1], unipolar)


def _button(entry: Any, field: str, code_of: Callable[[Any, str, str], int],
            fail: Fail) -> ButtonSpec:
    entry = _fields(entry, field, {'name', 'code'}, fail)
    return ButtonSpec(entry['name'], code_of(entry['code'], f'{field}.code', 'BTN_'))


def _drive(data: Any, axis_names: set[str], pair_names: set[str],
           fail: Fail) -> dict[str, DriveSpec]:
    if not isinstance(data, dict):
        raise fail('drive', 'expected a mapping of input axis -> {axis: NAME} or '
                            '{negative: NAME, positive: NAME}')
    drive = {}
    for target, spec in data.items():
        field = f'drive.{target}'
        if target not in INPUT_AXES:
            raise fail(field, f'unknown input axis; known: {", ".join(INPUT_AXES)}')
        if not isinstance(spec, dict) or not spec:
            raise fail(field, 'expected {axis: NAME, invert: BOOL} or '
                              '{negative: NAME, positive: NAME}')
        if 'axis' in spec:
            if set(spec) - {'axis', 'invert'}:
                raise fail(field, 'an axis entry takes only axis and invert')
            if spec['axis'] not in axis_names:
                raise fail(f'{field}.axis', f'no axis named {spec["axis"]!r} in axes')
            if not isinstance(spec.get('invert', False), bool):
                raise fail(f'{field}.invert', f'expected true or false, got {spec["invert"]!r}')
            drive[target] = DriveSpec(axis=spec['axis'], invert=spec.get('invert', False))
            continue
        if set(spec) - {'negative', 'positive'}:
            raise fail(field, 'expected {axis: NAME, invert: BOOL} or '
                              '{negative: NAME, positive: NAME}')
        for side in ('negative', 'positive'):
            if side in spec and spec[side] not in pair_names:
                raise fail(f'{field}.{side}',
                           f'no button or unipolar axis named {spec[side]!r}')
        drive[target] = DriveSpec(negative=spec.get('negative'), positive=spec.get('positive'))
    return drive


def _actions(data: Any, button_names: set[str], fail: Fail) -> dict[str, str]:
    if not isinstance(data, dict):
        raise fail('actions', 'expected a mapping of action -> button name')
    for action, button in data.items():
        if action not in ACTIONS:
            raise fail(f'actions.{action}', f'unknown action; known: {", ".join(ACTIONS)}')
        if button not in button_names:
            raise fail(f'actions.{action}', f'no button named {button!r} in buttons')
    return dict(data)
