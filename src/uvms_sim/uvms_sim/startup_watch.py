"""The simulator's view of the control loop at start-up: lifecycle states and first answers.

Adapter of `uvms_sim.startup.LoopStartup`: a raw subscription to the controller's
``command/generalized_force`` (only its header stamp is read), and in real time a
``<node>/get_state`` client per managed node of ``startup.nodes``, asked every
``POLL_PERIOD_S``. Everything is destroyed once the loop is closed, so the running loop
carries no extra subscription.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any

from lifecycle_msgs.srv import GetState
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import (
    DurabilityPolicy,
    QoSCompatibility,
    QoSProfile,
    ReliabilityPolicy,
    qos_check_compatible,
)
from rclpy.task import Future
from std_msgs.msg import Bool

from uvms_msgs.msg import GeneralizedForce
from uvms_sim.errors import StartupError
from uvms_sim.startup import (
    ACTUATOR_TOPIC,
    COMMAND_TOPIC,
    LoopStartup,
    StartupSettings,
    subscriber_matched,
)

#: Wall time between two ``get_state`` requests to a node that is not active yet (s).
POLL_PERIOD_S = 0.2
#: Wall time after which an unanswered ``get_state`` request is given up and sent again (s).
_REQUEST_TIMEOUT_S = 2.0


def header_stamp_ns(data: bytes) -> int | None:
    """The ``std_msgs/Header`` stamp (ns) at the start of a serialized CDR message."""
    if len(data) < 12:
        return None
    order = '<' if data[1] == 1 else '>'  # encapsulation 00 01: CDR little endian
    sec, nanosec = struct.unpack_from(order + 'iI', data, 4)
    return sec * 1_000_000_000 + nanosec


class StartupWatch:
    """Watches controller and allocator answer the held initial state, until the loop closes."""

    def __init__(self, node: Node, settings: StartupSettings, realtime: bool,
                 start_ns: int) -> None:
        """Subscribe and create the lifecycle clients of ``node`` (the simulator)."""
        self._node = node
        self.core = LoopStartup(settings, realtime, start_ns)
        self.held_stamp_ns = 0
        self._subscription: Any = node.create_subscription(
            GeneralizedForce, COMMAND_TOPIC, self._on_command,
            QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE), raw=True)
        self._clients = ({name: node.create_client(GetState, f'{name}/get_state')
                          for name in settings.nodes} if realtime else {})
        self._pending: dict[str, Future] = {}
        self._asked_ns: dict[str, int] = {}

    def _on_command(self, data: bytes) -> None:
        stamp = header_stamp_ns(data)
        self.core.generalized_force(self.core.realtime or stamp == self.held_stamp_ns)

    def poll(self, now_ns: int) -> None:
        """Ask each managed node that is not known active for its state (at most 5 Hz)."""
        for name, client in self._clients.items():
            waited_ns = now_ns - self._asked_ns.get(name, -10**18)
            if waited_ns < POLL_PERIOD_S * 1e9 or (
                    name in self._pending and waited_ns < _REQUEST_TIMEOUT_S * 1e9):
                continue
            self._pending.pop(name, None)  # unanswered: a service seen but gone, ask again
            self._asked_ns[name] = now_ns
            if not client.service_is_ready():
                self.core.node_state(name, None)
                continue
            future = client.call_async(GetState.Request())
            self._pending[name] = future
            future.add_done_callback(lambda f, n=name: self._on_state(n, f))

    def _on_state(self, name: str, future: Future) -> None:
        if self._pending.get(name) is not future:
            return  # given up on, or the watch is done
        self._pending.pop(name)
        response = future.result()
        if response is not None:
            self.core.node_state(name, str(response.current_state.label))

    def failure(self, now_ns: int) -> str:
        """The start-up error naming the node that did not answer (the ROS graph asked)."""
        publishers = {topic: [info.node_name for info in self._node.get_publishers_info_by_topic(
            self._node.resolve_topic_name(topic))] for topic in (COMMAND_TOPIC, ACTUATOR_TOPIC)}
        return self.core.failure(now_ns, publishers)

    def destroy(self) -> None:
        """Drop the subscription and the clients: the loop is closed."""
        if self._subscription is not None:
            self._node.destroy_subscription(self._subscription)
            self._subscription = None
        for client in self._clients.values():
            self._node.destroy_client(client)
        self._clients = {}
        self._pending = {}


def recorded_publishers(namespace: str, publishers: Sequence[Publisher]) -> list[Publisher]:
    """The state publishers a recorder of ``namespace`` subscribes to: ``/clock`` and those in it.

    A topic remapped out of the namespace is not the recording's: with ``--hardware twin`` the
    measurements go to ``/plant`` for the twins, and the recording takes them from the bridges.
    """
    inside = namespace.rstrip('/') + '/'
    return [p for p in publishers if p.topic_name == '/clock' or p.topic_name.startswith(inside)]


class SubscriberWait:
    """Before the first state: whether a node (the recorder) subscribes to the state topics.

    ``startup.recorder``: the simulator publishes its first state only once that node's
    subscriptions to each of ``publishers`` are matched, so that a recording holds the run
    from t = 0. The ROS graph is asked at most every ``POLL_PERIOD_S``.
    """

    def __init__(self, node: Node, settings: StartupSettings,
                 publishers: Sequence[Publisher]) -> None:
        """Wait for ``settings.recorder`` (none: ``passed`` at once) on ``publishers``, from now.

        The timeout is ``settings.timeout_ns`` of the node's clock (the simulator's: wall time).
        """
        self._node = node
        self.subscriber = subscriber = settings.recorder
        self._publishers = list(publishers)
        if settings.recorder_topics:
            recorded = {node.resolve_topic_name(topic) for topic in settings.recorder_topics}
            self._publishers = [p for p in self._publishers if p.topic_name in recorded]
        self.start_ns = node.get_clock().now().nanoseconds
        self._timeout_ns = settings.timeout_ns
        self._asked_ns: int | None = None
        self.missing = [publisher.topic_name for publisher in self._publishers]
        self._passed = not subscriber
        if subscriber:
            node.get_logger().info(f'publishing the first state once {subscriber} subscribes '
                                   'to the state topics (startup.recorder)')

    def passed(self, now_ns: int) -> bool:
        """Whether the node has subscribed (True at once without one); raise after the timeout.

        Raises:
            StartupError: ``startup.timeout_s`` passed without it subscribing; the message
                names the node and the topics.
        """
        if self._passed:
            return True
        if self.ready(now_ns):
            self._passed = True
            self._node.get_logger().info(
                f'{self.subscriber} subscribed to the state topics after '
                f'{(now_ns - self.start_ns) * 1e-9:.2f} s: publishing the initial state')
            return True
        if self.expired(now_ns):
            msg = self.failure(now_ns)
            self._node.get_logger().fatal(msg)
            raise StartupError(msg)
        return False

    def ready(self, now_ns: int) -> bool:
        """Whether every state topic's subscription of the node is matched (asks the graph)."""
        if self._asked_ns is not None and now_ns - self._asked_ns < POLL_PERIOD_S * 1e9:
            return not self.missing
        self._asked_ns = now_ns
        namespace = self._node.get_namespace()
        self.missing = []
        for publisher in self._publishers:
            endpoints = [(info.node_name, info.node_namespace, qos_check_compatible(
                publisher.qos_profile, info.qos_profile)[0] != QoSCompatibility.ERROR)
                for info in self._node.get_subscriptions_info_by_topic(publisher.topic_name)]
            if not subscriber_matched(self.subscriber, namespace, endpoints,
                                      publisher.get_subscription_count()):
                self.missing.append(publisher.topic_name)
        return not self.missing

    def expired(self, now_ns: int) -> bool:
        """Whether ``startup.timeout_s`` passed without the node subscribing (0: never)."""
        return 0 < self._timeout_ns <= now_ns - self.start_ns

    def failure(self, now_ns: int) -> str:
        """The start-up error naming the node and the topics it did not subscribe to."""
        return (f'{self.subscriber} did not subscribe to the state topics within '
                f'startup.timeout_s = {self._timeout_ns * 1e-9:g} s '
                f'({(now_ns - self.start_ns) * 1e-9:.1f} s; startup.recorder): no matched '
                f'subscription of it on {", ".join(self.missing)}')


