"""Foxglove client publishing onto the pilot topics, and nothing else (issue 51).

A Foxglove client (the app's Teleop or Publish panel, a script) advertises a channel, then
sends messages on it (Foxglove WebSocket protocol: ``clientAdvertise``, client message data;
the SDK's ``ClientPublish`` capability). A channel is taken when its topic is a pilot topic,
its schema one of that topic's (``ACCEPTED``) and its encoding ``json`` or ``cdr``; anything
else is refused with one console line naming client, topic, schema and encoding, and its
messages are dropped. Taken messages are published on ROS:

- geometry_msgs/Twist (what Foxglove's Teleop panel publishes) becomes a TwistStamped stamped
  with this node's now in the vehicle body frame (base_link_frd);
- a TwistStamped with a zero stamp (the Publish panel's template) gets this node's now; any
  other stamp and frame go on unchanged for the controller to judge;
- std_msgs/Float64 goes to the jaw as it is.

A message that cannot be decoded is dropped, named once per channel on the console.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from geometry_msgs.msg import Twist, TwistStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from std_msgs.msg import Float64

#: Pilot topics relative to the node's namespace (/uvms), and the schemas each takes.
ACCEPTED: dict[str, tuple[type, frozenset[str]]] = {
    'pilot/vehicle_twist': (TwistStamped, frozenset({
        'geometry_msgs/msg/TwistStamped', 'geometry_msgs/TwistStamped',
        'geometry_msgs/msg/Twist', 'geometry_msgs/Twist'})),
    'pilot/ee_twist': (TwistStamped, frozenset({
        'geometry_msgs/msg/TwistStamped', 'geometry_msgs/TwistStamped',
        'geometry_msgs/msg/Twist', 'geometry_msgs/Twist'})),
    'pilot/jaw': (Float64, frozenset({'std_msgs/msg/Float64', 'std_msgs/Float64'})),
}
#: Encodings of client messages this server decodes (serverInfo supportedEncodings).
ENCODINGS = ('json', 'cdr')
#: Frame of a bare Twist from a client (the Teleop panel's): the vehicle body.
BODY_FRAME = 'base_link_frd'
#: The pilot topics' QoS (the pilot interface contract): reliable, depth 10, volatile.
PILOT_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


@dataclass(frozen=True)
class _Channel:
    topic: str
    schema: str
    encoding: str


def _schema_type(schema: str) -> type:
    return Float64 if schema.endswith('Float64') else (
        TwistStamped if schema.endswith('TwistStamped') else Twist)


def _vector(target: Any, values: dict[str, Any]) -> None:
    target.x, target.y, target.z = (float(values.get(k, 0.0)) for k in ('x', 'y', 'z'))


def _twist_from_json(target: Twist, values: dict[str, Any]) -> None:
    _vector(target.linear, values.get('linear', {}))
    _vector(target.angular, values.get('angular', {}))


def decode(data: bytes, schema: str, encoding: str) -> Any:
    """A client message as a ROS message of its schema's type.

    Raises:
        ValueError: The payload does not decode as that type (the message says why).
    """
    kind = _schema_type(schema)
    if encoding == 'cdr':
        try:
            return deserialize_message(bytes(data), kind)
        except Exception as exc:  # rclpy raises its C layer's error types
            msg = f'not CDR of {schema}: {exc}'
            raise ValueError(msg) from None
    try:
        values = json.loads(bytes(data).decode('utf-8'))
        if kind is Float64:
            return Float64(data=float(values['data']))
        if kind is Twist:
            twist = Twist()
            _twist_from_json(twist, values)
            return twist
        msg = TwistStamped()
        header, stamp = values.get('header', {}), values.get('header', {}).get('stamp', {})
        msg.header.frame_id = str(header.get('frame_id', ''))
        msg.header.stamp.sec = int(stamp.get('sec', 0))
        msg.header.stamp.nanosec = int(stamp.get('nanosec', stamp.get('nsec', 0)))
        _twist_from_json(msg.twist, values.get('twist', {}))
        return msg
    except (ValueError, KeyError, TypeError, AttributeError, UnicodeDecodeError) as exc:
        msg_text = f'not JSON of {schema}: {exc!r}'
        raise ValueError(msg_text) from None


class ClientPublishing:
    """Takes Foxglove clients' channels on the pilot topics and publishes their messages.

    Called from the SDK's threads (``advertise``, ``unadvertise``, ``message``).

    Args:
        node: The node to publish on (its namespace resolves the pilot topics).
        warn: Writes one console line (the node's logger's warning).
    """

    def __init__(self, node: Node, warn: Callable[[str], None]) -> None:
        self._node = node
        self._warn = warn
        self._lock = threading.Lock()
        self._channels: dict[tuple[int, int], _Channel] = {}
        self._undecodable: set[tuple[int, int]] = set()
        self._publishers: dict[str, Any] = {}
        for relative, (kind, _) in ACCEPTED.items():
            topic = node.resolve_topic_name(relative)
            self._publishers[topic] = node.create_publisher(kind, topic, PILOT_QOS)
        self._schemas = {node.resolve_topic_name(relative): schemas
                         for relative, (_, schemas) in ACCEPTED.items()}
        self.forwarded = 0

    @property
    def topics(self) -> list[str]:
        """The pilot topics clients may publish on (absolute names)."""
        return sorted(self._publishers)

    def advertise(self, client_id: int, channel: Any) -> bool:
        """A client's channel: taken (True), or refused with one console line (False)."""
        topic, schema, encoding = channel.topic, channel.schema_name, channel.encoding
        why = None
        if topic not in self._schemas:
            why = f'not a pilot topic (clients may publish on {", ".join(self.topics)})'
        elif schema not in self._schemas[topic]:
            why = f'schema not taken there (one of {", ".join(sorted(self._schemas[topic]))})'
        elif encoding not in ENCODINGS:
            why = f'encoding not taken (one of {", ".join(ENCODINGS)})'
        if why is not None:
            self._warn(f'Foxglove client {client_id}: channel on {topic} ({schema}, '
                       f'{encoding}) refused: {why}')
            return False
        with self._lock:
            self._channels[(client_id, channel.id)] = _Channel(topic, schema, encoding)
        self._node.get_logger().info(
            f'Foxglove client {client_id} publishes on {topic} ({schema}, {encoding})')
        return True

    def unadvertise(self, client_id: int, channel_id: int) -> None:
        """A client's channel is gone."""
        with self._lock:
            self._channels.pop((client_id, channel_id), None)
            self._undecodable.discard((client_id, channel_id))

    def message(self, client_id: int, channel_id: int, data: bytes) -> None:
        """A client's message: published on its pilot topic, or dropped (refused channel)."""
        key = (client_id, channel_id)
        with self._lock:
            channel = self._channels.get(key)
        if channel is None:
            return
        try:
            msg = decode(data, channel.schema, channel.encoding)
        except ValueError as exc:
            with self._lock:
                first = key not in self._undecodable
                self._undecodable.add(key)
            if first:
                self._warn(f'Foxglove client {client_id}: message on {channel.topic} '
                           f'dropped: {exc} (said once per channel)')
            return
        if isinstance(msg, Twist):
            msg = TwistStamped(twist=msg)
            msg.header.frame_id = BODY_FRAME
            msg.header.stamp = self._node.get_clock().now().to_msg()
        elif isinstance(msg, TwistStamped) and (msg.header.stamp.sec, msg.header.stamp.nanosec
                                                ) == (0, 0):
            msg.header.stamp = self._node.get_clock().now().to_msg()
        self._publishers[channel.topic].publish(msg)
        self.forwarded += 1
