"""Publishers and subscriptions of the compat rclpy, delivered through executors in process.

Each test states the behaviour of rclpy (Jazzy) it mirrors.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
    qos_profile_sensor_data,
)
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, String


@pytest.fixture
def executor(context: Context, node: Node) -> Iterator[SingleThreadedExecutor]:
    """A single-threaded executor spinning ``node``."""
    ex = SingleThreadedExecutor(context=context)
    ex.add_node(node)
    yield ex
    ex.shutdown()


def joint_state(position: float = 0.0) -> JointState:
    """A 3-joint JointState with the given first position."""
    return JointState(name=['a', 'b', 'c'], position=[position, 1.0, 2.0])


def test_subscription_receives_published_message_when_spun(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """As in rclpy, a message published on a topic reaches the callback when the executor spins."""
    received: list[String] = []
    node.create_subscription(String, 'chatter', received.append, 10)
    publisher = node.create_publisher(String, 'chatter', 10)
    publisher.publish(String(data='hello'))
    assert received == []
    executor.spin_once(timeout_sec=1.0)
    assert [m.data for m in received] == ['hello']


def test_delivery_reaches_nodes_of_the_same_context_only(context: Context, node: Node) -> None:
    """As in rclpy, nodes in one context share a graph; another context (domain) is separate."""
    other_context = Context()
    rclpy.init(args=[], context=other_context)
    try:
        listener = Node('listener', context=context)
        stranger = Node('stranger', context=other_context)
        heard: list[str] = []
        not_heard: list[str] = []
        listener.create_subscription(String, '/chatter', lambda m: heard.append(m.data), 10)
        stranger.create_subscription(String, '/chatter', lambda m: not_heard.append(m.data), 10)
        node.create_publisher(String, '/chatter', 10).publish(String(data='x'))
        for ex_context, spun in ((context, listener), (other_context, stranger)):
            ex = SingleThreadedExecutor(context=ex_context)
            ex.add_node(spun)
            ex.spin_once(timeout_sec=0)
            ex.shutdown()
        assert heard == ['x']
        assert not_heard == []
    finally:
        other_context.try_shutdown()


def test_message_changed_after_publish_is_delivered_as_published(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """As rclpy serializes at publish, mutating the message afterwards changes nothing received."""
    received: list[JointState] = []
    node.create_subscription(JointState, 'joints', received.append, 10)
    publisher = node.create_publisher(JointState, 'joints', 10)
    msg = joint_state(0.5)
    publisher.publish(msg)
    msg.position[0] = 99.0
    msg.name.append('d')
    executor.spin_once(timeout_sec=1.0)
    assert list(received[0].position) == [0.5, 1.0, 2.0]
    assert list(received[0].name) == ['a', 'b', 'c']


def test_each_subscription_gets_its_own_copy(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """As rclpy deserializes per subscription, a callback mutating its message affects no other."""
    first: list[JointState] = []
    second: list[JointState] = []

    def mutate(msg: JointState) -> None:
        msg.position[0] = -1.0
        first.append(msg)

    node.create_subscription(JointState, 'joints', mutate, 10)
    node.create_subscription(JointState, 'joints', second.append, 10)
    node.create_publisher(JointState, 'joints', 10).publish(joint_state(0.25))
    executor.spin_once(timeout_sec=1.0)
    executor.spin_once(timeout_sec=1.0)
    assert first[0].position[0] == -1.0
    assert second[0].position[0] == 0.25
    assert first[0] is not second[0]


def test_raw_subscription_receives_cdr_bytes_that_deserialize_back(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """With raw=True (rclpy) the callback gets the CDR bytes, with their 4-byte header."""
    received: list[bytes] = []
    node.create_subscription(JointState, 'joints', received.append, 10, raw=True)
    msg = joint_state(0.75)
    node.create_publisher(JointState, 'joints', 10).publish(msg)
    executor.spin_once(timeout_sec=1.0)
    assert isinstance(received[0], bytes)
    assert received[0] == serialize_message(msg)
    assert received[0][:4] == b'\x00\x01\x00\x00'
    assert deserialize_message(received[0], JointState) == msg


def test_publishing_bytes_delivers_the_deserialized_message(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """Publisher.publish accepts the bytes of a serialized message, as rclpy's publish_raw."""
    received: list[JointState] = []
    node.create_subscription(JointState, 'joints', received.append, 10)
    msg = joint_state(1.5)
    node.create_publisher(JointState, 'joints', 10).publish(serialize_message(msg))
    executor.spin_once(timeout_sec=1.0)
    assert received == [msg]


def test_publishing_wrong_message_type_raises_type_error_naming_both_types(node: Node) -> None:
    """As in rclpy, publishing another type raises TypeError('Expected <type>, got <type>')."""
    publisher = node.create_publisher(String, 'chatter', 10)
    with pytest.raises(TypeError, match=r'Expected .*String.*, got .*Float64'):
        publisher.publish(Float64(data=1.0))


