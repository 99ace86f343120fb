"""The in-process ROS graph of one context: nodes, topics and the endpoints matched on them."""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING, Any

from rclpy.qos import QoSCompatibility, qos_check_compatible

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.publisher import Publisher
    from rclpy.subscription import Subscription


class _Topic:
    __slots__ = ('publishers', 'subscriptions')

    def __init__(self) -> None:
        self.publishers: list[Publisher] = []
        self.subscriptions: list[Subscription] = []


class Graph:
    """Who publishes and subscribes what in one context; connects matching endpoints.

    A publisher and a subscription are connected when they use the same topic, the same
    message type and compatible QoS (a BEST_EFFORT publisher does not serve a RELIABLE
    subscription; a VOLATILE publisher does not serve a TRANSIENT_LOCAL one), as DDS does.
    """

    def __init__(self) -> None:
        self._lock = threading.RLock()
        self._topics: dict[str, _Topic] = {}
        self._nodes: list[Node] = []

    def add_node(self, node: Node) -> None:
        """Register a node."""
        with self._lock:
            self._nodes.append(node)

    def remove_node(self, node: Node) -> None:
        """Forget a node."""
        with self._lock:
            if node in self._nodes:
                self._nodes.remove(node)

    def nodes(self) -> list[Node]:
        """Return the registered nodes in creation order."""
        with self._lock:
            return list(self._nodes)

    @staticmethod
    def _connects(publisher: Publisher, subscription: Subscription) -> bool:
        if publisher._type_name != subscription._type_name:
            return False
        compatibility, _ = qos_check_compatible(publisher.qos_profile, subscription.qos_profile)
        return compatibility != QoSCompatibility.ERROR

    def _refresh(self, topic: _Topic) -> None:
        for publisher in topic.publishers:
            publisher._set_matched(
                tuple(s for s in topic.subscriptions if self._connects(publisher, s))
            )

    def add_publisher(self, publisher: Publisher) -> None:
        """Register a publisher and connect it to the matching subscriptions."""
        with self._lock:
            topic = self._topics.setdefault(publisher.topic_name, _Topic())
            topic.publishers.append(publisher)
            self._refresh(topic)
            for subscription in topic.subscriptions:
                _warn_if_incompatible_qos(publisher, subscription, new_publisher=True)

    def add_subscription(self, subscription: Subscription) -> None:
        """Register a subscription, connect it, and hand it transient-local history."""
        with self._lock:
            topic = self._topics.setdefault(subscription.topic_name, _Topic())
            topic.subscriptions.append(subscription)
            self._refresh(topic)
            for publisher in topic.publishers:
                if self._connects(publisher, subscription):
                    publisher._deliver_history(subscription)
                else:
                    _warn_if_incompatible_qos(publisher, subscription, new_publisher=False)

    def remove_publisher(self, publisher: Publisher) -> None:
        """Disconnect and forget a publisher."""
        with self._lock:
            topic = self._topics.get(publisher.topic_name)
            if topic is None or publisher not in topic.publishers:
                return
            topic.publishers.remove(publisher)
            publisher._set_matched(())
            self._drop_if_empty(publisher.topic_name, topic)

    def remove_subscription(self, subscription: Subscription) -> None:
        """Disconnect and forget a subscription."""
        with self._lock:
            topic = self._topics.get(subscription.topic_name)
            if topic is None or subscription not in topic.subscriptions:
                return
            topic.subscriptions.remove(subscription)
            self._refresh(topic)
            self._drop_if_empty(subscription.topic_name, topic)

    def _drop_if_empty(self, name: str, topic: _Topic) -> None:
        if not topic.publishers and not topic.subscriptions:
            del self._topics[name]

    def publishers(self, topic_name: str) -> list[Publisher]:
        """Return the publishers of a topic."""
        with self._lock:
            topic = self._topics.get(topic_name)
            return list(topic.publishers) if topic else []

    def subscriptions(self, topic_name: str) -> list[Subscription]:
        """Return the subscriptions of a topic."""
        with self._lock:
            topic = self._topics.get(topic_name)
            return list(topic.subscriptions) if topic else []

    def topic_names_and_types(self) -> list[tuple[str, list[str]]]:
        """Return every topic with the sorted message type names used on it, sorted by name."""
        with self._lock:
            result = []
            for name in sorted(self._topics):
                topic = self._topics[name]
                types = {e._type_name for e in [*topic.publishers, *topic.subscriptions]}
                result.append((name, sorted(types)))
            return result

    def endpoints_of_node(self, node: Any, publishers: bool) -> list[tuple[str, list[str]]]:
        """Return the topics (with types) a node publishes or subscribes to."""
        with self._lock:
            found: dict[str, set[str]] = {}
            for name, topic in self._topics.items():
                endpoints = topic.publishers if publishers else topic.subscriptions
                for endpoint in endpoints:
                    if endpoint._node is node:
                        found.setdefault(name, set()).add(endpoint._type_name)
            return [(name, sorted(types)) for name, types in sorted(found.items())]


def _warn_if_incompatible_qos(
    publisher: Publisher, subscription: Subscription, *, new_publisher: bool
) -> None:
    """Log rclpy's default warnings for a publisher and subscription with incompatible QoS."""
    if publisher._type_name != subscription._type_name:
        return
    compatibility, reason = qos_check_compatible(
        publisher.qos_profile, subscription.qos_profile
    )
    if compatibility != QoSCompatibility.ERROR:
        return
    policy = 'RELIABILITY' if 'reliab' in reason.lower() else 'DURABILITY'
    topic = publisher.topic_name
    if new_publisher:
        subscription._node.get_logger().warning(
            f"New publisher discovered on topic '{topic}', offering incompatible QoS. "
            f'No messages will be received from it. Last incompatible policy: {policy}'
        )
    else:
        publisher._node.get_logger().warning(
            f"New subscription discovered on topic '{topic}', requesting incompatible QoS. "
            f'No messages will be sent to it. Last incompatible policy: {policy}'
        )
