"""The robot loop's costs: one /clock subscription per process, and its CPU ledger."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from uvms_common.raw_clock import RawClockTimeSource
from uvms_hardware.loop_ledger import LoopLedger, NullLedger, make_ledger
from uvms_hardware.robot_loop import share_clock


@pytest.fixture
def nodes() -> Iterator[list[Node]]:
    """Three nodes on simulated time in one context (as the robot process builds them)."""
    context = Context()
    rclpy.init(args=[], context=context)
    built = [Node(name, context=context,
                  parameter_overrides=[Parameter('use_sim_time', value=True)])
             for name in ('controller', 'estimator', 'alpha5_bridge')]
    yield built
    for node in built:
        node.destroy_node()
    rclpy.try_shutdown(context=context)


def clock_subscriptions(nodes: list[Node]) -> int:
    """/clock subscriptions of the nodes."""
    return sum(sub.topic_name == '/clock' for node in nodes for sub in node.subscriptions)


def test_one_clock_message_sets_every_node_clock_through_one_subscription(
        nodes: list[Node]) -> None:
    """Each node subscribed /clock on its own (each message taken N times); then once."""
    assert clock_subscriptions(nodes) == len(nodes)
    assert share_clock(nodes[0], nodes) == len(nodes) - 1
    assert clock_subscriptions(nodes) == 1
    source = nodes[0]._time_source
    assert isinstance(source, RawClockTimeSource)
    msg = Clock()
    msg.clock.sec, msg.clock.nanosec = 12, 345_000_000
    source.raw_clock_callback(serialize_message(msg))
    assert [node.get_clock().now().nanoseconds for node in nodes] == [12_345_000_000] * 3


def test_the_ledger_charges_nested_phases_once_each() -> None:
    """A delivery inside the chain and a publish inside it: each span counted in one phase."""
    ticks = iter(range(0, 1000, 10))  # the thread's CPU clock: +10 ns per reading
    ledger = LoopLedger(clock=lambda: next(ticks))
    ledger.enter('loop')                      # 0
    ledger.enter('controller <- odometry')    # 10: loop 10
    ledger.publish('/uvms/command', lambda msg: None, b'')  # 20 -> 30: controller 10, dds 10
    ledger.leave()                            # 40: controller 10 more
    ledger.leave()                            # 50: loop 10 more
    assert dict(ledger.phase_ns) == {'loop': 20, 'controller <- odometry': 20,
                                     'dds publish': 10}
    assert dict(ledger.publishes) == {'/uvms/command': 1}
    assert ledger.publish_ns['/uvms/command'] == 10
    assert 'loop 0.0' in ledger.lines(1, 1.0)[0]


def test_the_ledger_is_off_unless_asked() -> None:
    """Off by default: its clock reads would cost the loop; on with UVMS_LOOP_CPU=1."""
    assert isinstance(make_ledger({}), NullLedger)
    assert not isinstance(make_ledger({'UVMS_LOOP_CPU': '1'}), NullLedger)
    sent: list[bytes] = []
    off = make_ledger({})
    off.enter('loop')
    off.publish('/uvms/wrench', sent.append, b'x')
    assert sent == [b'x']
    assert off.lines(10, 1.0) == []