def test_create_publisher_rejects_a_message_instance_as_type(node: Node) -> None:
    """As in rclpy, msg_type must be a message class; an instance fails at creation."""
    with pytest.raises(TypeError, match='not a ROS message class'):
        node.create_publisher(String(), 'chatter', 10)  # type: ignore[arg-type]


def test_keep_last_depth_keeps_only_newest_messages(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """KEEP_LAST depth 3: of 10 messages published before spinning, the last 3 arrive in order."""
    received: list[float] = []
    node.create_subscription(Float64, 'values', lambda m: received.append(m.data), 3)
    publisher = node.create_publisher(Float64, 'values', 10)
    for i in range(10):
        publisher.publish(Float64(data=float(i)))
    for _ in range(10):
        executor.spin_once(timeout_sec=0)
    assert received == [7.0, 8.0, 9.0]


def test_subscription_callbacks_run_in_publish_order(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """As rclpy takes one message per wait from a subscription's queue, order is FIFO."""
    received: list[float] = []
    node.create_subscription(Float64, 'values', lambda m: received.append(m.data), 100)
    publisher = node.create_publisher(Float64, 'values', 100)
    for i in range(50):
        publisher.publish(Float64(data=float(i)))
    for _ in range(50):
        executor.spin_once(timeout_sec=0)
    assert received == [float(i) for i in range(50)]


def test_transient_local_late_joiner_receives_last_depth_messages(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """TRANSIENT_LOCAL publisher depth 2 replays its last 2 messages to a late TL subscription."""
    latched = QoSProfile(depth=2, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    publisher = node.create_publisher(String, 'map', latched)
    for text in ('one', 'two', 'three'):
        publisher.publish(String(data=text))
    received: list[str] = []
    node.create_subscription(String, 'map', lambda m: received.append(m.data), latched)
    for _ in range(5):
        executor.spin_once(timeout_sec=0)
    assert received == ['two', 'three']


def test_volatile_late_joiner_gets_nothing_published_before_it(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """DDS durability: a VOLATILE subscription to a TRANSIENT_LOCAL publisher gets no history."""
    latched = QoSProfile(depth=2, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    publisher = node.create_publisher(String, 'map', latched)
    publisher.publish(String(data='old'))
    received: list[str] = []
    node.create_subscription(String, 'map', lambda m: received.append(m.data), 10)
    executor.spin_once(timeout_sec=0)
    publisher.publish(String(data='new'))
    executor.spin_once(timeout_sec=0)
    assert received == ['new']


def test_best_effort_publisher_does_not_reach_reliable_subscription(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """DDS: RELIABLE subscription and BEST_EFFORT publisher are incompatible; nothing arrives."""
    received: list[str] = []
    node.create_subscription(String, 'scan', lambda m: received.append(m.data), 10)
    publisher = node.create_publisher(String, 'scan', qos_profile_sensor_data)
    publisher.publish(String(data='x'))
    executor.spin_once(timeout_sec=0)
    assert received == []
    assert publisher.get_subscription_count() == 0


def test_reliable_publisher_reaches_best_effort_subscription(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """DDS: a BEST_EFFORT subscription matches a RELIABLE publisher."""
    received: list[str] = []
    node.create_subscription(
        String, 'scan', lambda m: received.append(m.data), qos_profile_sensor_data
    )
    node.create_publisher(String, 'scan', 10).publish(String(data='x'))
    executor.spin_once(timeout_sec=0)
    assert received == ['x']


def test_qos_profile_requires_history_or_depth() -> None:
    """rclpy.qos: QoSProfile() without history and depth raises InvalidQoSProfileException."""
    from rclpy.qos import InvalidQoSProfileException

    with pytest.raises(InvalidQoSProfileException):
        QoSProfile()
    profile = QoSProfile(depth=7)
    assert profile.history == HistoryPolicy.KEEP_LAST
    assert profile.reliability == ReliabilityPolicy.RELIABLE
    assert profile.durability == DurabilityPolicy.VOLATILE


def test_integer_qos_is_keep_last_depth(node: Node) -> None:
    """As in rclpy, an int qos_profile means KEEP_LAST with that depth and default policies."""
    publisher = node.create_publisher(String, 'chatter', 4)
    assert publisher.qos_profile == QoSProfile(depth=4)


def test_destroyed_subscription_receives_nothing(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """As in rclpy, a destroyed subscription leaves the graph and gets no later messages."""
    received: list[str] = []
    subscription = node.create_subscription(String, 'chatter', received.append, 10)
    publisher = node.create_publisher(String, 'chatter', 10)
    assert node.destroy_subscription(subscription)
    publisher.publish(String(data='x'))
    executor.spin_once(timeout_sec=0)
    assert received == []
    assert node.count_subscribers('chatter') == 0


def test_destroyed_node_leaves_the_graph(context: Context, node: Node) -> None:
    """As in rclpy, destroy_node destroys the node's publishers and subscriptions."""
    other = Node('other', context=context)
    other.create_publisher(String, '/shared', 10)
    other.create_subscription(String, '/shared', lambda m: None, 10)
    assert node.count_publishers('/shared') == 1
    other.destroy_node()
    assert node.count_publishers('/shared') == 0
    assert node.count_subscribers('/shared') == 0
    assert 'other' not in node.get_node_names()


def test_relative_private_and_absolute_names_resolve_as_ros2(context: Context) -> None:
    """As rcl expands names: relative ones get the namespace, ~ the node's name, / stays."""
    named = Node('controller', namespace='/uvms', context=context)
    try:
        relative = named.create_publisher(String, 'joint_states', 10)
        private = named.create_publisher(String, '~/debug', 10)
        absolute = named.create_publisher(String, '/clock_like', 10)
        assert relative.topic_name == '/uvms/joint_states'
        assert private.topic_name == '/uvms/controller/debug'
        assert absolute.topic_name == '/clock_like'
    finally:
        named.destroy_node()


def test_invalid_topic_name_raises(node: Node) -> None:
    """As in rclpy, an invalid topic name raises InvalidTopicNameException at creation."""
    from rclpy.exceptions import InvalidTopicNameException

    with pytest.raises(InvalidTopicNameException, match='topic name'):
        node.create_publisher(String, 'bad name', 10)


def test_topic_names_and_types_list_every_topic_of_the_context(node: Node) -> None:
    """As in rclpy, get_topic_names_and_types gives (name, ['pkg/msg/Type']) per topic."""
    node.create_publisher(JointState, '/uvms/joint_states', 10)
    topics = dict(node.get_topic_names_and_types())
    assert topics['/uvms/joint_states'] == ['sensor_msgs/msg/JointState']
    assert topics['/parameter_events'] == ['rcl_interfaces/msg/ParameterEvent']
    assert topics['/rosout'] == ['rcl_interfaces/msg/Log']


def test_publish_from_another_thread_wakes_blocked_spin_once(
    node: Node, executor: SingleThreadedExecutor
) -> None:
    """As in rclpy, a message arriving wakes an executor blocked in spin_once(timeout_sec=None)."""
    received: list[str] = []
    node.create_subscription(String, 'chatter', lambda m: received.append(m.data), 10)
    publisher = node.create_publisher(String, 'chatter', 10)

    def publish_later() -> None:
        time.sleep(0.05)
        publisher.publish(String(data='wake'))

    thread = threading.Thread(target=publish_later)
    thread.start()
    start = time.monotonic()
    executor.spin_once(timeout_sec=5.0)
    thread.join()
    assert received == ['wake']
    assert time.monotonic() - start < 2.0


def test_numpy_arrays_arrive_as_published(node: Node, executor: SingleThreadedExecutor) -> None:
    """Message fields set from numpy keep their values through delivery."""
    received: list[JointState] = []
    node.create_subscription(JointState, 'joints', received.append, 10)
    msg = JointState(name=['q1', 'q2'], position=np.array([0.1, -0.2]))
    node.create_publisher(JointState, 'joints', 10).publish(msg)
    executor.spin_once(timeout_sec=0)
    np.testing.assert_array_equal(np.asarray(received[0].position), [0.1, -0.2])


def test_publishing_after_shutdown_raises(context: Context, node: Node) -> None:
    """As in rclpy, publishing on a shut-down context raises an RCLError (a RuntimeError)."""
    publisher = node.create_publisher(String, 'chatter', 10)
    context.shutdown()
    with pytest.raises(RuntimeError, match='context is invalid'):
        publisher.publish(String(data='late'))


def test_incompatible_qos_is_reported_with_rclpy_warning(
    node: Node, capfd: pytest.CaptureFixture[str]
) -> None:
    """As rclpy's default QoS event handlers: an incompatible pair logs the offending policy."""
    node.create_subscription(
        String, 'latched', lambda m: None,
        QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL),
    )
    node.create_publisher(String, 'latched', 10)
    err = capfd.readouterr().err
    assert "New publisher discovered on topic '/latched', offering incompatible QoS" in err
    assert 'Last incompatible policy: DURABILITY' in err


def test_sensor_data_preset_is_best_effort_keep_last_5() -> None:
    """As rmw's qos_profile_sensor_data: KEEP_LAST 5, BEST_EFFORT, VOLATILE."""
    from rclpy.qos import QoSPresetProfiles

    assert QoSPresetProfiles.get_from_short_key('sensor_data') == qos_profile_sensor_data
    assert qos_profile_sensor_data.depth == 5
    assert qos_profile_sensor_data.reliability == ReliabilityPolicy.BEST_EFFORT
    assert qos_profile_sensor_data.durability == DurabilityPolicy.VOLATILE


def test_qos_argument_of_wrong_type_raises(node: Node) -> None:
    """As in rclpy, qos_profile must be a QoSProfile or an int depth."""
    with pytest.raises(TypeError, match='Expected QoSProfile or int'):
        node.create_publisher(String, 'chatter', 'reliable')  # type: ignore[arg-type]
    with pytest.raises(ValueError, match='history depth must be greater than or equal to zero'):
        node.create_publisher(String, 'chatter', -1)
