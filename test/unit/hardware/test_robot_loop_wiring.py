"""uvms_hardware.robot_loop: one period reads, runs the chain by calls, then writes."""

from __future__ import annotations

from typing import Any

import pytest
from rclpy.clock import Clock, ClockType
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from uvms_common.direct_topics import Bus
from uvms_hardware.robot_loop import RobotLoop

from uvms_common import direct_topics


class FakePublisher:
    """A publisher that records what it sent on DDS."""

    def __init__(self, topic_name: str) -> None:
        self.topic_name = topic_name
        self.sent: list[Any] = []

    def publish(self, msg: Any) -> None:
        """As ``rclpy.publisher.Publisher.publish``."""
        self.sent.append(msg)


class FakeNode:
    """A node with publishers, DDS subscriptions made on demand and a steady clock."""

    def __init__(self, name: str, *topics: str) -> None:
        self.name = name
        self.publishers = [FakePublisher(t) for t in topics]
        self.subscriptions: list[Any] = []
        self.clock = Clock(clock_type=ClockType.STEADY_TIME)

    def get_name(self) -> str:
        """As ``rclpy.node.Node.get_name``."""
        return self.name

    def get_clock(self) -> Clock:
        """As ``rclpy.node.Node.get_clock``."""
        return self.clock

    def resolve_topic_name(self, topic: str) -> str:
        """As ``rclpy.node.Node.resolve_topic_name`` in /uvms."""
        return topic if topic.startswith('/') else f'/uvms/{topic}'

    def create_subscription(self, msg_type: Any, topic: str, callback: Any, qos: Any,
                            raw: bool = False) -> str:
        """As ``rclpy.node.Node.create_subscription``: a name stands for the subscription."""
        self.subscriptions.append(f'dds:{topic}')
        return f'dds:{topic}'

    def destroy_timer(self, timer: Any) -> bool:
        """As ``rclpy.node.Node.destroy_timer``."""
        return True


def test_a_reading_reaches_its_consumer_by_a_call_and_is_still_published(bus: Bus) -> None:
    """A message published by a bridge: sent on DDS and handed as CDR bytes to a raw input."""
    bridge = FakeNode('alpha5_bridge', '/uvms/joint_states')
    controller = FakeNode('controller')
    got: list[bytes] = []
    direct_topics.subscribe(controller, JointState, 'joint_states', got.append, 10, raw=True)
    loop = RobotLoop(bus, [controller, bridge], 500.0)
    msg = JointState(name=['joint_1'], position=[0.5])
    bridge.publishers[0].publish(msg)
    assert bridge.publishers[0].sent == [msg]  # the recorder's copy
    assert list(deserialize_message(got[0], JointState).position) == [0.5]
    assert loop.delivered['/uvms/joint_states', 'controller'] == 1
    assert controller.subscriptions == [] and loop.dds_inputs() == []


def test_cdr_bytes_for_two_typed_inputs_are_deserialized_once(
        bus: Bus, monkeypatch: pytest.MonkeyPatch) -> None:
    """The allocator's raw command to the arm's and the vehicle's bridges: one message for both.

    Each typed subscriber got its own deserialization of the same bytes (14 us each, every
    control period); the message is now made once and handed to both, as an intra-process
    delivery shares it.
    """
    from uvms_hardware import robot_loop

    calls: list[Any] = []

    def counted(data: bytes, msg_type: Any) -> Any:
        calls.append(msg_type)
        return deserialize_message(data, msg_type)

    monkeypatch.setattr(robot_loop, 'deserialize_message', counted)
    allocator = FakeNode('thruster_allocator', '/uvms/joint_states')
    arm, vehicle = FakeNode('alpha5_bridge'), FakeNode('ardusub_bridge')
    got: list[JointState] = []
    for node in (arm, vehicle):
        direct_topics.subscribe(node, JointState, 'joint_states', got.append, 10)
    RobotLoop(bus, [allocator, arm, vehicle], 500.0)
    from rclpy.serialization import serialize_message
    allocator.publishers[0].publish(serialize_message(JointState(name=['joint_1'],
                                                                 position=[0.5])))
    assert len(got) == 2 and list(got[0].position) == [0.5] and got[1] is got[0]
    assert calls == [JointState]


def test_an_input_no_node_of_the_process_publishes_comes_through_dds(bus: Bus) -> None:
    """No DVL bridge in the process: the estimator's dvl input falls back to DDS."""
    estimator = FakeNode('estimator')
    direct_topics.subscribe(estimator, object, 'dvl', print, 10, raw=True)
    loop = RobotLoop(bus, [estimator], 500.0)
    assert estimator.subscriptions == ['dds:/uvms/dvl']
    assert loop.fallbacks == ['estimator:/uvms/dvl'] and bus.on('/uvms/dvl') == []


def test_one_period_reads_then_steps_the_chain_then_writes(bus: Bus) -> None:
    """Order in a tick: device read, the clock to the estimator, the device write."""
    events: list[str] = []
    bridge = FakeNode('ardusub_bridge')
    estimator = FakeNode('estimator')
    direct_topics.device_timer(bridge, 0.002, lambda: events.append('read'),
                               lambda p, c: None, then=lambda: events.append('write'))
    direct_topics.subscribe(estimator, object, '/clock', lambda data: events.append('clock'),
                            10, raw=True)
    loop = RobotLoop(bus, [estimator, bridge], 500.0)
    loop.tick()
    assert events == ['read', 'clock', 'write']
    assert loop.periods == 1 and loop.steps == 1 and loop.writes == 1
