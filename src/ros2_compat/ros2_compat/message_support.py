"""Message helpers for tools (recorder, replay, plots): names, classes, copies, CDR, schemas.

Works with whichever message classes are active: the compat classes, or the real rosidl
classes of a sourced ROS 2 (then CDR goes through the real ``rclpy.serialization``). Node code
does not use this module: it uses ``rclpy.serialization`` and the message packages.

Importing this module does not activate the compat overlay; ``uvms_typestore()`` in particular
needs neither ROS 2 nor the overlay.
"""

from __future__ import annotations

import copy
import functools
import importlib
import importlib.util
import re
from typing import Any

from rosbags.typesys import TypesysError

from ros2_compat import MESSAGE_PACKAGES, PROVIDED_PACKAGES, _cdr, _messages, rclpy_is_compat
from ros2_compat._messages import MessageMeta
from ros2_compat._typestore import uvms_typestore

__all__ = [
    'MessageTypeError',
    'copy_message',
    'deserialize',
    'get_message_class',
    'is_message_class',
    'message_definition',
    'message_type_name',
    'normalize_type_name',
    'provided_message_types',
    'serialize',
    'type_hash',
    'uvms_typestore',
]

_TYPE_NAME = re.compile(r'^([A-Za-z][A-Za-z0-9_]*)/(?:(msg)/)?([A-Za-z][A-Za-z0-9_]*)$')


class MessageTypeError(LookupError):
    """A message type name is malformed or names no known message type."""


def normalize_type_name(name: str) -> str:
    """Return 'pkg/msg/Type' for 'pkg/msg/Type' or 'pkg/Type'.

    Raises:
        MessageTypeError: The name has neither form.
    """
    match = _TYPE_NAME.match(name)
    if match is None:
        msg = f"message type name {name!r} is not of the form 'pkg/msg/Type' or 'pkg/Type'"
        raise MessageTypeError(msg)
    return f'{match.group(1)}/msg/{match.group(3)}'


def is_message_class(obj: object) -> bool:
    """Tell whether obj is a ROS 2 message class (compat or rosidl-generated)."""
    if not isinstance(obj, type):
        return False
    if type(obj) is MessageMeta:
        return True
    return (
        hasattr(type(obj), '_TYPE_SUPPORT')
        and hasattr(obj, 'get_fields_and_field_types')
        and hasattr(obj, 'SLOT_TYPES')
        and len(obj.__module__.split('.')) >= 3
    )


def message_type_name(cls_or_msg: object) -> str:
    """Return the 'pkg/msg/Type' name of a message class or instance.

    Raises:
        TypeError: The object is neither a message class nor a message.
    """
    cls = cls_or_msg if isinstance(cls_or_msg, type) else type(cls_or_msg)
    if not is_message_class(cls):
        msg = f'{cls_or_msg!r} is not a ROS 2 message class or message'
        raise TypeError(msg)
    name = getattr(cls, '_TYPE_NAME', None)
    if isinstance(name, str):
        return name
    pkg, sub = cls.__module__.split('.')[:2]
    return f'{pkg}/{sub}/{cls.__name__}'


def _compat_is_the_runtime() -> bool:
    """Tell whether the compat message classes are the right ones (no real rclpy around)."""
    return rclpy_is_compat() or importlib.util.find_spec('rclpy') is None


def get_message_class(name: str) -> type:
    """Return the message class of 'pkg/msg/Type' or 'pkg/Type'.

    The class comes from ``import pkg.msg``: the real package under a sourced ROS 2, else the
    compat package (also when the overlay is not activated).

    Raises:
        MessageTypeError: The name is malformed or no such message type exists.
    """
    typename = normalize_type_name(name)
    pkg, sub, type_ = typename.split('/')
    try:
        module = importlib.import_module(f'{pkg}.{sub}')
    except ImportError:
        module = None
    if module is not None:
        cls = getattr(module, type_, None)
        if is_message_class(cls):
            assert isinstance(cls, type)
            return cls
    elif pkg in PROVIDED_PACKAGES and _compat_is_the_runtime():
        try:
            cls = _messages.get_class(typename)
        except KeyError:
            pass
        else:
            assert isinstance(cls, type)
            return cls
    msg = f'unknown message type {typename!r}'
    raise MessageTypeError(msg)


def copy_message(msg: Any) -> Any:
    """Return a deep copy of a message (generated fast path for compat messages)."""
    if type(type(msg)) is MessageMeta:
        try:
            return msg._fast_deepcopy(msg)
        except Exception:
            return _messages.fast_deepcopy(msg)
    return copy.deepcopy(msg)


def serialize(msg: Any) -> bytes:
    """Serialize a message to CDR bytes with the encapsulation header, as rclpy does.

    Raises:
        TypeError: msg is not a message.
        ros2_compat._cdr.CdrError: A field of a compat message holds a value its type
            cannot take.
    """
    if type(type(msg)) is MessageMeta:
        return _cdr.serialize(msg)
    if not is_message_class(type(msg)):
        text = f'{msg!r} is not a ROS 2 message'
        raise TypeError(text)
    from rclpy.serialization import serialize_message

    return serialize_message(msg)  # type: ignore[no-any-return]


def deserialize(data: bytes | bytearray | memoryview, cls: type) -> Any:
    """Build a message of class cls from CDR bytes with the encapsulation header.

    Raises:
        TypeError: cls is not a message class.
        ros2_compat._cdr.CdrError: The data does not encode a compat message of cls.
    """
    if type(cls) is MessageMeta:
        return _cdr.deserialize(data, cls)
    if not is_message_class(cls):
        text = f'{cls!r} is not a ROS 2 message class'
        raise TypeError(text)
    from rclpy.serialization import deserialize_message

    return deserialize_message(bytes(data), cls)


@functools.cache
def message_definition(name: str) -> str:
    """Return the ros2msg schema text of a type with its dependencies, as rosbag2 writes it.

    The type's own definition comes first, then each dependency after a line of 80 '='
    and a ``MSG: pkg/Type`` line (rosbags' ``generate_msgdef(..., ros_version=2)``).

    Raises:
        MessageTypeError: The type is unknown.
    """
    typename = normalize_type_name(name)
    store = uvms_typestore()
    if typename not in store.fielddefs:
        msg = f'unknown message type {typename!r}'
        raise MessageTypeError(msg)
    text, _ = store.generate_msgdef(typename, ros_version=2)
    return text


@functools.cache
def type_hash(name: str) -> str:
    """Return the RIHS01 type hash of a type ('RIHS01_' + 64 hex digits), as ROS 2 computes it.

    Raises:
        MessageTypeError: The type is unknown.
    """
    typename = normalize_type_name(name)
    store = uvms_typestore()
    if typename not in store.fielddefs:
        msg = f'unknown message type {typename!r}'
        raise MessageTypeError(msg)
    try:
        return store.hash_rihs01(typename)
    except (KeyError, TypesysError) as exc:
        msg = f'cannot hash message type {typename!r}: {exc}'
        raise MessageTypeError(msg) from exc


def provided_message_types() -> list[str]:
    """Return every 'pkg/msg/Type' the compat runtime provides, sorted."""
    store = uvms_typestore()
    return sorted(name for name in store.fielddefs if name.split('/', 1)[0] in MESSAGE_PACKAGES)
