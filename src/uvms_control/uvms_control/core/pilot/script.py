"""A pilot session as a file: timed commands played on the control clock (lockstep).

A script is a YAML list (a scenario's ``pilot:`` key, or a file it names); each entry holds a
command from ``at_s`` (simulated s) for ``for_s`` (s), repeated at every control step as a
stick held would send it, then nothing (the deadman releases it)::

    - {at_s: 1.0, for_s: 5.0, vehicle: [0.2, 0, 0, 0, 0, 0]}   # body twist: m/s, rad/s
    - {at_s: 7.0, for_s: 3.0, ee: [0, 0, 0.02], frame: base_link_frd}  # m/s; or map_ned
    - {at_s: 9.0, for_s: 1.0, jaw: -0.01}                      # m/s, + opens
    - {at_s: 12.0, hold: true}                                 # the hold service, once

Commands go through the same checks and limits as messages (``inputs``), stamped with the
step's time: a script is a pilot session that runs the same every time.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from uvms_control.core.errors import ControlParameterError

_KEYS = {'at_s', 'for_s', 'vehicle', 'ee', 'frame', 'jaw', 'hold'}


@dataclass(frozen=True)
class ScriptCommand:
    """One timed command of a pilot script.

    Attributes:
        at_s: start (s, controller clock).
        for_s: how long it is sent (s); 0 for a hold.
        vehicle: body twist [vx, vy, vz, wx, wy, wz] (m/s, rad/s) or None.
        ee: end-effector velocity [vx, vy, vz] (m/s) or None.
        frame: the end-effector velocity's frame.
        jaw: jaw speed (m/s) or None.
        hold: ask for hold at at_s.
    """

    at_s: float
    for_s: float = 0.0
    vehicle: tuple[float, ...] | None = None
    ee: tuple[float, ...] | None = None
    frame: str = 'base_link_frd'
    jaw: float | None = None
    hold: bool = False

    def active(self, t_s: float) -> bool:
        """The command is sent at t_s (s)."""
        return self.at_s <= t_s < self.at_s + self.for_s


def _numbers(entry: dict[str, Any], key: str, size: int, where: str) -> tuple[float, ...] | None:
    value = entry.get(key)
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != size or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        raise ControlParameterError(f'{where}.{key}', value, f'a list of {size} numbers')
    return tuple(float(v) for v in value)  # NaN and huge values are the checks' job


def parse_script(data: Any, where: str = 'pilot.script') -> tuple[ScriptCommand, ...]:
    """The commands of a script document (a list of mappings), sorted by at_s.

    Raises:
        ControlParameterError: naming the entry and key that is wrong.
    """
    if data is None:
        return ()
    if not isinstance(data, list):
        raise ControlParameterError(where, data, 'a list of timed commands')
    commands = []
    for i, entry in enumerate(data):
        at = f'{where}[{i}]'
        if not isinstance(entry, dict) or set(entry) - _KEYS:
            raise ControlParameterError(at, entry, f'a mapping of {sorted(_KEYS)}')
        start, duration = entry.get('at_s'), entry.get('for_s', 0.0)
        for key, value in (('at_s', start), ('for_s', duration)):
            if isinstance(value, bool) or not isinstance(value, int | float) or not (
                    math.isfinite(value) and value >= 0.0):
                raise ControlParameterError(f'{at}.{key}', value, 'a number of seconds >= 0')
        jaw = entry.get('jaw')
        if jaw is not None and (isinstance(jaw, bool) or not isinstance(jaw, int | float)):
            raise ControlParameterError(f'{at}.jaw', jaw, 'a number (m/s)')
        hold = entry.get('hold', False)
        if not isinstance(hold, bool):
            raise ControlParameterError(f'{at}.hold', hold, 'true or false')
        frame = entry.get('frame', 'base_link_frd')
        if not isinstance(frame, str):
            raise ControlParameterError(f'{at}.frame', frame, 'a frame name')
        command = ScriptCommand(float(start or 0.0), float(duration),
                                _numbers(entry, 'vehicle', 6, at), _numbers(entry, 'ee', 3, at),
                                frame,
                                None if jaw is None else float(jaw), hold)
        if not hold and command.vehicle is None and command.ee is None and jaw is None:
            raise ControlParameterError(at, entry, 'vehicle, ee, jaw or hold: true')
        commands.append(command)
    return tuple(sorted(commands, key=lambda c: c.at_s))


def script_text(value: Any, directory: Path) -> str:
    """A scenario's ``pilot:`` (a list of commands, or a file of one) as ``pilot.script`` text.

    Args:
        value: the list, or the name of a YAML file holding it (relative to ``directory``).
        directory: where a relative file name is looked up (the scenario's folder).

    Raises:
        ControlParameterError: a file that cannot be read or is not YAML, or a wrong entry,
            named (``pilot[1].vehicle``).
    """
    where = 'pilot'
    if isinstance(value, str):
        path = Path(value) if Path(value).is_absolute() else directory / value
        where = f'pilot ({path})'
        try:
            value = yaml.safe_load(path.read_text(encoding='utf-8'))
        except (OSError, yaml.YAMLError) as error:
            raise ControlParameterError(where, str(path),
                                        f'a readable YAML pilot script: {error}') from error
    parse_script(value, where)
    return yaml.safe_dump(value, default_flow_style=None, sort_keys=False)


def load_script_text(text: str) -> tuple[ScriptCommand, ...]:
    """The commands of a script's YAML text ('' : none).

    Raises:
        ControlParameterError: not YAML, or a wrong entry.
    """
    if not text.strip():
        return ()
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise ControlParameterError('pilot.script', text[:80], f'YAML text: {error}') from error
    return parse_script(data)


class ScriptPlayer:
    """Plays a script: the commands to send at each step, each hold once."""

    def __init__(self, commands: Sequence[ScriptCommand]) -> None:
        self.commands = tuple(commands)
        self._held: set[int] = set()

    def due(self, t_s: float) -> list[ScriptCommand]:
        """The commands to send at t_s (s): the active ones and holds not sent yet."""
        due = []
        for i, command in enumerate(self.commands):
            if command.hold:
                if t_s >= command.at_s and i not in self._held:
                    self._held.add(i)
                    due.append(command)
            elif command.active(t_s):
                due.append(command)
        return due
