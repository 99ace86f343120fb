"""In-process rclpy-compatible runtime and message classes for machines without ROS 2.

The packages under ``_overlay`` (``rclpy``, the message packages) are importable under their
ROS 2 names only through a fallback finder placed at the end of ``sys.meta_path``: every other
finder, and so any sourced ROS 2 install, is asked first. The real rclpy always wins.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

OVERLAY_DIR = Path(__file__).resolve().parent / '_overlay'

#: Packages whose message types ros2_compat provides (their whole `msg` namespace).
MESSAGE_PACKAGES = (
    'builtin_interfaces',
    'std_msgs',
    'geometry_msgs',
    'sensor_msgs',
    'nav_msgs',
    'rosgraph_msgs',
    'tf2_msgs',
    'rcl_interfaces',
    'uvms_msgs',
)

#: Top-level modules the compat runtime provides, under their ROS 2 names.
PROVIDED_PACKAGES = ('rclpy', *MESSAGE_PACKAGES)


class _FallbackFinder(importlib.abc.MetaPathFinder):
    """Finds the overlay packages, and is asked only after every other finder failed."""

    def find_spec(
        self,
        fullname: str,
        path: object = None,
        target: ModuleType | None = None,
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in PROVIDED_PACKAGES:
            return None
        return importlib.machinery.PathFinder.find_spec(fullname, [str(OVERLAY_DIR)])


def activate() -> None:
    """Append the fallback finder to ``sys.meta_path`` (idempotent)."""
    if not any(isinstance(finder, _FallbackFinder) for finder in sys.meta_path):
        sys.meta_path.append(_FallbackFinder())


def rclpy_is_compat() -> bool:
    """Tell whether ``import rclpy`` resolves to this compat runtime rather than a real ROS 2."""
    spec = importlib.util.find_spec('rclpy')
    if spec is None or spec.origin is None:
        return False
    return Path(spec.origin).resolve().is_relative_to(OVERLAY_DIR)
