"""Stand-in for rclpy's C extension module: the error types it defines.

Real rclpy raises these from ``_rclpy_pybind11``; code that catches them reaches them as
``rclpy.impl.implementation_singleton.rclpy_implementation.RCLError`` and so on.
"""

from __future__ import annotations

from types import SimpleNamespace


class RCLError(RuntimeError):
    """An error reported by the ROS client library layer (rcl)."""


class UnknownROSArgsError(RCLError):
    """Raised when ``--ros-args`` holds an argument rcl does not know."""


class InvalidHandle(Exception):  # noqa: N818 (rclpy's name)
    """Raised when using an entity (node, publisher, ...) that was already destroyed."""


class NodeNameNonExistentError(RCLError):
    """Raised when a graph query names a node that does not exist."""


#: Namespace object shaped like rclpy's ``rclpy_implementation`` for the error types.
rclpy_implementation = SimpleNamespace(
    RCLError=RCLError,
    UnknownROSArgsError=UnknownROSArgsError,
    InvalidHandle=InvalidHandle,
    NodeNameNonExistentError=NodeNameNonExistentError,
)
