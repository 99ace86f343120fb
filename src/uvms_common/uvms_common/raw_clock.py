"""``/clock`` taken as raw CDR bytes by every node's time source.

Under ``use_sim_time`` rclpy's ``TimeSource`` subscribes ``/clock`` typed: each of the
simulator's 500 Clock messages a second is deserialized into a Python message object in
every node that runs on simulated time (measured: a typed take costs 52-58 us of CPU, a raw
one 13-14 us; docs/running.md). ``take_clock_raw(node)`` swaps the node's time source for
``RawClockTimeSource``: the same subscription (``/clock``, best effort, depth 1, as rclpy's),
the same behaviour (``use_sim_time`` switches it on and off at run time, every clock of the
node follows the last stamp), but taken raw and decoded with ``struct``. A payload too
short to hold a Clock is ignored (counted in ``malformed``), as a typed take would have
failed on it.

rclpy keeps the time source in ``Node._time_source`` and its clocks in
``TimeSource._associated_clocks``; these private names are those of Jazzy's rclpy (7.1.x),
which the project pins. ``test_raw_clock.py`` runs a node on a typed ``/clock`` publisher.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import TYPE_CHECKING

from rclpy.clock import ClockType, ROSClock
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from rclpy.time_source import CLOCK_TOPIC, TimeSource
from rosgraph_msgs.msg import Clock

if TYPE_CHECKING:
    from rclpy.node import Node

__all__ = ['RawClockTimeSource', 'take_clock_raw']

#: builtin_interfaces/Time after the 4-byte encapsulation header: int32 sec, uint32 nanosec.
_LITTLE = struct.Struct('<iI')
_BIG = struct.Struct('>iI')


class RawClockTimeSource(TimeSource):
    """rclpy's TimeSource with ``/clock`` subscribed raw (``raw=True``) and decoded by struct.

    Attributes:
        malformed: Payloads too short for a Clock message, ignored.
    """

    def __init__(self, *, node: Node | None = None) -> None:
        """Attach to ``node`` as rclpy's TimeSource does (reads ``use_sim_time``)."""
        self.malformed = 0
        self.last_ns = 0
        self._fed = False
        #: Called with each stamp from /clock after the clocks are set (the robot loop's
        #: period on simulated time); None: nothing called.
        self.on_clock: Callable[[int], None] | None = None
        super().__init__(node=node)

    @property
    def fed(self) -> bool:
        """Whether the node feeds the time itself (``feed_from_node``), not /clock."""
        return self._fed

    def feed_from_node(self) -> None:
        """The node sets the time itself (``advance``): no /clock subscription of its own.

        For a node that receives every /clock message anyway (the recorder records it) or
        whose clock only times what its stamped inputs bring: one subscription (500 messages
        a second) less. ``use_sim_time`` still switches simulated time on and off.
        """
        self._fed = True
        if self._clock_sub is not None:
            node = self._get_node()
            if node is not None:
                node.destroy_subscription(self._clock_sub)
            self._clock_sub = None

    def advance(self, stamp_ns: int) -> None:
        """Set the clocks to ``stamp_ns`` under ``use_sim_time`` (ignored on wall time)."""
        if self.ros_time_is_active:
            self._set(stamp_ns)

    def _subscribe_to_clock_topic(self) -> None:
        if self._clock_sub is None and not self._fed:
            node = self._get_node()
            if node is not None:
                self._clock_sub = node.create_subscription(
                    Clock, CLOCK_TOPIC, self.raw_clock_callback,
                    QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT), raw=True)

    def raw_clock_callback(self, data: bytes) -> None:
        """Set every associated clock to the stamp of one serialized Clock message."""
        if len(data) < 12:
            self.malformed += 1
            return
        sec, nanosec = (_BIG if data[1] == 0 else _LITTLE).unpack_from(data, 4)
        self._set(sec * 1_000_000_000 + nanosec)
        if self.on_clock is not None:
            self.on_clock(self.last_ns)

    def _set(self, stamp_ns: int) -> None:
        self.last_ns = stamp_ns
        time = Time(nanoseconds=stamp_ns, clock_type=ClockType.ROS_TIME)
        self._last_time_set = time
        for clock in self._associated_clocks:
            clock.set_ros_time_override(time)


def take_clock_raw(node: Node) -> RawClockTimeSource:
    """Replace the node's time source by a ``RawClockTimeSource``; return it.

    Call it in the node's constructor, before its clock is used. The typed ``/clock``
    subscription (if ``use_sim_time`` made one) is destroyed and the old source's parameter
    callback removed, so ``use_sim_time`` set at run time acts on the new source only.
    """
    old = node._time_source
    if isinstance(old, RawClockTimeSource):
        return old
    old.detach_node()
    node.remove_on_set_parameters_callback(old._on_parameter_event)
    old._associated_clocks.clear()
    source = RawClockTimeSource(node=node)
    clock = node.get_clock()
    if isinstance(clock, ROSClock):
        source.attach_clock(clock)
    node._time_source = source
    return source
