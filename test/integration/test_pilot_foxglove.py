"""Foxglove client publishing: a WebSocket client of the Foxglove protocol drives the pilot topics.

The foxglove_server node runs in this process on a free port; the client speaks the protocol
as the app does (``foxglove_client``: subprotocol, JSON ``clientAdvertise``, binary client
message data: opcode 1, channel id uint32 LE, payload). A subscriber in /uvms takes what
reaches ROS; refusals are read from the node's console output.
"""

from __future__ import annotations

import json
import struct
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest
import rclpy
from foxglove_client import FoxgloveClient, connect_when_up
from geometry_msgs.msg import Twist, TwistStamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.serialization import serialize_message
from std_msgs.msg import Float64
from test_pilot_tui import spin_in_thread
from uvms_viz.foxglove_server_node import FoxgloveServerNode

#: Client Message Data opcode (Foxglove WebSocket protocol, sent by clients).
CLIENT_MESSAGE_DATA = 1


@dataclass
class Graph:
    """The server node, a listener in /uvms, and what it received."""

    server: FoxgloveServerNode
    listener: Node
    received: dict[str, list[Any]] = field(default_factory=dict)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def wait(self, done: Callable[[], bool], timeout_s: float = 5.0) -> bool:
        """Poll done() until it holds or the timeout (s)."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with self.lock:
                if done():
                    return True
            time.sleep(0.02)
        return False


@pytest.fixture
def graph() -> Iterator[Graph]:
    """foxglove_server (port 0) and a listener of the pilot topics, spun in a thread."""
    context = Context()
    rclpy.init(args=[], context=context)
    server = FoxgloveServerNode(namespace='uvms', context=context, parameter_overrides=[
        Parameter('port', value=0), Parameter('topics', value=['wrench:geometry_msgs/msg/'
                                                                'WrenchStamped'])])
    listener = Node('listener', namespace='uvms', context=context)
    graph = Graph(server, listener, {'vehicle': [], 'ee': [], 'jaw': []})

    def keep(name: str) -> Callable[[Any], None]:
        def on_message(msg: Any) -> None:
            with graph.lock:
                graph.received[name].append(msg)
        return on_message

    listener.create_subscription(TwistStamped, 'pilot/vehicle_twist', keep('vehicle'), 10)
    listener.create_subscription(TwistStamped, 'pilot/ee_twist', keep('ee'), 10)
    listener.create_subscription(Float64, 'pilot/jaw', keep('jaw'), 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(server)
    executor.add_node(listener)
    end = spin_in_thread(executor)
    yield graph
    end()
    executor.shutdown(timeout_sec=2.0)
    server.destroy_node()
    listener.destroy_node()
    rclpy.try_shutdown(context=context)


@pytest.fixture
def client(graph: Graph) -> Iterator[FoxgloveClient]:
    """A connected client that has read the server's info."""
    connection = connect_when_up(f'ws://127.0.0.1:{graph.server.port}', timeout_s=20.0)
    connection.read_advertisements({'/uvms/wrench'}, timeout_s=20.0)
    yield connection
    connection.close()


def advertise(client: FoxgloveClient, channel_id: int, topic: str, schema: str,
              encoding: str) -> None:
    """Advertise one client channel (clientAdvertise)."""
    client.connection.send(json.dumps({'op': 'advertise', 'channels': [{
        'id': channel_id, 'topic': topic, 'encoding': encoding, 'schemaName': schema}]}))


def send(client: FoxgloveClient, channel_id: int, payload: bytes) -> None:
    """Client message data on a channel."""
    client.connection.send(struct.pack('<BI', CLIENT_MESSAGE_DATA, channel_id) + payload)


def twist(x: float = 0.0, yaw: float = 0.0) -> Twist:
    """A Twist with surge x (m/s) and yaw rate (rad/s)."""
    msg = Twist()
    msg.linear.x, msg.angular.z = x, yaw
    return msg


def test_server_offers_client_publishing(client: FoxgloveClient) -> None:
    """The server info offers clientPublish, with json and cdr as client encodings."""
    assert 'clientPublish' in client.server_info['capabilities']
    assert set(client.server_info['supportedEncodings']) == {'json', 'cdr'}


