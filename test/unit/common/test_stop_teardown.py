"""A node process's stop runs the node's own end and leaves the middleware's teardown out.

Issue 48: a mission whose task SUCCEEDED ended with ``Timeout (0:00:02)!`` and a stack in
rclpy's ``ActionClient.destroy`` (the DDS teardown blocked holding the GIL; faulthandler's
backstop exited 1). In a node process (``uvms_common.node_entry``) the process's end frees
what the teardown would; the node's own end (its ``destroy_node`` override) still runs.
"""

from __future__ import annotations

import time

import pytest
import rclpy
from rclpy.action import ActionClient
from rclpy.node import Node
from std_msgs.msg import String
from uvms_common.node_main import middleware_teardown_skipped, run_node

from uvms_common import node_entry


class _Node(Node):
    def __init__(self) -> None:
        super().__init__('stop_teardown_test')
        self.publisher = self.create_publisher(String, 'stop_teardown_test', 10)
        self.ends: list[str] = []

    def destroy_node(self) -> None:
        self.ends.append('own end')
        super().destroy_node()


def test_a_node_process_runs_the_nodes_own_end_but_not_the_middleware_teardown(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Goals cancelled, devices put back (the override) run; the publisher is not destroyed."""
    monkeypatch.setattr(node_entry, '_process_ends_after_main', True)
    nodes: list[_Node] = []

    def make() -> _Node:
        nodes.append(_Node())
        return nodes[-1]

    original = Node.destroy_node
    started = time.monotonic()
    status = run_node(make, [], 'stop_teardown_test', finished=lambda node: True)
    try:
        assert status == 0
        assert nodes[0].ends == ['own end']
        assert list(nodes[0].publishers), 'the middleware teardown ran (publisher destroyed)'
        assert Node.destroy_node is original
        assert time.monotonic() - started < 5.0
    finally:
        original(nodes[0])
        rclpy.try_shutdown()


def test_outside_a_node_process_the_teardown_runs_as_before() -> None:
    """run_node called in a process that goes on (a test, a tool) still tears down."""
    nodes: list[_Node] = []

    def make() -> _Node:
        nodes.append(_Node())
        return nodes[-1]

    assert run_node(make, [], 'stop_teardown_test', finished=lambda node: True) == 0
    assert nodes[0].ends == ['own end']
    assert not list(nodes[0].publishers)
    assert not rclpy.ok()


def test_a_hanging_action_client_destroy_is_not_called_when_skipped(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The CI stack's call: made a no-op within the block, restored after it."""
    def hang(self: ActionClient) -> None:
        time.sleep(30)

    monkeypatch.setattr(ActionClient, 'destroy', hang)
    started = time.monotonic()
    with middleware_teardown_skipped():
        ActionClient.destroy(object())  # type: ignore[arg-type]
    assert time.monotonic() - started < 1.0
    assert ActionClient.destroy is hang


_STOP_WITHOUT_ACTIONS = """
import sys
from rclpy.node import Node
from uvms_common import node_entry
from uvms_common.node_main import run_node

node_entry.mark_process_ends_after_main()
status = run_node(lambda: Node('no_actions'), [], 'no_actions', finished=lambda node: True)
print(status, 'rclpy.action.server' in sys.modules, 'rclpy.action.client' in sys.modules)
"""


def test_a_node_process_without_actions_imports_none_at_its_stop() -> None:
    """Skipping the teardown imports no rclpy.action (over 1 s at its stop under load)."""
    import subprocess
    import sys

    result = subprocess.run([sys.executable, '-c', _STOP_WITHOUT_ACTIONS], capture_output=True,
                            text=True, timeout=120, check=False)
    assert result.stdout.split() == ['0', 'False', 'False'], result.stdout + result.stderr
