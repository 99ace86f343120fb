"""declare_autostart, autostart and guard_change_state on a minimal rclpy LifecycleNode."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
import rclpy
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState
from rclpy.context import Context
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.node import Node
from rclpy.parameter import Parameter
from uvms_common.lifecycle import autostart, declare_autostart, guard_change_state, state_label
from uvms_common.node_main import make_executor


class Managed(LifecycleNode):
    """Succeeds in every transition unless told to fail configure."""

    def __init__(self, context: Context, fail_configure: bool = False, **overrides: bool) -> None:
        super().__init__('managed', context=context, parameter_overrides=[
            Parameter(k, value=v) for k, v in overrides.items()])
        self.fail_configure = fail_configure
        guard_change_state(self)
        self.started = declare_autostart(self) and autostart(self)

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """FAILURE when told so."""
        if self.fail_configure:
            return TransitionCallbackReturn.FAILURE
        return TransitionCallbackReturn.SUCCESS


@pytest.fixture
def context() -> Iterator[Context]:
    """An initialised rclpy context."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def test_autostart_by_default_activates(context: Context) -> None:
    """The default brings the node to active."""
    node = Managed(context)
    assert node.started and state_label(node) == 'active'
    assert node.get_parameter('autostart').value is True
    node.destroy_node()


def test_autostart_false_leaves_it_unconfigured(context: Context) -> None:
    """-p autostart:=false: unconfigured, for a lifecycle manager."""
    node = Managed(context, autostart=False)
    assert not node.started and state_label(node) == 'unconfigured'
    node.destroy_node()


def test_a_failed_configure_is_logged_and_returns_false(
    context: Context, capfd: pytest.CaptureFixture[str]
) -> None:
    """The transition and the state it left the node in are named."""
    node = Managed(context, fail_configure=True)
    assert not node.started and state_label(node) == 'unconfigured'
    assert 'autostart: configure returned transition_failure; the node is unconfigured' in (
        capfd.readouterr().err)
    node.destroy_node()


def test_an_impossible_transition_request_is_refused_not_raised(context: Context) -> None:
    """change_state 'configure' on an active node: success false, the executor goes on."""
    node = Managed(context)
    client_node = Node('client', context=context)
    executor = make_executor('events', context)
    for n in (node, client_node):
        executor.add_node(n)
    client = client_node.create_client(ChangeState, '/managed/change_state')
    try:
        assert client.wait_for_service(timeout_sec=5.0)
        future = client.call_async(ChangeState.Request(
            transition=Transition(id=Transition.TRANSITION_CONFIGURE)))
        deadline = time.monotonic() + 5.0
        while not future.done() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)
        assert future.done() and future.result().success is False
        assert state_label(node) == 'active'
    finally:
        executor.shutdown()
        client_node.destroy_node()
        node.destroy_node()
