"""Topics between the nodes of one process as function calls: the robot loop's wiring.

In the robot process (``uvms_hardware.robot_loop``) a device's reading reaches the estimator
and the controller, and a command the device, by a function call in the loop's period, not
through DDS. The nodes do not know which process they run in: they subscribe and make their
device timers through this module, which gives them

- ``subscribe``: a DDS subscription (``node.create_subscription``), or, when a bus is installed
  and the topic is one of its direct topics, a `DirectSubscription` that the bus calls when a
  publisher of the same process publishes on that topic (the publisher still publishes on
  DDS, for the recorder and viewers);
- ``device_timer``: a ROS timer, or a `LoopTimer` that the loop calls at its own period.

Without an installed bus (a node process, ``ros2 run``, the tests) nothing changes.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

__all__ = ['Bus', 'DirectSubscription', 'LoopTimer', 'active_bus', 'device_timer', 'install',
           'subscribe', 'uninstall']

#: Topics (as the nodes name them) that the robot process delivers by function calls: what
#: a bridge, the estimator, the controller or the allocator of the process publishes for
#: another of them; ``/clock`` is the loop's own period (the estimator publishes on it).
DIRECT_TOPICS = frozenset({
    'joint_states', 'wrench', 'imu', 'depth', 'dvl', 'odometry/filtered',
    'command/generalized_force', 'command/actuators', 'command/jaw', '/clock'})


@dataclass
class DirectSubscription:
    """A subscription served by the bus: ``callback`` gets the message or its CDR bytes."""

    node: Any
    msg_type: Any
    topic: str
    callback: Callable[[Any], None]
    qos: Any
    raw: bool
    bus: Bus
    #: Messages delivered by function call.
    delivered: int = 0
    #: The DDS subscription that replaced it (no publisher of the process on the topic).
    fallback: Any = None
    #: What the loop charges its callback's CPU to (``uvms_hardware.loop_ledger``).
    phase: str = ''

    def destroy(self) -> None:
        """Stop the deliveries (and the fallback DDS subscription, if any)."""
        self.bus.remove(self)
        if self.fallback is not None:
            self.node.destroy_subscription(self.fallback)
            self.fallback = None


@dataclass
class LoopTimer:
    """A device timer the loop calls: ``read`` at ``period_s``, ``then`` after the control."""

    node: Any
    period_s: float
    read: Callable[[], None]
    then: Callable[[], None] | None
    bus: Bus
    canceled: bool = False
    next_s: float | None = None

    def cancel(self) -> None:
        """Stop calling (``rclpy.timer.Timer.cancel``)."""
        self.canceled = True

    def reset(self) -> None:
        """Call again from the next period (``rclpy.timer.Timer.reset``)."""
        self.canceled = False
        self.next_s = None

    def is_canceled(self) -> bool:
        """Whether the timer is cancelled."""
        return self.canceled

    def due(self, now_s: float, slack_s: float = 0.0) -> bool:
        """Whether its period has come (then the next is scheduled); never twice behind.

        Args:
            now_s: The steady clock (s).
            slack_s: How early a call still counts (half the loop's period: a loop tick a
                little early must not make a 20 ms device period 22 ms).
        """
        if self.canceled:
            return False
        if self.next_s is None or now_s - self.next_s > self.period_s:
            self.next_s = now_s
        if now_s < self.next_s - slack_s:
            return False
        self.next_s += self.period_s
        return True

    def destroy(self) -> None:
        """Never called again."""
        self.canceled = True
        if self in self.bus.timers:
            self.bus.timers.remove(self)


@dataclass
class Bus:
    """The direct subscriptions (by resolved topic) and device timers of one process."""

    topics: frozenset[str] = DIRECT_TOPICS
    subscriptions: dict[str, list[DirectSubscription]] = field(default_factory=dict)
    timers: list[LoopTimer] = field(default_factory=list)

    def add(self, sub: DirectSubscription) -> None:
        """Serve ``sub`` from now on."""
        self.subscriptions.setdefault(sub.topic, []).append(sub)

    def remove(self, sub: DirectSubscription) -> None:
        """Serve ``sub`` no more."""
        subs = self.subscriptions.get(sub.topic, [])
        if sub in subs:
            subs.remove(sub)

    def on(self, topic: str) -> list[DirectSubscription]:
        """The direct subscriptions of a resolved topic (those without a DDS fallback)."""
        return [s for s in self.subscriptions.get(topic, ()) if s.fallback is None]

    def all(self) -> Iterator[DirectSubscription]:
        """Every direct subscription."""
        for subs in self.subscriptions.values():
            yield from subs


_BUS: Bus | None = None


def install(bus: Bus) -> None:
    """Serve the direct topics of the nodes built from now on in this process by ``bus``."""
    global _BUS
    _BUS = bus


def uninstall() -> None:
    """Back to DDS for the nodes built from now on."""
    global _BUS
    _BUS = None


def active_bus() -> Bus | None:
    """The installed bus, if any."""
    return _BUS


def subscribe(node: Any, msg_type: Any, topic: str, callback: Callable[[Any], None],
              qos: Any, *, raw: bool = False) -> tuple[Callable[[Any], Any], Any]:
    """(destroy, subscription): direct when a bus serves ``topic``, else a DDS subscription.

    The pair is the nodes' own entity form: ``destroy(subscription)`` ends it either way.
    """
    bus = _BUS
    if bus is None or topic not in bus.topics:
        return node.destroy_subscription, node.create_subscription(msg_type, topic, callback,
                                                                   qos, raw=raw)
    sub = DirectSubscription(node, msg_type, node.resolve_topic_name(topic), callback, qos,
                             raw, bus, phase=f'{node.get_name()} <- {topic}')
    bus.add(sub)
    return DirectSubscription.destroy, sub


def device_timer(node: Any, period_s: float, read: Callable[[], None],
                 make_timer: Callable[[float, Callable[[], None]], Any],
                 then: Callable[[], None] | None = None) -> tuple[Callable[[Any], Any], Any]:
    """(destroy, timer): a `LoopTimer` when a bus is installed, else ``make_timer``'s.

    Args:
        node: The node the timer belongs to.
        period_s: Its period (s).
        read: What it does each period (a device's read and publish).
        make_timer: Makes the ROS timer of a process without a bus.
        then: What it does after the period's control step (a device's write); without a
            bus, right after ``read``.
    """
    bus = _BUS
    if bus is None:
        def both() -> None:
            read()
            if then is not None:
                then()
        return node.destroy_timer, make_timer(period_s, both if then is not None else read)
    timer = LoopTimer(node, period_s, read, then, bus)
    bus.timers.append(timer)
    return LoopTimer.destroy, timer
