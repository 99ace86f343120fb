"""uvms_common.direct_topics: direct subscriptions and loop timers only where a bus serves."""

from __future__ import annotations

from typing import Any

from uvms_common.direct_topics import Bus, DirectSubscription, LoopTimer

from uvms_common import direct_topics


class FakeNode:
    """The parts of a node the module uses: subscriptions, timers, names."""

    def __init__(self) -> None:
        self.created: list[tuple[str, str]] = []

    def get_name(self) -> str:
        """As ``rclpy.node.Node.get_name`` (the loop's CPU ledger names each delivery by it)."""
        return 'fake'

    def create_subscription(self, msg_type: Any, topic: str, callback: Any, qos: Any,
                            raw: bool = False) -> str:
        """As ``rclpy.node.Node.create_subscription``."""
        self.created.append(('subscription', topic))
        return f'dds:{topic}'

    def destroy_subscription(self, sub: Any) -> bool:
        """As ``rclpy.node.Node.destroy_subscription``."""
        self.created.remove(('subscription', sub.split(':', 1)[1]))
        return True

    def destroy_timer(self, timer: Any) -> bool:
        """As ``rclpy.node.Node.destroy_timer``."""
        return True

    def resolve_topic_name(self, topic: str) -> str:
        """As ``rclpy.node.Node.resolve_topic_name``."""
        return topic if topic.startswith('/') else f'/uvms/{topic}'


def test_without_a_bus_a_node_subscribes_on_dds() -> None:
    """A node process (no bus): the DDS subscription, destroyed by the node's own call."""
    node = FakeNode()
    destroy, sub = direct_topics.subscribe(node, object, 'joint_states', print, 10)
    assert sub == 'dds:joint_states' and node.created == [('subscription', 'joint_states')]
    destroy(sub)
    assert node.created == []


def test_with_a_bus_a_direct_topic_is_served_by_it_until_destroyed(bus: Bus) -> None:
    """Direct topics by resolved name; other topics stay on DDS; destroy stops deliveries."""
    node = FakeNode()
    destroy, sub = direct_topics.subscribe(node, object, 'joint_states', print, 10, raw=True)
    _, fix = direct_topics.subscribe(node, object, 'position_fix', print, 10)
    assert isinstance(sub, DirectSubscription) and sub.raw
    assert bus.on('/uvms/joint_states') == [sub]
    assert fix == 'dds:position_fix' and node.created == [('subscription', 'position_fix')]
    destroy(sub)
    assert bus.on('/uvms/joint_states') == []


def test_a_loop_timer_fires_at_its_own_period_on_a_faster_loop(bus: Bus) -> None:
    """A 50 Hz device timer on a 500 Hz loop reads every tenth period, cancel stops it."""
    node = FakeNode()
    _, timer = direct_topics.device_timer(node, 0.02, print, lambda p, c: None, then=print)
    assert isinstance(timer, LoopTimer) and bus.timers == [timer]
    fired = [k for k in range(100) if timer.due(k * 0.002, slack_s=0.001)]
    assert fired == list(range(0, 100, 10))
    timer.cancel()
    assert not timer.due(1.0)
    timer.reset()
    assert timer.due(1.0)
    timer.destroy()
    assert bus.timers == []


def test_without_a_bus_the_write_follows_the_read_on_one_timer() -> None:
    """A node process: one ROS timer calling the read, then the write."""
    calls: list[str] = []
    made: list[Any] = []
    direct_topics.device_timer(FakeNode(), 0.02, lambda: calls.append('read'),
                               lambda p, c: made.append(c), then=lambda: calls.append('write'))
    made[0]()
    assert calls == ['read', 'write']
