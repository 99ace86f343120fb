"""take_clock_raw: a node on simulated time follows a typed /clock publisher through raw takes."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

import pytest
import rclpy
from builtin_interfaces.msg import Time as TimeMsg
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from uvms_common.node_main import make_executor
from uvms_common.raw_clock import RawClockTimeSource, take_clock_raw


@pytest.fixture
def context() -> Iterator[Context]:
    """An initialised rclpy context."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def clock_message(sec: int, nanosec: int) -> Clock:
    """A Clock message at sec + nanosec."""
    return Clock(clock=TimeMsg(sec=sec, nanosec=nanosec))


def spin_until(context: Context, nodes: list[Node], condition: Callable[[], bool],
               action: Callable[[], None]) -> bool:
    """Repeat ``action`` and spin until ``condition`` holds (False after 10 s)."""
    executor = make_executor('events', context)
    for node in nodes:
        executor.add_node(node)
    deadline = time.monotonic() + 10.0
    try:
        while time.monotonic() < deadline:
            action()
            executor.spin_once(timeout_sec=0.05)
            if condition():
                return True
        return False
    finally:
        executor.shutdown()


def subscriptions_of(node: Node, topic: str) -> int:
    """Subscriptions the node itself holds on a topic."""
    return sum(1 for s in node.subscriptions if s.topic_name == topic)


def test_sim_time_node_follows_a_typed_clock_publisher(context: Context) -> None:
    """The node's clock reads each stamp of a typed /clock publisher, to the nanosecond."""
    node = rclpy.create_node('follower', context=context,
                             parameter_overrides=[Parameter('use_sim_time', value=True)])
    source = take_clock_raw(node)
    publisher_node = rclpy.create_node('clock_source', context=context)
    publisher = publisher_node.create_publisher(
        Clock, '/clock', QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
    assert isinstance(node._time_source, RawClockTimeSource)
    assert subscriptions_of(node, '/clock') == 1  # the typed one was destroyed
    stamp_ns = 12 * 1_000_000_000 + 345_678_901
    followed = spin_until(context, [node, publisher_node],
                          lambda: node.get_clock().now().nanoseconds == stamp_ns,
                          lambda: publisher.publish(clock_message(12, 345_678_901)))
    assert followed, f'clock reads {node.get_clock().now().nanoseconds} ns'
    assert source.last_ns == stamp_ns and source.malformed == 0
    # A clock created after the swap follows too: rclpy's timers and rates use the node clock.
    assert node.get_clock().ros_time_is_active
    node.destroy_node()
    publisher_node.destroy_node()


def test_use_sim_time_switches_the_raw_subscription(context: Context) -> None:
    """use_sim_time false at run time: no /clock subscription, the system clock; true again."""
    node = rclpy.create_node('switching', context=context,
                             parameter_overrides=[Parameter('use_sim_time', value=True)])
    take_clock_raw(node)
    assert subscriptions_of(node, '/clock') == 1
    node.set_parameters([Parameter('use_sim_time', value=False)])
    assert subscriptions_of(node, '/clock') == 0
    assert abs(node.get_clock().now().nanoseconds - time.time_ns()) < 5_000_000_000
    node.set_parameters([Parameter('use_sim_time', value=True)])
    assert subscriptions_of(node, '/clock') == 1
    assert node.get_clock().now().nanoseconds == 0  # no /clock yet: ROS time zero
    node.destroy_node()


def test_wall_time_node_keeps_no_clock_subscription(context: Context) -> None:
    """Without use_sim_time nothing subscribes /clock, as with rclpy's own time source."""
    node = rclpy.create_node('wall', context=context)
    take_clock_raw(node)
    assert subscriptions_of(node, '/clock') == 0
    assert not node.get_clock().ros_time_is_active
    node.destroy_node()


def test_short_payload_is_counted_and_leaves_the_clock(context: Context) -> None:
    """A payload too short for a Clock is ignored and counted; the next good one is taken."""
    node = rclpy.create_node('guarded', context=context,
                             parameter_overrides=[Parameter('use_sim_time', value=True)])
    source = take_clock_raw(node)
    source.raw_clock_callback(b'\x00\x01\x00\x00\x05')
    assert source.malformed == 1 and node.get_clock().now().nanoseconds == 0
    source.raw_clock_callback(b'\x00\x01\x00\x00' + (7).to_bytes(4, 'little')
                              + (9).to_bytes(4, 'little'))
    assert node.get_clock().now().nanoseconds == 7_000_000_009
    source.raw_clock_callback(b'\x00\x00\x00\x00' + (7).to_bytes(4, 'big')
                              + (10).to_bytes(4, 'big'))  # big-endian CDR
    assert node.get_clock().now().nanoseconds == 7_000_000_010
    node.destroy_node()


def test_fed_node_takes_its_time_from_its_stamps_not_clock(context: Context) -> None:
    """feed_from_node: no /clock subscription, even after use_sim_time toggles; advance sets it."""
    node = rclpy.create_node('fed', context=context,
                             parameter_overrides=[Parameter('use_sim_time', value=True)])
    source = take_clock_raw(node)
    source.feed_from_node()
    assert source.fed and subscriptions_of(node, '/clock') == 0
    source.advance(3_000_000_007)
    assert node.get_clock().now().nanoseconds == 3_000_000_007
    node.set_parameters([Parameter('use_sim_time', value=False)])
    source.advance(5)  # wall time: stamps do not move the clock
    assert abs(node.get_clock().now().nanoseconds - time.time_ns()) < 5_000_000_000
    node.set_parameters([Parameter('use_sim_time', value=True)])
    assert subscriptions_of(node, '/clock') == 0
    node.destroy_node()
