"""Publishers: send messages (or serialized bytes) to the subscriptions of a topic."""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from rclpy._support import message_support
from rclpy.exceptions import InvalidHandle
from rclpy.impl.implementation_singleton import RCLError
from rclpy.qos import DurabilityPolicy, QoSProfile

if TYPE_CHECKING:
    from rclpy.callback_groups import CallbackGroup
    from rclpy.node import Node
    from rclpy.subscription import Subscription

MsgT = TypeVar('MsgT')


class Publisher(Generic[MsgT]):
    """Publishes messages of one type on one topic (create with ``node.create_publisher``).

    Each subscription gets its own copy of the message as it was at ``publish`` time, as with
    rclpy (which serializes): changing the message afterwards changes nothing delivered. A
    TRANSIENT_LOCAL publisher keeps its last ``depth`` messages for late-joining
    TRANSIENT_LOCAL subscriptions.
    """

    def __init__(
        self,
        node: Node,
        msg_type: type[MsgT],
        topic: str,
        topic_name: str,
        qos_profile: QoSProfile,
        callback_group: CallbackGroup,
    ) -> None:
        support = message_support()
        self._node = node
        self._context = node.context
        self.msg_type = msg_type
        self.topic = topic
        self._topic_name = topic_name
        self.qos_profile = qos_profile
        self.callback_group = callback_group
        self.event_handlers: list[Any] = []
        self._type_name: str = support.message_type_name(msg_type)
        self._copy = support.copy_message
        self._serialize = support.serialize
        self._deserialize = support.deserialize
        self._matched: tuple[Subscription, ...] = ()
        self._history: deque[Any] | None = None
        if qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL:
            self._history = deque(maxlen=qos_profile._keep())
        self._destroyed = False

    @property
    def topic_name(self) -> str:
        """Fully qualified (expanded and remapped) topic name."""
        return self._topic_name

    @property
    def handle(self) -> Publisher[MsgT]:
        """Handle of the publisher (usable in ``with``)."""
        self._check()
        return self

    def __enter__(self) -> Publisher[MsgT]:
        return self

    def __exit__(self, *exc_info: object) -> None:
        return None

    def _check(self) -> None:
        if self._destroyed:
            raise InvalidHandle('cannot use Destroyable because destruction was requested')

    def _set_matched(self, subscriptions: tuple[Subscription, ...]) -> None:
        self._matched = subscriptions

    def publish(self, msg: MsgT | bytes) -> None:
        """Send a message, or bytes holding a serialized message (CDR with its header).

        Raises:
            TypeError: If ``msg`` is neither a ``msg_type`` instance nor bytes.
            InvalidHandle: If the publisher was destroyed.
            RCLError: If the context was shut down.
        """
        if self._destroyed:
            self._check()
        if not self._context._ok:
            raise RCLError("Failed to publish: publisher's context is invalid")
        if type(msg) is self.msg_type or isinstance(msg, self.msg_type):
            matched = self._matched
            if matched:
                copy = self._copy
                serialized = None
                for subscription in matched:
                    if subscription.raw:
                        if serialized is None:
                            serialized = self._serialize(msg)
                        subscription._deliver(serialized)
                    else:
                        subscription._deliver(copy(msg))
            if self._history is not None:
                self._history.append(self._copy(msg))
        elif isinstance(msg, bytes):
            self._publish_serialized(msg)
        else:
            raise TypeError(f'Expected {self.msg_type}, got {type(msg)}')

    def _publish_serialized(self, data: bytes) -> None:
        for subscription in self._matched:
            if subscription.raw:
                subscription._deliver(data)
            else:
                subscription._deliver(self._deserialize(data, self.msg_type))
        if self._history is not None:
            self._history.append(self._deserialize(data, self.msg_type))

    def _deliver_history(self, subscription: Subscription) -> None:
        """Hand a late-joining TRANSIENT_LOCAL subscription the messages kept."""
        if self._history is None or subscription.qos_profile.durability not in (
            DurabilityPolicy.TRANSIENT_LOCAL, DurabilityPolicy.BEST_AVAILABLE
        ):
            return
        for msg in list(self._history):
            if subscription.raw:
                subscription._deliver(self._serialize(msg))
            else:
                subscription._deliver(self._copy(msg))

    def get_subscription_count(self) -> int:
        """Return the number of subscriptions matched with this publisher."""
        self._check()
        return len(self._matched)

    def assert_liveliness(self) -> None:
        """Assert liveliness (nothing to do in process)."""
        self._check()

    def wait_for_all_acked(self, timeout: Any = None) -> bool:
        """Return True: in-process delivery is complete when ``publish`` returns."""
        self._check()
        return True

    def destroy(self) -> None:
        """Destroy the publisher; prefer ``node.destroy_publisher``."""
        if not self._destroyed:
            self._destroyed = True
            self._node.context._graph.remove_publisher(self)
            self._history = None
