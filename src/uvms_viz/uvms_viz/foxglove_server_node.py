"""The ``foxglove_server`` node: the graph's topics, live, over Foxglove's WebSocket protocol.

Every topic the recorder records is subscribed raw and forwarded unchanged (CDR) to the
Foxglove app through the foxglove-sdk server, with the ros2msg schema text the recordings
carry (``uvms_recording.typestore.message_definition``). The server binds 127.0.0.1 unless
the ``host`` parameter says otherwise (then with a warning). Nothing of the graph changes
when no one watches: the other nodes do not know this one exists. A port already in use
leaves the node idle with one error line, and the run goes on. Every client joining and
leaving is one info line, a dropped connection (a killed tab) included, with its error
(``foxglove_log``: the SDK's own log, formatted). Latched topics (/tf_static,
/robot_description) are sent again to each client that subscribes to them, as a
transient-local subscription would receive them. ``/diagnostics`` reports the server's
address, its clients (subscribed, and connected) and the forwarded message rate. Clients may
publish on the pilot topics only (``foxglove_client_publish``: Foxglove's Teleop panel drives
the vehicle); any other channel a client advertises is refused with one console line.
"""

from __future__ import annotations

import functools
import logging
import sys
import threading
from typing import Any

from rcl_interfaces.msg import IntegerRange, ParameterDescriptor
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from uvms_common.diagnostics import OK, WARN, DiagnosticsPublisher, RateMeter, Report
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.raw_clock import take_clock_raw
from uvms_recording.errors import RecordingError
from uvms_recording.recorded_topics import (
    DEFAULT_TOPICS,
    message_class,
    parse_topic_spec,
    publisher_qos,
    subscription_qos,
)
from uvms_recording.typestore import InterfaceError, message_definition

from uvms_viz.foxglove_client_publish import ENCODINGS, ClientPublishing
from uvms_viz.foxglove_defaults import FOXGLOVE_HOST, FOXGLOVE_PORT
from uvms_viz.foxglove_log import SDK_LOGGER, SdkLogHandler, capture_sdk_log

#: Hosts that keep the server on this machine.
LOOPBACK_HOSTS = ('127.0.0.1', 'localhost', '::1')
#: Package whose files the server hands to the Foxglove app (the URDF's meshes).
ASSET_PACKAGE = 'uvms_description'


class FoxgloveServerError(RuntimeError):
    """The node cannot be configured (bad parameter, unknown topic type); the message names it."""


def asset(uri: str) -> bytes | None:
    """A ``package://uvms_description/...`` file for the Foxglove app, or None.

    Only files inside uvms_description's share directory are served (the hull mesh the URDF
    names); any other URI, or a path leaving that directory, gets None.
    """
    prefix = f'package://{ASSET_PACKAGE}/'
    if not uri.startswith(prefix):
        return None
    import uvms_description

    try:
        share = uvms_description.share_directory().resolve()
    except FileNotFoundError:
        return None
    path = (share / uri[len(prefix):]).resolve()
    if not path.is_relative_to(share) or not path.is_file():
        return None
    return path.read_bytes()


class _Listener:
    """Foxglove server callbacks (SDK threads): resend latched messages, log clients."""

    def __init__(self, node: FoxgloveServerNode) -> None:
        self._node = node
        self._lock = threading.Lock()
        self._subscribed: dict[int, set[str]] = {}

    @property
    def clients(self) -> int:
        """Clients subscribed to at least one topic."""
        with self._lock:
            return len(self._subscribed)

    def on_subscribe(self, client: Any, channel: Any) -> None:
        with self._lock:
            topics = self._subscribed.setdefault(client.id, set())
            first = not topics
            topics.add(channel.topic)
        if first:
            self._node.get_logger().info(f'Foxglove client {client.id} subscribed')
        self._node.resend_latched(channel.topic)

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        with self._lock:
            topics = self._subscribed.get(client.id, set())
            topics.discard(channel.topic)
            left = not topics and client.id in self._subscribed
            if left:
                del self._subscribed[client.id]
        if left:  # the SDK's log gives the leave line of a client that disconnects
            self._node.get_logger().debug(
                f'Foxglove client {client.id} unsubscribed from every topic')

    def on_client_advertise(self, client: Any, channel: Any) -> None:
        self._node.client_publishing.advertise(client.id, channel)

    def on_client_unadvertise(self, client: Any, client_channel_id: int) -> None:
        self._node.client_publishing.unadvertise(client.id, client_channel_id)

    def on_message_data(self, client: Any, client_channel_id: int, data: bytes) -> None:
        self._node.client_publishing.message(client.id, client_channel_id, data)


