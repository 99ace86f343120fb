"""Module-level helpers of rclpy: the default context, ok/shutdown, ROS argument removal."""

from __future__ import annotations

import sys
import threading
from collections.abc import Sequence

from rclpy.constants import S_TO_NS
from rclpy.context import Context

_default_context: Context | None = None
_context_lock = threading.RLock()


def get_default_context(*, shutting_down: bool = False) -> Context:
    """Return the global default context (a new one after the previous was shut down).

    Args:
        shutting_down: Return the current default context and forget it, so the next call
            creates a fresh one (what ``rclpy.shutdown()`` does).
    """
    global _default_context
    with _context_lock:
        if _default_context is None:
            _default_context = Context()
        context = _default_context
        if shutting_down:
            _default_context = None
        return context


def remove_ros_args(args: Sequence[str] | None = None) -> list[str]:
    """Return only the non-ROS arguments of ``args`` (``sys.argv`` if None).

    Raises:
        UnknownROSArgsError: If a ``--ros-args`` section holds unknown flags.
        RCLError: If the ROS arguments are malformed.
    """
    from rclpy._arguments import remove_ros_args as _remove

    return _remove(sys.argv if args is None else args)


def ok(*, context: Context | None = None) -> bool:
    """Tell whether a context (the default one if None) is initialized and not shut down."""
    if context is None:
        context = get_default_context()
    return context.ok()


def shutdown(*, context: Context | None = None) -> None:
    """Shut a context down (the default one if None; the next default context is fresh)."""
    if context is None:
        context = get_default_context(shutting_down=True)
    context.shutdown()


def try_shutdown(*, context: Context | None = None) -> None:
    """Shut a context down if not already shut down (the default one if None)."""
    global _default_context
    if context is None:
        with _context_lock:
            if _default_context is None:
                _default_context = Context()
            _default_context.try_shutdown()
            if not _default_context.ok():
                _default_context = None
    else:
        context.try_shutdown()


def get_rmw_implementation_identifier() -> str:
    """Return the middleware identifier (the in-process runtime has its own)."""
    return 'rmw_ros2_compat_inprocess'


def timeout_sec_to_nsec(timeout_sec: float | None) -> int:
    """Convert a timeout in seconds (None or negative: forever) to nanoseconds (-1: forever)."""
    if timeout_sec is None or timeout_sec < 0:
        return -1
    return int(float(timeout_sec) * S_TO_NS)
