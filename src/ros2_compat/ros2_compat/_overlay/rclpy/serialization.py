"""Serialize ROS messages to CDR bytes and back, as rclpy.serialization does.

The bytes are those rmw_fastrtps gives rclpy in Jazzy: the encapsulation header
``00 01 00 00`` (CDR, little endian) followed by the CDR payload.
"""

from __future__ import annotations

from typing import Any

from ros2_compat._messages import MessageMeta

from rclpy.impl.implementation_singleton import RCLError
from ros2_compat import _cdr

__all__ = ['deserialize_message', 'serialize_message']


class NotAMessageTypeError(AttributeError, TypeError):
    """The object is not a ROS 2 message (rclpy raises AttributeError; TypeError says it too)."""


def _check_for_type_support(message_type: type) -> None:
    """Raise as rclpy.type_support.check_for_type_support does for a non-message type."""
    if not isinstance(message_type, MessageMeta):
        msg = (
            f"type object '{message_type.__name__}' has no attribute '_TYPE_SUPPORT'"
            ' This might be a ROS 1 message type but it should be a ROS 2 message type.'
            ' Make sure to source your ROS 2 workspace after your ROS 1 workspace.'
        )
        raise NotAMessageTypeError(msg)


def serialize_message(message: Any) -> bytes:
    """Serialize a ROS message.

    Args:
        message: The ROS message to serialize.

    Returns:
        The serialized bytes (CDR with its 4-byte encapsulation header).

    Raises:
        NotAMessageTypeError: message is not a ROS message (an AttributeError, as in rclpy,
            and a TypeError).
        ros2_compat._cdr.CdrError: A field holds a value its type cannot take.
    """
    message_type = type(message)
    _check_for_type_support(message_type)
    return _cdr.serialize(message)


def deserialize_message(serialized_message: bytes, message_type: type) -> Any:
    """Deserialize a ROS message.

    Args:
        serialized_message: The serialized bytes (CDR with its encapsulation header).
        message_type: The class of the serialized message.

    Returns:
        A new message of message_type.

    Raises:
        NotAMessageTypeError: message_type is not a ROS message class.
        RCLError: The bytes are not a valid serialization of message_type.
    """
    _check_for_type_support(message_type)
    try:
        return _cdr.deserialize(serialized_message, message_type)
    except _cdr.CdrError as exc:
        msg = f'failed to deserialize ROS message: {exc}'
        raise RCLError(msg) from exc
