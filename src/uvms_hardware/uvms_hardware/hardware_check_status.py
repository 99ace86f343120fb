"""What ``uvms hardware check`` knows beside the devices: running bridges, its bounds, its lines.

No ROS here: ``hardware_check_graph`` fills `BridgeStatus` from ``/diagnostics``; the device
checks (``hardware_check``, ``hardware_check_ardusub``, ``hardware_check_alpha5``) read it to
tell what a device should look like: disarmed with no bridge, armed while an ardusub_bridge is
active; an arm joint at rest with no bridge, in Current mode while an alpha5_bridge drives it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

#: One line of output.
Say = Callable[[str], None]

#: Levels of diagnostic_msgs/DiagnosticStatus.
LEVEL_NAMES = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}


@dataclass(frozen=True)
class BridgeStatus:
    """A bridge's last ``/diagnostics`` status (its base adds the lifecycle state).

    Attributes:
        name: The bridge node's name (``alpha5_bridge``).
        state: Its lifecycle state (``active``, ``inactive``, ``unconfigured``, ...).
        level: 0 OK, 1 WARN, 2 ERROR, 3 STALE.
        message: The status line.
        values: Its key/values, as strings.
    """

    name: str
    state: str
    level: int
    message: str
    values: Mapping[str, str] = field(default_factory=dict)

    @property
    def active(self) -> bool:
        """True while the bridge drives or streams its device."""
        return self.state == 'active'

    def describe(self) -> str:
        """``alpha5_bridge active, ERROR: tripped: ...``."""
        return f'{self.name} {self.state}, {LEVEL_NAMES.get(self.level, self.level)}: ' \
               f'{self.message}'


#: Bridge node name -> its status; bridges not running are absent.
Graph = Mapping[str, BridgeStatus]


@dataclass(frozen=True)
class CheckBounds:
    """How long the check waits for each device, whatever the hardware file's start-up waits.

    The bridges' ``heartbeat_timeout_s`` / ``connect_timeout_s`` / ``startup_wait_s`` are how
    long a *launch* waits for devices that start with it (30 s in ``twin.yaml``); the check
    asks devices that are either there or not.

    Attributes:
        wait_s: For a device's first answer: a HEARTBEAT, a DVL connection, a bottom lock, an
            RDT record (s).
        reply_s: For each answer after that: a MAVLink parameter, an Alpha 5 REQUEST (s).
        retries: Tries of a MAVLink parameter read and of an Alpha 5 REQUEST.
    """

    wait_s: float = 3.0
    reply_s: float = 0.3
    retries: int = 2

    def __post_init__(self) -> None:
        """Positive, finite waits; at least one try."""
        for name in ('wait_s', 'reply_s'):
            value = getattr(self, name)
            if not 0.0 < value < float('inf'):
                raise ValueError(f'{name} = {value!r}: expected seconds > 0')
        if self.retries < 1:
            raise ValueError(f'retries = {self.retries}: expected >= 1')


class Device:
    """One device's lines: its name first, a PROBLEM counted, a warning said."""

    def __init__(self, short: str, say: Say) -> None:
        self.short = short
        self._say = say
        self.problems = 0

    def info(self, text: str) -> None:
        """A line of what was found."""
        self._say(f'{self.short}: {text}')

    def warn(self, text: str) -> None:
        """Something to know that does not stop the bridge."""
        self._say(f'{self.short}: warning: {text}')

    def problem(self, text: str) -> None:
        """What stops the bridge (or shows it stopped): counted."""
        self.problems += 1
        self._say(f'{self.short}: PROBLEM: {text}')
