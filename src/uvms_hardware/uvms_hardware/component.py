"""A device as a hardware component, as ros2_control loads them: no ROS, no waiting per period.

Each device of the robot (Net F/T, DVL, ArduSub, ...) is one `HardwareComponent`. Its
lifecycle is ros2_control's; who runs it (a bridge node, ``uvms_hardware.bridge_node``, or one
real-time loop over several components) calls::

    component.configure()              # find and check the device; HardwareError refuses
    component.activate()               # change the device (journal first): now driven/streamed
    while running:
        component.read(now_s)          # drain the socket, never blocks; state() updated
        ...                            # estimate, control
        component.write(now_s, cmds)   # actuators only (sensors: nothing)
        component.report(now_s)        # /diagnostics: level, message, values
    problems = component.put_back()    # deactivate: neutral, restored; the problems met
    component.release()                # cleanup: close the link

``now_s`` is the steady clock (s): the device's watchdog, periods and timeouts are wall-time
facts of the wire. Each component keeps its own watchdog: a device that is silent is never
returned as fresh by `state` (``fresh`` False) and is an ERROR in `report`.

Messages go through ``log(level, text)`` (``'info'``, ``'warning'``, ``'error'``): a node
passes its logger, a test a list; `Throttle` keeps a repeating warning to one in a while.
"""

from __future__ import annotations

import logging
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ['ERROR', 'OK', 'WARN', 'ComponentReport', 'HardwareComponent', 'LogFn', 'Throttle',
           'logger_log', 'python_log']

#: Report levels, as diagnostic_msgs/DiagnosticStatus numbers them (0 OK, 1 WARN, 2 ERROR).
OK, WARN, ERROR = 0, 1, 2

#: ``log(level, text)``: level is 'info', 'warning' or 'error'.
LogFn = Callable[[str, str], None]

_LOGGER = logging.getLogger('uvms_hardware')


def python_log(level: str, text: str) -> None:
    """The default `LogFn`: Python's logging (logger ``uvms_hardware``)."""
    _LOGGER.log({'info': logging.INFO, 'warning': logging.WARNING}.get(level, logging.ERROR),
                text)


def logger_log(logger: Any) -> LogFn:
    """A `LogFn` onto a logger with ``info``/``warning``/``error`` (a node's, rclpy's).

    One call site per level: rclpy's logger refuses a call site whose severity changes.
    """
    def log(level: str, text: str) -> None:
        if level == 'info':
            logger.info(text)
        elif level == 'warning':
            logger.warning(text)
        else:
            logger.error(text)
    return log


@dataclass(frozen=True)
class ComponentReport:
    """The device's health for /diagnostics.

    Attributes:
        level: `OK`, `WARN` or `ERROR`.
        message: One line.
        values: Name -> value (counters, ages in s, clock figures).
    """

    level: int
    message: str
    values: Mapping[str, object] = field(default_factory=dict)


class Throttle:
    """True at most once per ``period_s`` (s, on the caller's clock): for repeated warnings."""

    def __init__(self, period_s: float) -> None:
        self.period_s = period_s
        self._last_s = -math.inf

    def __call__(self, now_s: float) -> bool:
        """Whether to speak now (and if so, the period starts again)."""
        if now_s - self._last_s < self.period_s:
            return False
        self._last_s = now_s
        return True


class HardwareComponent(ABC):
    """One device: lifecycle, non-blocking read/write, own watchdog, restore on every way out.

    ``active`` is True between a successful `activate` and `put_back`; ``configured`` between
    `configure` and `release`. The runner guarantees `put_back` after any `activate` that was
    started (even one that raised half-way) and `release` after any `configure` started.
    """

    #: The name the device's reports and stop reports carry (the bridge node's name).
    name: str = 'device'

    def __init__(self) -> None:
        self.active = False
        self.configured = False

    # -- lifecycle ---------------------------------------------------------------------------
    @abstractmethod
    def configure(self) -> None:
        """Find the device and check it.

        Raises:
            HardwareError: Refused (also ValueError/OSError), naming what is wrong.
        """

    def activate(self) -> None:
        """Change on the device what driving or streaming it needs (journal first)."""
        self.active = True

    def put_back(self) -> list[str]:
        """Leave the device at rest and as found; what could not be done (never raises)."""
        self.active = False
        return []

    def release(self) -> None:
        """Close the link; nothing is sent to the device here."""
        self.active = False
        self.configured = False

    def deactivate(self) -> list[str]:
        """ros2_control's name for `put_back`."""
        return self.put_back()

    def cleanup(self) -> None:
        """ros2_control's name for `release`."""
        self.release()

    # -- the loop ----------------------------------------------------------------------------
    @abstractmethod
    def read(self, now_s: float) -> None:
        """Take what the device sent since the last call (never waits); update `state`."""

    def write(self, now_s: float, commands: Any = None) -> None:
        """Send the commands of this period (actuators; a sensor ignores it)."""
        return None

    @abstractmethod
    def state(self) -> Any:
        """What the device gives, as plain data (dataclasses, tuples, numpy; no messages)."""

    @abstractmethod
    def report(self, now_s: float) -> ComponentReport:
        """The device's health at ``now_s`` (steady s)."""