class MissionWait:
    """Whether the mission has found the controller's action server, before physics starts.

    ``startup.mission``: the simulator starts physics only once True arrives on the mission's
    latched readiness topic, so that a goal never starts late (or not at all) because the
    mission was still discovering the action server while physics ran. In lockstep the
    first state waits for it; in real time the held initial state goes out at once and the
    loop's start-up hold waits for it too.
    """

    def __init__(self, node: Node, settings: StartupSettings,
                 waiting: str = 'publishing the first state') -> None:
        """Subscribe to ``settings.mission`` (none: ``passed`` at once), from now.

        The timeout is ``settings.timeout_ns`` of the node's clock (the simulator's: wall time);
        ``waiting`` says in the log line what waits for the mission.
        """
        self._node = node
        self.topic = settings.mission
        self.start_ns = node.get_clock().now().nanoseconds
        self._timeout_ns = settings.timeout_ns
        self.ready = not self.topic
        self._passed = self.ready
        self._subscription: Any = None
        if self.topic:
            self._subscription = node.create_subscription(
                Bool, self.topic, self._on_ready, QoSProfile(
                    depth=1, reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.TRANSIENT_LOCAL))
            node.get_logger().info(
                f'{waiting} once the mission is ready ({self.topic}, startup.mission)')

    def _on_ready(self, message: Bool) -> None:
        self.ready = self.ready or bool(message.data)

    def passed(self, now_ns: int) -> bool:
        """Whether the mission said it is ready (True at once without one); raise past the timeout.

        Raises:
            StartupError: ``startup.timeout_s`` passed without it; the message names the topic.
        """
        if self._passed:
            return True
        if self.ready:
            self._passed = True
            self._node.get_logger().info(
                f'the mission is ready after {(now_ns - self.start_ns) * 1e-9:.2f} s')
            self._node.destroy_subscription(self._subscription)
            self._subscription = None
            return True
        if 0 < self._timeout_ns <= now_ns - self.start_ns:
            msg = (f'the mission did not say it is ready within startup.timeout_s = '
                   f'{self._timeout_ns * 1e-9:g} s (no True on {self.topic}, '
                   "startup.mission): it did not find the controller's action server, or "
                   'it is not running')
            self._node.get_logger().fatal(msg)
            raise StartupError(msg)
        return False


class StartGates:
    """What the first state and physics wait for besides the control loop: recorder, mission.

    In lockstep (and real time without the start-up hold) the first state waits for both.
    In real time with the hold the held state goes out once the recorder subscribes (with
    ``--hardware twin`` the twins answer the bridges only once the plant has a state), and
    physics waits for the mission beside the loop's own start-up.
    """

    def __init__(self, node: Node, settings: StartupSettings, publishers: Sequence[Publisher],
                 realtime_hold: bool) -> None:
        """The recorder's wait on ``publishers`` and the mission's, as ``settings`` ask."""
        self.recorder = SubscriberWait(node, settings, publishers)
        self._mission_holds_physics = realtime_hold
        self.mission = MissionWait(node, settings, 'starting physics' if realtime_hold
                                   else 'publishing the first state')

    def first_state(self, now_ns: int) -> bool:
        """Whether the first state may go out (raises past ``startup.timeout_s``)."""
        return self.recorder.passed(now_ns) and (
            self._mission_holds_physics or self.mission.passed(now_ns))

    def physics(self, now_ns: int) -> bool:
        """Whether physics may start as far as the mission goes (raises past the timeout)."""
        return self.mission.passed(now_ns)