def test_teleop_panel_twist_in_cdr_reaches_the_vehicle_twist(graph: Graph,
                                                             client: FoxgloveClient) -> None:
    """A bare Twist (the Teleop panel's) becomes a TwistStamped in base_link_frd, stamped now."""
    advertise(client, 1, '/uvms/pilot/vehicle_twist', 'geometry_msgs/msg/Twist', 'cdr')
    time.sleep(0.3)
    before_ns = graph.server.get_clock().now().nanoseconds
    send(client, 1, serialize_message(twist(0.2, -0.1)))
    assert graph.wait(lambda: bool(graph.received['vehicle']))
    msg = graph.received['vehicle'][0]
    assert (msg.twist.linear.x, msg.twist.angular.z) == (0.2, -0.1)
    assert msg.header.frame_id == 'base_link_frd'
    stamp_ns = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
    assert 0 <= stamp_ns - before_ns < 2 * 10**9


def test_json_twist_stamped_keeps_its_frame_and_stamp(graph: Graph,
                                                      client: FoxgloveClient) -> None:
    """A JSON TwistStamped keeps its own frame and stamp; a zero stamp gets the node's now."""
    advertise(client, 7, '/uvms/pilot/ee_twist', 'geometry_msgs/msg/TwistStamped', 'json')
    time.sleep(0.3)
    send(client, 7, json.dumps({'header': {'stamp': {'sec': 12, 'nanosec': 5},
                                           'frame_id': 'map_ned'},
                                'twist': {'linear': {'x': 0.01, 'y': 0.0, 'z': -0.02},
                                          'angular': {'x': 0, 'y': 0, 'z': 0}}}).encode())
    send(client, 7, json.dumps({'header': {'frame_id': 'base_link_frd'},
                                'twist': {'linear': {'z': 0.03}}}).encode())
    assert graph.wait(lambda: len(graph.received['ee']) == 2)
    first, second = graph.received['ee']
    assert first.header.frame_id == 'map_ned'
    assert (first.header.stamp.sec, first.header.stamp.nanosec) == (12, 5)
    assert (first.twist.linear.x, first.twist.linear.z) == (0.01, -0.02)
    assert second.header.stamp.sec + second.header.stamp.nanosec > 0
    assert second.twist.linear.z == 0.03


def test_jaw_float_reaches_the_jaw(graph: Graph, client: FoxgloveClient) -> None:
    """std_msgs/Float64 (json) on the jaw topic arrives as it is."""
    advertise(client, 3, '/uvms/pilot/jaw', 'std_msgs/msg/Float64', 'json')
    time.sleep(0.3)
    send(client, 3, b'{"data": -0.005}')
    assert graph.wait(lambda: bool(graph.received['jaw']))
    assert graph.received['jaw'][0].data == -0.005


@pytest.mark.parametrize(('topic', 'schema', 'encoding', 'why'), [
    ('/uvms/command/generalized_force', 'geometry_msgs/msg/Twist', 'cdr',
     'not a pilot topic'),
    ('/uvms/pilot/vehicle_twist', 'std_msgs/msg/String', 'json', 'schema not taken there'),
    ('/uvms/pilot/jaw', 'geometry_msgs/msg/Twist', 'cdr', 'schema not taken there'),
    ('/uvms/pilot/vehicle_twist', 'geometry_msgs/msg/Twist', 'protobuf',
     'encoding not taken'),
])
def test_anything_else_is_refused_with_one_line_and_never_reaches_ros(
        graph: Graph, client: FoxgloveClient, capfd: pytest.CaptureFixture[str], topic: str,
        schema: str, encoding: str, why: str) -> None:
    """A channel off the pilot topics, of another schema or encoding: refused, named, dropped."""
    advertise(client, 5, topic, schema, encoding)
    time.sleep(0.3)
    for _ in range(3):
        send(client, 5, serialize_message(twist(1.0)))
    time.sleep(0.5)
    assert not any(graph.received.values())
    err = capfd.readouterr().err
    line = f'channel on {topic} ({schema}, {encoding}) refused: {why}'
    assert err.count(line) == 1, err


def test_undecodable_message_is_dropped_and_named_once(
        graph: Graph, client: FoxgloveClient, capfd: pytest.CaptureFixture[str]) -> None:
    """Garbage on a taken channel: nothing published, one line however many arrive."""
    advertise(client, 9, '/uvms/pilot/vehicle_twist', 'geometry_msgs/msg/Twist', 'json')
    time.sleep(0.3)
    for _ in range(3):
        send(client, 9, b'{"linear": {"x": "fast"')
    send(client, 9, json.dumps({'linear': {'x': 0.1}}).encode())
    assert graph.wait(lambda: bool(graph.received['vehicle']))
    assert graph.received['vehicle'][0].twist.linear.x == 0.1
    err = capfd.readouterr().err
    assert err.count('message on /uvms/pilot/vehicle_twist dropped: not JSON') == 1, err
