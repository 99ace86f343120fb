"""The robot loop: read the devices, estimate, control, allocate, write, in one period.

As ros2_control's controller manager runs ``read()`` -> ``update()`` -> ``write()``, the robot
process (``uvms launch --compose robot``) runs its bridges, estimator, controller and thruster
allocator on one timer at the controller's ``control_rate_hz``. Each period:

1. every device timer whose own period has come reads its device (never waits) and publishes
   what it read: on DDS for the recorder and viewers, and by a function call to the
   estimator and the controller (``uvms_common.direct_topics``);
2. the period's time goes to the estimator (its ``/clock``), whose estimate goes to the
   controller, whose generalized force goes to the allocator, whose command goes to the arm
   (written at once) and the thrusters: function calls, no DDS;
3. the device timers that read in step 1 write (the ArduSub's RC overrides).

The nodes keep their lifecycle services, /diagnostics, parameters and the ContactTask action
server; the devices keep their own watchdogs (a silent device publishes nothing, so nothing
stale is delivered) and their restore on every way out (``composed_run``). A publisher
created after the start (a node configured again) is tapped within a second.
"""

from __future__ import annotations

import os
import struct
import time
from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np
from rclpy.clock import Clock, ClockType, ROSClock
from rclpy.node import Node
from rclpy.serialization import deserialize_message, serialize_message
from uvms_common.clock_read import now_ns
from uvms_common.direct_topics import Bus
from uvms_common.raw_clock import take_clock_raw

from uvms_hardware import latency_probe
from uvms_hardware.loop_ledger import LoopLedger, make_ledger

__all__ = ['RobotLoop']

#: How often new publishers are looked for (s).
REWIRE_PERIOD_S = 1.0
#: Periods between two control steps while the node clock stands.
HELD_PERIODS = 10
#: A rosgraph_msgs/Clock in CDR: encapsulation (CDR, little endian), int32 sec, uint32 nanosec.
_CLOCK_CDR = struct.Struct('<4siI')
CDR_LE_HEADER = b'\x00\x01\x00\x00'
#: Durations kept for the read-to-write figures (periods).
KEPT_PERIODS = 4096


def share_clock(main: Node, nodes: Sequence[Node]) -> int:
    """One ``/clock`` subscription for the process: every node's clock set by ``main``'s.

    Under ``use_sim_time`` each node's time source subscribes ``/clock`` on its own: in one
    process the same message was taken and decoded once per node (seven times at the
    simulator's rate; measured, most of the loop thread's CPU outside its periods). Here
    ``main``'s source (taken raw, ``uvms_common.raw_clock``) sets every node's clock and the
    others subscribe nothing (``feed_from_node``). Their clocks read the same time as before,
    as each node of the process would have set it from the same message.

    Returns:
        The number of nodes whose clock now follows ``main``'s.
    """
    source = take_clock_raw(main)
    shared = 0
    for node in nodes:
        if node is main:
            continue
        take_clock_raw(node).feed_from_node()
        clock = node.get_clock()
        if isinstance(clock, ROSClock):
            source.attach_clock(clock)
            shared += 1
    return shared


