"""Node health on ``/diagnostics``, as diagnostic_updater publishes it (which has no wheel).

A node builds one `DiagnosticsPublisher` and adds its checks; once per period of the node's
clock every check is called and the results go out as one ``diagnostic_msgs/DiagnosticArray``
on the absolute topic ``/diagnostics``, each status named ``"<node name>: <task name>"`` with
the robot's name as hardware_id, as Jazzy's diagnostic_updater names them. The node keeps
plain counters; a check turns them into a `Report` (`RateMeter` gives rates per second).

API (everything a node needs)::

    diagnostics = DiagnosticsPublisher(node, hardware_id=robot_name(urdf_text), period_s=1.0)
    diagnostics.add('allocation', check)  # check() -> Report(level, message, values)
    # Report(OK, 'running', {'rate_hz': 499.8, 'rejected': 0}); levels OK/WARN/ERROR/STALE
    diagnostics.update()                  # publish now (the timer calls it once a period)
    diagnostics.destroy()                 # timer and publisher gone (before destroy_node)

A check that raises gives an ERROR status naming the exception; the node goes on.
"""

from __future__ import annotations

import math
import os
import re
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.timer import Timer

__all__ = ['DEFAULT_HARDWARE_ID', 'ERROR', 'OK', 'STALE', 'TOPIC', 'WARN', 'DiagnosticsPublisher',
           'RateMeter', 'Report', 'format_value', 'robot_name']

#: Levels as diagnostic_msgs defines them (bytes, as rclpy maps the ``byte`` fields).
OK: bytes = DiagnosticStatus.OK
WARN: bytes = DiagnosticStatus.WARN
ERROR: bytes = DiagnosticStatus.ERROR
STALE: bytes = DiagnosticStatus.STALE
_LEVELS = (OK, WARN, ERROR, STALE)
#: The topic every node reports on (absolute, as diagnostic_aggregator reads it).
TOPIC = '/diagnostics'
#: hardware_id of a node without robot parameters (the URDF's robot name).
DEFAULT_HARDWARE_ID = 'uvms'

_ROBOT_NAME = re.compile(r'<robot\b[^>]*?\bname\s*=\s*["\']([^"\']+)["\']')


@dataclass(frozen=True)
class Report:
    """What one check found.

    Attributes:
        level: OK, WARN, ERROR or STALE.
        message: One line for a person (``'running'``, ``'2 lockstep timeouts'``).
        values: Key/values shown beside it, in order; units in the key (``rate_hz``).
    """

    level: bytes
    message: str
    values: Mapping[str, Any] = field(default_factory=dict)


def format_value(value: Any) -> str:
    """A value as a KeyValue string: floats with 4 significant digits, None as ``'none'``.

    >>> [format_value(v) for v in (499.8123, 0.000123456, True, None, 3, 'run.mcap')]
    ['499.8', '0.0001235', 'true', 'none', '3', 'run.mcap']
    """
    if value is None:
        return 'none'
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, float):
        return f'{value:.4g}' if math.isfinite(value) else str(value)
    return str(value)


def robot_name(urdf_text: str | None) -> str:
    """The ``<robot name=...>`` of a URDF, the hardware_id; `DEFAULT_HARDWARE_ID` without one.

    >>> robot_name('<?xml version="1.0"?><robot name="bluerov_alpha"><link name="a"/></robot>')
    'bluerov_alpha'
    >>> robot_name(None)
    'uvms'
    """
    match = _ROBOT_NAME.search(urdf_text or '')
    return match.group(1) if match else DEFAULT_HARDWARE_ID


class RateMeter:
    """Events per second of a growing counter between two reads (one diagnostics period).

    >>> meter = RateMeter()
    >>> meter.rate_hz(10, 1_000_000_000) is None  # the first read has no interval
    True
    >>> meter.rate_hz(510, 2_000_000_000)
    500.0
    """

    def __init__(self) -> None:
        """Start without a previous read."""
        self._count: float | None = None
        self._t_ns = 0

    def rate_hz(self, count: float, now_ns: int) -> float | None:
        """Growth of ``count`` per second of clock time since the last read; None at first.

        Args:
            count: The counter now (events, or any growing quantity such as seconds).
            now_ns: Clock time of this read (ns), from the clock the period runs on.
        """
        previous, previous_ns = self._count, self._t_ns
        self._count, self._t_ns = count, now_ns
        if previous is None or now_ns <= previous_ns:
            return None
        return (count - previous) * 1e9 / (now_ns - previous_ns)


