"""The foxglove_server node on its own: where it binds, and what it says when it cannot."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import rclpy
from rclpy.context import Context
from rclpy.parameter import Parameter
from uvms_viz.foxglove_server_node import FoxgloveServerError, FoxgloveServerNode


@pytest.fixture
def context() -> Iterator[Context]:
    """An rclpy context of its own."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def node(context: Context, **parameters: object) -> FoxgloveServerNode:
    """The node in /uvms with parameter overrides."""
    return FoxgloveServerNode(namespace='uvms', context=context, parameter_overrides=[
        Parameter(name, value=value) for name, value in parameters.items()])


def test_default_binds_loopback_on_a_free_port(context: Context) -> None:
    """By default (127.0.0.1) with port 0 the server listens on a port of its choosing."""
    server = node(context, port=0)
    try:
        assert server.port is not None and server.port > 0
    finally:
        server.destroy_node()


def test_a_wider_host_is_warned_and_an_unusable_one_leaves_the_node_idle(
        context: Context, capfd: pytest.CaptureFixture[str]) -> None:
    """A non-loopback host is warned; one it cannot bind (TEST-NET) is one error line."""
    server = node(context, host='192.0.2.1', port=0)
    try:
        assert server.port is None
    finally:
        server.destroy_node()
    err = capfd.readouterr().err
    assert 'reachable from other machines' in err
    assert err.count('no Foxglove live view: cannot serve ws://192.0.2.1:0') == 1


def test_an_unknown_topic_type_is_named(context: Context) -> None:
    """A topics entry of a type the typestore lacks stops the node, naming the entry."""
    with pytest.raises(FoxgloveServerError, match=r"parameter 'topics'.*nope"):
        node(context, port=0, topics=['x:nope_msgs/msg/Nothing'])