class RobotLoop:
    """The one timer of the robot process and the direct deliveries of its topics."""

    def __init__(self, bus: Bus, nodes: Sequence[Node], rate_hz: float) -> None:
        """Tap the nodes' publishers; the timer starts with `start`.

        Args:
            bus: The bus the nodes were built with (``direct_topics.install``).
            nodes: The process's nodes.
            rate_hz: The loop's rate (the controller's ``control_rate_hz``).
        """
        self.bus, self.nodes, self.rate_hz = bus, list(nodes), float(rate_hz)
        self._tapped: set[int] = set()
        self._steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._clock_node = nodes[0]
        self._rewire_s = 0.0
        self._durations_ns = np.zeros(KEPT_PERIODS, dtype=np.int64)
        #: Periods run, periods that wrote a device.
        self.periods = 0
        self.writes = 0
        self.timer: Any = None
        #: Nodes whose clock follows the loop's clock node (`share_clock`).
        self.shared_clocks = 0
        self.fallbacks = self._fall_back_to_dds()
        #: Periods that ran the control chain (new time on the node clock).
        self.steps = 0
        self._period_ns = round(1e9 / self.rate_hz * 0.999)
        #: Whether /clock runs the periods (simulated time; `start`).
        self.clock_driven = False
        self._fallback_ns = round(1.5e9 / self.rate_hz)
        self._slack_s = 0.5 / self.rate_hz
        self._stepped_ns, self._stepped_period = -self._period_ns, 0
        #: The thread's CPU per phase and per published topic (``loop_ledger``; counted
        #: only with ``UVMS_LOOP_CPU=1``).
        self.ledger: LoopLedger = make_ledger(os.environ)
        self._labels: dict[int, str] = {}
        self._first_ns = self._last_ns = 0
        self.wire()

    def _fall_back_to_dds(self) -> list[str]:
        """A DDS subscription for each direct one that no node of the process publishes.

        A topic the process does not make (a device another process bridges) still comes
        in, through DDS; ``/clock`` is the loop's own.
        """
        published = {pub.topic_name for node in self.nodes for pub in node.publishers}
        out = []
        for sub in list(self.bus.all()):
            if sub.topic != '/clock' and sub.topic not in published and sub.fallback is None:
                sub.fallback = sub.node.create_subscription(sub.msg_type, sub.topic,
                                                            sub.callback, sub.qos, raw=sub.raw)
                out.append(f'{sub.node.get_name()}:{sub.topic}')
        return out

    def start(self, node: Node) -> None:
        """The loop's timer, on ``node``; on simulated time, each new period of /clock too.

        ``node``'s time source is also the only ``/clock`` subscription of the process: the
        other nodes' clocks follow it (`share_clock`). On the wall clock (the robot) the
        steady timer is the period. On simulated time (the twin stand) a period runs as each
        /clock message brings a new control period, as gz_ros2_control runs the controller
        manager from the simulator's step: on its own timer the loop beat against the
        simulator's /clock (both 500 Hz, free running), and one period in five found no new
        time and the next two periods' worth, a state left unanswered (measured 4-30 % at
        factor 1). The steady timer then runs a period only when /clock has not for
        1.5 periods (a simulator holding its first state, a stall), so the devices are still
        read and, while the clock stands, commanded (`HELD_PERIODS`).
        """
        self._clock_node = node
        self.shared_clocks = share_clock(node, self.nodes)
        source = take_clock_raw(node)
        if source.ros_time_is_active:
            source.on_clock = self._on_clock
            self.clock_driven = True
        self.timer = node.create_timer(1.0 / self.rate_hz, self._on_timer, clock=self._steady)

    def _on_clock(self, stamp_ns: int) -> None:
        """/clock arrived (simulated time): a period when it brings a new control period."""
        if stamp_ns - self._stepped_ns >= self._period_ns:
            self.tick()

    def _on_timer(self) -> None:
        """The steady timer: the period, or on simulated time the fallback of a still clock."""
        if (self.clock_driven and self.periods
                and time.perf_counter_ns() - self._last_ns < self._fallback_ns):
            return
        self.tick()

    def wire(self) -> None:
        """Tap every publisher not yet tapped: its CPU counted, its direct deliveries made."""
        for node in self.nodes:
            for publisher in list(node.publishers):
                if id(publisher) not in self._tapped:
                    self._tap(publisher)

    def _tap(self, publisher: Any) -> None:
        self._tapped.add(id(publisher))
        topic, send, ledger = publisher.topic_name, publisher.publish, self.ledger
        direct = topic in self.bus.subscriptions
        if not direct and not ledger.enabled:
            return

        def publish(msg: Any) -> None:
            ledger.publish(topic, send, msg)
            if direct and getattr(publisher, '_enabled', True):  # an inactive lifecycle one
                self.deliver(topic, msg)                           # sends nothing

        publisher.publish = publish

    def _label(self, timer: Any, what: str) -> str:
        if not self.ledger.enabled:
            return what  # no ledger: no phase name built twice a period per device
        label = self._labels.get(id(timer))
        if label is None:
            label = self._labels[id(timer)] = timer.node.get_name().removesuffix('_bridge')
        return f'{what} {label}'

    def deliver(self, topic: str, msg: Any) -> None:
        """Call every direct subscription of ``topic`` with ``msg`` (message or CDR bytes).

        A message is serialized at most once, CDR bytes deserialized at most once per message
        type, whatever the number of subscriptions (``command/actuators``: the arm's and the
        vehicle's bridges take the same message, as an intra-process delivery shares it).
        """
        data: bytes | None = None
        typed: dict[Any, Any] = {}
        for sub in self.bus.on(topic):
            if sub.raw:
                if isinstance(msg, (bytes, bytearray, memoryview)):
                    value: Any = msg
                else:
                    data = data if data is not None else serialize_message(msg)
                    value = data
            elif isinstance(msg, (bytes, bytearray, memoryview)):
                value = typed.get(sub.msg_type)
                if value is None:
                    value = typed[sub.msg_type] = deserialize_message(bytes(msg), sub.msg_type)
            else:
                value = msg
            sub.delivered += 1
            self.ledger.enter(sub.phase)
            try:
                sub.callback(value)
            finally:
                self.ledger.leave()

    def tick(self) -> None:
        """One period: due reads, the clock down the control chain, the writes."""
        start_ns = time.perf_counter_ns()
        ledger = self.ledger
        if self.periods:
            ledger.leave()  # 'outside': the executor since the last period
        else:
            self._first_ns = start_ns
        ledger.enter('loop')
        now_s = time.monotonic()
        fired = [timer for timer in list(self.bus.timers) if timer.due(now_s, self._slack_s)]
        for timer in fired:
            ledger.enter(self._label(timer, 'read'))
            timer.read()
            ledger.leave()
        clock_ns = now_ns(self._clock_node.get_clock())
        # One control step per control period of the node clock: on a simulated clock slower
        # than the wall (--real-time-factor) a period without new time computes nothing, but
        # a clock that stands (a simulator holding its first state until the devices are
        # driven) still gets the command every HELD_PERIODS, so the devices' watchdogs hold.
        if self.bus.on('/clock') and (clock_ns - self._stepped_ns >= self._period_ns
                                      or self.periods - self._stepped_period >= HELD_PERIODS):
            self._stepped_ns, self._stepped_period = clock_ns, self.periods
            self.steps += 1
            # Its CDR bytes by struct: the estimator takes /clock raw (no message built and
            # serialized again each period); a typed input gets it deserialized.
            self.deliver('/clock', _CLOCK_CDR.pack(CDR_LE_HEADER,
                                                   *divmod(clock_ns, 1_000_000_000)))
        wrote = False
        for timer in fired:
            if timer.then is not None:
                ledger.enter(self._label(timer, 'write'))
                timer.then()
                ledger.leave()
                wrote = True
        self._last_ns = time.perf_counter_ns()
        self._durations_ns[self.periods % KEPT_PERIODS] = self._last_ns - start_ns
        self.periods += 1
        self.writes += wrote  # ArduSub overrides; the arm is written in the chain itself
        if now_s - self._rewire_s > REWIRE_PERIOD_S:
            self._rewire_s = now_s
            self.wire()
        ledger.switch('outside')

    @property
    def delivered(self) -> Counter[tuple[str, str]]:
        """Messages delivered by call, by (topic, receiving node): the subscriptions' counts."""
        out: Counter[tuple[str, str]] = Counter()
        for sub in self.bus.all():
            out[sub.topic, sub.node.get_name()] += sub.delivered
        return +out  # the edges that delivered

    def dds_inputs(self) -> list[str]:
        """Subscriptions of the process's nodes on DDS for a topic the bus serves."""
        served = set(self.bus.subscriptions) - {'/clock'}  # /clock: the nodes' time source
        fallbacks = {id(sub.fallback) for sub in self.bus.all()}
        return [f'{node.get_name()}:{sub.topic_name}' for node in self.nodes
                for sub in node.subscriptions
                if sub.topic_name in served and id(sub) not in fallbacks]

    def summary(self) -> str:
        """One line: periods, the read-to-write time, the deliveries per edge."""
        latency_probe.flush()  # the process may end without its atexit hooks
        kept = self._durations_ns[:min(self.periods, KEPT_PERIODS)] * 1e-6
        figures = (f'read->write p50 {np.percentile(kept, 50):.2f} ms, p99 '
                   f'{np.percentile(kept, 99):.2f} ms, max {kept.max():.2f} ms'
                   if kept.size else 'no period')
        edges = ', '.join(f'{topic}->{node} {n}' for (topic, node), n in
                          sorted(self.delivered.items()))
        dds = self.dds_inputs()
        wall_s = (self._last_ns - self._first_ns) * 1e-9
        cpu = '; '.join(self.ledger.lines(self.periods, wall_s))
        return (f'robot loop: {self.periods} periods at {self.rate_hz:g} Hz'
                f'{" (on /clock)" if self.clock_driven else ""}, {self.steps} '
                f'control steps, {self.writes} with a thruster write; {figures}; direct: '
                f'{edges or "none"}; DDS inputs on direct topics: {", ".join(dds) or "none"}'
                + (f'; on DDS (no publisher in the process): {", ".join(self.fallbacks)}'
                   if self.fallbacks else '')
                + f'; /clock: one subscription, {self.shared_clocks} other nodes follow it'
                + (f'; {cpu}' if cpu else ''))