class _ProcessCpu:
    """CPU of this process (every thread) in % of one core since the previous read."""

    def __init__(self) -> None:
        self._last = (time.monotonic(), self._cpu_s())

    @staticmethod
    def _cpu_s() -> float:
        times = os.times()
        return times.user + times.system

    def percent(self) -> float | None:
        """% of a core since the last read (None when no wall time passed)."""
        now, cpu = time.monotonic(), self._cpu_s()
        (then, before), self._last = self._last, (now, cpu)
        return 100.0 * (cpu - before) / (now - then) if now > then else None


class DiagnosticsPublisher:
    """The node's checks, published as one DiagnosticArray on `TOPIC` once a period.

    The period runs on the node's clock (simulated time under ``use_sim_time``), as
    diagnostic_updater's timer does. Every node also reports ``"<node>: process"``: CPU % of
    a core of its process (wall time), and the periods its ``MissCounter`` objects counted
    (``uvms_common.realtime.process_periods``: missed, worst lateness).
    """

    def __init__(self, node: Node, hardware_id: str = DEFAULT_HARDWARE_ID,
                 period_s: float = 1.0) -> None:
        """Create the publisher and the timer.

        Args:
            node: The node reporting; its name prefixes every status name.
            hardware_id: The robot's name (`robot_name` of its URDF).
            period_s: Time between two publications on the node clock (s), > 0.

        Raises:
            ValueError: A period that is not a positive finite number.
        """
        if not (math.isfinite(period_s) and period_s > 0.0):
            msg = f'diagnostics period_s = {period_s!r}: valid: a positive number of seconds'
            raise ValueError(msg)
        self._node = node
        self.hardware_id = hardware_id
        self._checks: list[tuple[str, Callable[[], Report]]] = []
        self._publisher = node.create_publisher(
            DiagnosticArray, TOPIC, QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
        self._timer: Timer | None = node.create_timer(period_s, self.update)
        self._cpu = _ProcessCpu()

    def add(self, task_name: str, check: Callable[[], Report]) -> None:
        """Report ``check()`` as status ``"<node name>: <task_name>"`` every period."""
        self._checks.append((task_name, check))

    def update(self) -> DiagnosticArray:
        """Run every check and publish their statuses now; return the published array."""
        array = DiagnosticArray()
        array.header.stamp = self._node.get_clock().now().to_msg()
        checks = [*self._checks, ('process', self._process_report)]
        array.status = [self._status(name, check) for name, check in checks]
        self._publisher.publish(array)
        return array

    def _process_report(self) -> Report:
        """What the node's process costs: CPU % of a core, missed periods, worst lateness."""
        from uvms_common.realtime import process_periods

        periods = process_periods()
        return Report(OK, 'running', {'cpu_percent': self._cpu.percent(), **periods})

    def destroy(self) -> None:
        """Remove the timer and the publisher from the node (idempotent)."""
        if self._timer is not None:
            self._node.destroy_timer(self._timer)
            self._node.destroy_publisher(self._publisher)
            self._timer = None

    def _status(self, task_name: str, check: Callable[[], Report]) -> DiagnosticStatus:
        try:
            report = check()
            if report.level not in _LEVELS:
                msg = f'level {report.level!r}: valid: OK, WARN, ERROR, STALE (bytes)'
                raise ValueError(msg)
            level, message = report.level, str(report.message)
            values = [KeyValue(key=str(key), value=format_value(value))
                      for key, value in report.values.items()]
        except Exception as exc:  # a broken check must not stop the node
            level, message, values = ERROR, f'check failed: {type(exc).__name__}: {exc}', []
            self._node.get_logger().error(f'diagnostics {task_name!r}: {message}',
                                          throttle_duration_sec=10.0)
        return DiagnosticStatus(level=level, name=f'{self._node.get_name()}: {task_name}',
                                message=message, hardware_id=self.hardware_id, values=values)
