"""Subscriptions: queue messages of a topic for an executor to hand to a callback."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from rclpy._support import message_support
from rclpy.exceptions import InvalidHandle
from rclpy.qos import QoSProfile

if TYPE_CHECKING:
    from rclpy.callback_groups import CallbackGroup
    from rclpy.node import Node

MsgT = TypeVar('MsgT')


class Subscription(Generic[MsgT]):
    """Receives messages of one topic (create with ``node.create_subscription``).

    Messages wait in a queue that keeps the last ``depth`` of them (KEEP_LAST drops the oldest);
    an executor spinning the node calls ``callback`` once per message, oldest first. With
    ``raw=True`` the callback gets the serialized bytes (CDR with its 4-byte header).
    """

    def __init__(
        self,
        node: Node,
        msg_type: type[MsgT],
        topic: str,
        topic_name: str,
        callback: Callable[[Any], Any],
        callback_group: CallbackGroup,
        qos_profile: QoSProfile,
        raw: bool,
    ) -> None:
        self._node = node
        self.msg_type = msg_type
        self.topic = topic
        self._topic_name = topic_name
        self.callback = callback
        self.callback_group = callback_group
        self.qos_profile = qos_profile
        self.raw = raw
        self.event_handlers: list[Any] = []
        self._type_name: str = message_support().message_type_name(msg_type)
        self._queue: deque[Any] = deque(maxlen=qos_profile._keep())
        self._executor_event = False
        self._destroyed = False

    @property
    def topic_name(self) -> str:
        """Fully qualified (expanded and remapped) topic name."""
        return self._topic_name

    @property
    def handle(self) -> Subscription[MsgT]:
        """Handle of the subscription (usable in ``with``)."""
        if self._destroyed:
            raise InvalidHandle('cannot use Destroyable because destruction was requested')
        return self

    def __enter__(self) -> Subscription[MsgT]:
        return self

    def __exit__(self, *exc_info: object) -> None:
        return None

    def _deliver(self, item: Any) -> None:
        self._queue.append(item)
        executor = self._node._executor
        if executor is not None:
            executor._wake()

    def get_publisher_count(self) -> int:
        """Return the number of publishers matched with this subscription."""
        graph = self._node.context._graph
        return sum(1 for p in graph.publishers(self._topic_name) if self in p._matched)

    def destroy(self) -> None:
        """Destroy the subscription; prefer ``node.destroy_subscription``."""
        if not self._destroyed:
            self._destroyed = True
            self._node.context._graph.remove_subscription(self)
            self._queue.clear()
