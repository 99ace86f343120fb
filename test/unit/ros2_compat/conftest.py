"""Fixtures shared by the rclpy compat tests: a fresh context and a node in it."""

from collections.abc import Iterator

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node


@pytest.fixture
def context() -> Iterator[Context]:
    """A context initialized without ROS arguments, shut down after the test."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    ctx.try_shutdown()


@pytest.fixture
def node(context: Context) -> Iterator[Node]:
    """A node in the root namespace."""
    n = Node('tester', context=context)
    yield n
    n.destroy_node()
