"""Validation, expansion and remapping of ROS names (rcl/rmw name rules)."""

from __future__ import annotations

import re
from collections.abc import Iterable

from rclpy._arguments import RemapRule
from rclpy.exceptions import (
    InvalidNamespaceException,
    InvalidNodeNameException,
    InvalidServiceNameException,
    InvalidTopicNameException,
)

_NODE_NAME_MAX = 255
_TOKEN = re.compile(r'[A-Za-z0-9_]+')


def _node_name_error(name: str) -> tuple[str, int] | None:
    if not name:
        return 'node name must not be empty', 0
    for index, char in enumerate(name):
        if not (char.isascii() and (char.isalnum() or char == '_')):
            return "node name must not contain characters other than alphanumerics or '_'", index
    if name[0].isdigit():
        return 'node name must not start with a number', 0
    if len(name) > _NODE_NAME_MAX:
        return f'node name should not exceed {_NODE_NAME_MAX}', _NODE_NAME_MAX - 1
    return None


def validate_node_name(node_name: str) -> bool:
    """Check a node name; return True or raise InvalidNodeNameException."""
    error = _node_name_error(node_name)
    if error is not None:
        raise InvalidNodeNameException(node_name, *error)
    return True


def _absolute_name_error(name: str, what: str) -> tuple[str, int] | None:
    if not name:
        return f'{what} must not be empty', 0
    if not name.startswith('/'):
        return f"{what} must be absolute, it must lead with a '/'", 0
    if name == '/':
        return None
    if name.endswith('/'):
        return f"{what} must not end with a '/'", len(name) - 1
    for index, char in enumerate(name):
        if not (char == '/' or (char.isascii() and (char.isalnum() or char == '_'))):
            return f"{what} must not contain characters other than alphanumerics, '_', or " \
                "'/'", index
    if '//' in name:
        return f"{what} must not contain repeated '/'", name.index('//') + 1
    position = 1
    for token in name[1:].split('/'):
        if token[0].isdigit():
            return f'{what} must not have a token that starts with a number', position
        position += len(token) + 1
    return None


def validate_namespace(namespace: str) -> bool:
    """Check an absolute namespace; return True or raise InvalidNamespaceException."""
    error = _absolute_name_error(namespace, 'namespace')
    if error is not None:
        raise InvalidNamespaceException(namespace, *error)
    return True


def validate_full_topic_name(name: str, *, is_service: bool = False) -> bool:
    """Check a fully qualified topic name; return True or raise InvalidTopicNameException."""
    error = _absolute_name_error(name, 'service name' if is_service else 'topic name')
    if error is None and name == '/':
        error = ("topic name must not be just '/'", 0)
    if error is not None:
        if is_service:
            raise InvalidServiceNameException(name, *error)
        raise InvalidTopicNameException(name, *error)
    return True


def _topic_name_error(name: str) -> tuple[str, int] | None:
    if not name:
        return 'topic name must not be empty', 0
    if name.endswith('/'):
        return 'topic name must not end with a forward slash', len(name) - 1
    in_braces = False
    for index, char in enumerate(name):
        if char.isascii() and (char.isalnum() or char == '_'):
            continue
        if char == '/' or (char == '~' and index == 0):
            if in_braces and char == '/':
                return "topic name must not contain '/' in a substitution", index
            continue
        if char == '{' and not in_braces:
            in_braces = True
            continue
        if char == '}' and in_braces:
            in_braces = False
            continue
        if char == '~':
            return "'~' must only be the first character of a topic name", index
        return "topic name must not contain characters other than alphanumerics, '_', " \
            "'~', '{', or '}'", index
    if in_braces:
        return "topic name has an unmatched '{'", name.index('{')
    if name.startswith('~') and len(name) > 1 and name[1] != '/':
        return "'~' must be followed by '/'", 1
    if '//' in name:
        return "topic name must not contain repeated '/'", name.index('//') + 1
    position = 0
    for token in name.split('/'):
        if token and token[0].isdigit():
            return 'topic name must not have a token that starts with a number', position
        position += len(token) + 1
    return None


def validate_topic_name(name: str, *, is_service: bool = False) -> bool:
    """Check a (possibly relative) topic name; return True or raise InvalidTopicNameException."""
    error = _topic_name_error(name)
    if error is not None:
        if is_service:
            raise InvalidServiceNameException(name, *error)
        raise InvalidTopicNameException(name, *error)
    return True


def fully_qualified_node_name(node_name: str, namespace: str) -> str:
    """Join a namespace and a node name."""
    return f'/{node_name}' if namespace == '/' else f'{namespace}/{node_name}'


def expand_topic_name(topic_name: str, node_name: str, node_namespace: str) -> str:
    """Expand a relative or private (``~``) name to a fully qualified one, as rcl does.

    Raises:
        InvalidTopicNameException: If the name or the result is not a valid topic name.
    """
    validate_topic_name(topic_name)
    name = topic_name
    if name.startswith('~'):
        name = fully_qualified_node_name(node_name, node_namespace) + name[1:]
    name = name.replace('{node}', node_name)
    name = name.replace('{namespace}', node_namespace).replace('{ns}', node_namespace)
    if '{' in name:
        start = name.index('{')
        raise InvalidTopicNameException(topic_name, 'unknown substitution', start)
    if not name.startswith('/'):
        name = f'/{name}' if node_namespace == '/' else f'{node_namespace}/{name}'
    name = name.replace('//', '/')
    validate_full_topic_name(name)
    return name


def remap_name(
    rules: Iterable[RemapRule], kind: str, node_name: str, default: str
) -> str:
    """Apply the first node-name (``__node``) or namespace (``__ns``) rule that matches."""
    for rule in rules:
        if rule.kind == kind and rule.node_name in (None, node_name):
            return rule.replacement
    return default


def remap_topic_name(
    rules: Iterable[RemapRule], fq_topic: str, node_name: str, node_namespace: str
) -> str:
    """Apply the first topic remap rule whose expanded match equals ``fq_topic``."""
    for rule in rules:
        if rule.kind != 'topic' or rule.node_name not in (None, node_name):
            continue
        if expand_topic_name(rule.match, node_name, node_namespace) == fq_topic:
            return expand_topic_name(rule.replacement, node_name, node_namespace)
    return fq_topic
