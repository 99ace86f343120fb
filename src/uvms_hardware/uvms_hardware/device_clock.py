"""The clock a bridge talks to its device on: the steady clock, whatever the node's clock is.

A device's watchdog, poll period and link timeouts are wall-time facts of the wire. With
``use_sim_time`` (a bridge beside the simulator and the twins, ``uvms launch --hardware
twin``) the node's clock is ``/clock``, which stands still while the simulator holds its first
state until the loop is closed: timers on it would never fire, the bridge would never poll
its device, and the loop would never close. So every bridge polls, sends and times out on the
steady clock and only stamps its messages with the node clock::

    steady = DeviceClock(node)
    node.create_timer(period_s, callback, clock=steady.clock)
    t_s = steady.now_s()
"""

from __future__ import annotations

import time

from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from uvms_common.stop_event import active_stop_event


class DeviceClock:
    """The steady clock of a bridge: its timers and its device-side times (s)."""

    def __init__(self, node: Node) -> None:
        self.clock = Clock(clock_type=ClockType.STEADY_TIME)
        self._node = node

    def now_s(self) -> float:
        """Seconds on the steady clock (an arbitrary epoch: only differences mean anything).

        ``CLOCK_MONOTONIC``, which the steady ``clock`` reads too: the same value as
        ``clock.now().nanoseconds * 1e-9`` without an rclpy ``Time`` built per call.
        """
        return time.monotonic_ns() * 1e-9

    def timer(self, period_s: float, callback: object) -> object:
        """A timer of the node on the steady clock."""
        return self._node.create_timer(period_s, callback, clock=self.clock)  # type: ignore[arg-type]


def stop_requested() -> bool:
    """Whether SIGINT/SIGTERM asked this process to stop: a bridge's waits end at once."""
    event = active_stop_event()
    return event is not None and event.is_set()