class FoxgloveServerNode(Node):
    """Forwards the graph's topics, raw CDR, to Foxglove clients on ws://host:port."""

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        super().__init__('foxglove_server', **kwargs)
        self._clock_source = take_clock_raw(self)  # /clock raw under use_sim_time
        host = self.declare_parameter(
            'host', FOXGLOVE_HOST, ParameterDescriptor(
                description='Address the WebSocket server binds; 127.0.0.1 keeps it on this '
                            'machine', read_only=True)).value
        port = self.declare_parameter(
            'port', FOXGLOVE_PORT, ParameterDescriptor(
                description='TCP port of the WebSocket server; 0 picks a free one',
                read_only=True,
                integer_range=[IntegerRange(from_value=0, to_value=65535, step=1)])).value
        topic_specs = self.declare_parameter(
            'topics', list(DEFAULT_TOPICS), ParameterDescriptor(
                description="Topics to serve, each 'topic:pkg/msg/Type'; relative names "
                            'resolve in the node namespace', read_only=True)).value
        try:
            topics = {self.resolve_topic_name(topic): type_name
                      for topic, type_name in map(parse_topic_spec, topic_specs)}
            schemas = {type_name: message_definition(type_name)
                       for type_name in set(topics.values())}
            classes = {type_name: message_class(type_name) for type_name in schemas}
        except (RecordingError, InterfaceError) as exc:
            raise FoxgloveServerError(f"parameter 'topics': {exc}") from exc

        import foxglove

        capture_sdk_log()  # before the process's first server: the SDK takes it only then
        self._sdk_log = SdkLogHandler(self._log_line)
        logging.getLogger(SDK_LOGGER).addHandler(self._sdk_log)
        self._foxglove_context = foxglove.Context()
        self._channels = {
            topic: foxglove.Channel(
                topic, schema=foxglove.Schema(name=type_name, encoding='ros2msg',
                                              data=schemas[type_name].encode('utf-8')),
                message_encoding='cdr', context=self._foxglove_context)
            for topic, type_name in topics.items()
        }
        self._latched: dict[str, bytes] = {}
        self._latched_topics = {topic for topic in topics
                                if publisher_qos(topic).durability == 'transient_local'}
        self._server: Any = None
        self.client_publishing = ClientPublishing(self, self.get_logger().warning)
        self._listener = _Listener(self)
        self._address = f'ws://{host}:{port}'
        self._forwarded = 0
        self._forward_meter = RateMeter()
        self._diagnostics = DiagnosticsPublisher(self)
        self._diagnostics.add('live view', self._report)
        if host not in LOOPBACK_HOSTS:
            self.get_logger().warning(
                f"parameter 'host' = {host!r}: the live view is reachable from other machines; "
                f'use {FOXGLOVE_HOST} to keep it on this one')
        try:
            self._server = foxglove.start_server(
                name='uvms', host=host, port=port, context=self._foxglove_context,
                capabilities=[foxglove.Capability.Time, foxglove.Capability.ClientPublish],
                supported_encodings=list(ENCODINGS),
                server_listener=self._listener, asset_handler=asset)
        except RuntimeError as exc:
            # foxglove-sdk raises RuntimeError('FoxgloveError: Failed to bind port: ...').
            self.get_logger().error(
                f'no Foxglove live view: cannot serve ws://{host}:{port}: {exc}; '
                'the run goes on without it')
            return
        self._address = f'ws://{host}:{self._server.port}'
        for topic, type_name in topics.items():
            self.create_subscription(classes[type_name], topic,
                                     functools.partial(self._on_message, topic),
                                     subscription_qos(topic), raw=True)
        self.get_logger().info(
            f'Foxglove live view on ws://{host}:{self._server.port} '
            f'({len(topics)} topics, raw CDR)')

    @property
    def port(self) -> int | None:
        """The port the server listens on, None if it did not start."""
        return None if self._server is None else int(self._server.port)

    def _log_line(self, level: int, message: str) -> None:
        """A line of the SDK's log (``foxglove_log``) through this node's logger."""
        logger = self.get_logger()
        if level >= logging.ERROR:
            logger.error(message)
        elif level >= logging.WARNING:
            logger.warning(message)
        elif level >= logging.INFO:
            logger.info(message)
        else:
            logger.debug(message)

    def _on_message(self, topic: str, data: bytes) -> None:
        now_ns = self.get_clock().now().nanoseconds
        if topic in self._latched_topics:
            self._latched[topic] = data
        self._channels[topic].log(data, log_time=now_ns)
        self._forwarded += 1
        if topic == '/clock':
            self._server.broadcast_time(now_ns)

    def resend_latched(self, topic: str) -> None:
        """Send the last message of a latched topic again (to a client that just subscribed)."""
        data = self._latched.get(topic)
        if data is not None:
            self._channels[topic].log(data, log_time=self.get_clock().now().nanoseconds)

    def _report(self) -> Report:
        """/diagnostics: 'running' with address, clients and forwarded rate; WARN unserved."""
        values = {'address': self._address, 'topics': len(self._channels),
                  'client_messages_published': self.client_publishing.forwarded,
                  'clients': self._listener.clients,
                  'connected_clients': self._sdk_log.connected, 'forwarded_rate_hz':
                  self._forward_meter.rate_hz(self._forwarded,
                                              self.get_clock().now().nanoseconds)}
        if self._server is None:
            return Report(WARN, f'no live view: cannot serve {self._address}', values)
        return Report(OK, 'running', values)

    def destroy_node(self) -> None:
        """Stop the server, then destroy the node."""
        if self._server is not None:
            self._server.stop()
            self._server = None
        logging.getLogger(SDK_LOGGER).removeHandler(self._sdk_log)
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Run the Foxglove server node until SIGINT/SIGTERM."""
    sys.exit(run_node(FoxgloveServerNode, args, 'foxglove_server',
                      (FoxgloveServerError, ParameterException)))


if __name__ == '__main__':
    main()
