"""What an earlier ardusub_bridge left changed on the vehicle, and the command that restores it.

A bridge killed while in RC passthrough (SIGKILL, out of memory, power) leaves thruster
outputs at RCIN1..8 (51..58), saved in the autopilot, and its journal (``device_journal``)
with the original values. `find_leftovers` reads them at configure (the bridge refuses to
activate over them) and in ``uvms hardware check``; `restore_leftovers` is ``uvms hardware
restore ardusub``: the same `ArduSubLink.restore` a bridge runs at its stop (neutral, disarm,
overrides released, then the functions set and read back, within the restore budget), the
journal removed once every value was read back. No ROS.
"""

from __future__ import annotations

import re
import shlex
from collections.abc import Callable
from dataclasses import dataclass

from uvms_hardware.ardusub_link import (
    K_MOTOR1,
    ArduSubLink,
    LinkSettings,
    is_rcin,
    servo_function,
)
from uvms_hardware.device_journal import DeviceJournal
from uvms_hardware.errors import DeviceCheckError
from uvms_hardware.hardware_config import hardware_section
from uvms_hardware.t200_curve import T200Curve

#: What the firmware sets on outputs 1..8 of the BlueROV2 frames: Motor1..8 (33..40).
FIRMWARE_DEFAULTS = 'the firmware defaults Motor1..8 = 33..40'


@dataclass(frozen=True)
class Leftovers:
    """Outputs left changed: their values now, what to put back, and where that comes from."""

    now: dict[int, float]
    restore_to: dict[int, float]
    source: str

    def describe(self) -> str:
        """``SERVO1_FUNCTION = 51 (restore 33), ...`` and the values' source."""
        values = ', '.join(f'{servo_function(o)} = {self.now[o]:g} (restore '
                           f'{self.restore_to[o]:g})' for o in sorted(self.now))
        return f'{values}; the values to restore are {self.source}'


def restore_command(url: str, journal_dir: str = '') -> str:
    """The one command that restores what a bridge on ``url`` left changed."""
    command = f'uvms hardware restore ardusub --url {shlex.quote(url)}'
    return command + (f' --journal-dir {shlex.quote(journal_dir)}' if journal_dir else '')


def find_leftovers(link: ArduSubLink) -> Leftovers | None:
    """Thruster outputs at RCIN1..8, or not at their journalled value; None when none.

    Reads the thruster outputs' SERVOn_FUNCTIONs and any other output the journal names.
    Changes nothing (a journal that matches the vehicle is left for the caller to remove).

    Raises:
        DeviceCheckError: an output that does not answer (named).
        JournalError: a journal that cannot be read.
    """
    journal = link.journal.read()
    journalled = {int(m.group(1)): value for name, value in (journal or {}).items()
                  if (m := re.fullmatch(r'SERVO(\d+)_FUNCTION', name))}
    outputs = sorted(set(link.settings.thruster_channels) | set(journalled))
    now: dict[int, float] = {}
    for output in outputs:
        value = link.read_param(servo_function(output))
        if value is None:
            raise DeviceCheckError(f'{servo_function(output)} not answered: cannot check for '
                                   'thruster outputs left in RC passthrough')
        now[output] = value
    left = {o: v for o, v in now.items()
            if is_rcin(v) or (o in journalled and v != journalled[o])}
    if not left:
        return None
    restore_to = {o: journalled.get(o, float(K_MOTOR1 + o - 1)) for o in left}
    from_journal = [o for o in left if o in journalled]
    if len(from_journal) == len(left):
        source = f'from the journal {link.journal.path}'
    elif not from_journal:
        source = f'{FIRMWARE_DEFAULTS} (no journal at {link.journal.path})'
    else:
        source = (f'from the journal {link.journal.path} for outputs {sorted(from_journal)}, '
                  f'{FIRMWARE_DEFAULTS} for the others')
    return Leftovers(left, restore_to, source)


def leftovers_refusal(leftovers: Leftovers, url: str, journal_dir: str = '') -> str:
    """The configure refusal over leftovers: what, what to restore, and the one command."""
    return (f'thruster outputs left in RC passthrough by a run that did not end cleanly (a '
            f'crash or a kill): {leftovers.describe()}. Restore them with: '
            f'{restore_command(url, journal_dir)}')


def restore_leftovers(link: ArduSubLink, say: Callable[[str], None]) -> int:
    """Put back what an earlier run left changed on a found vehicle; the problems met.

    Neutral, disarm, release, then every leftover SERVOn_FUNCTION set and read back, within
    the link's restore budget; the journal is removed once everything was read back.
    """
    leftovers = find_leftovers(link)
    if leftovers is None:
        link.journal.remove()
        say('ardusub: nothing left changed: every thruster output has its own function')
        return 0
    say(f'ardusub: restoring {leftovers.describe()}')
    link.changed_functions = dict(leftovers.restore_to)
    start_s = link.clock()
    problems = link.restore()
    elapsed_s = link.clock() - start_s
    for problem in problems:
        say(f'ardusub: PROBLEM: {problem}')
    if problems or link.changed_functions:
        return max(len(problems), 1)
    say(f'ardusub: restored and read back in {elapsed_s:.2f} s; journal '
        f'{link.journal.path} removed')
    return 0


def restore_ardusub(robot: str, url: str, say: Callable[[str], None], gcs_system_id: int = 255,
                    journal_dir: str = '', heartbeat_timeout_s: float = 10.0) -> int:
    """``uvms hardware restore ardusub``: find the vehicle, restore its leftovers; problems."""
    _, section = hardware_section(robot, 'ardusub')
    settings = LinkSettings(url, tuple(int(c) for c in section['thruster_channels']),
                            tuple(int(d) for d in section['thruster_directions']),
                            gcs_system_id)
    link = ArduSubLink(settings, T200Curve.from_section(section['t200']),
                       journal=DeviceJournal.for_device('ardusub', url, journal_dir))
    try:
        link.open()
        link.wait_vehicle(heartbeat_timeout_s)
        return restore_leftovers(link, say)
    finally:
        link.close()
