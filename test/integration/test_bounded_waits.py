"""Waits that end and exits that cannot hang: the mission's wait and ``uvms task``'s end.

Issue 48: whoever waits for an action server or a node waits with a bound and says what it
waited for; a process whose work is done leaves without a DDS teardown that can hang (a
mission whose task SUCCEEDED ended with ``Timeout (0:00:02)!`` and a stack in rclpy's
``ActionClient.destroy``).
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import rclpy
import yaml
from rclpy.action import ActionServer
from rclpy.action.server import ServerGoalHandle
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from uvms_common.node_main import make_executor
from uvms_tasks.mission_node import MissionNode
from uvms_tasks.task_file import parse_mission

from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ControllerState

TASK = {'name': 'approach', 'path': [[1.6, 0, 0.2], [1.65, 0, 0.2]], 'time_from_start_s': [0, 1],
        'normal': [1, 0, 0]}


class _Spun:
    """A context and an executor spinning its nodes in a thread."""

    def __init__(self) -> None:
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor = make_executor('events', context=self.context)
        self.nodes: list[Node] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin)
        self._thread.start()

    def add(self, node: Node) -> None:
        """Spin a node."""
        self.executor.add_node(node)
        self.nodes.append(node)

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.01)

    def close(self) -> None:
        """Stop spinning, destroy the nodes, shut the context down."""
        self._stop.set()
        self._thread.join()
        for node in reversed(self.nodes):
            self.executor.remove_node(node)
            node.destroy_node()
        self.executor.shutdown()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def spun() -> Iterator[_Spun]:
    """A fresh in-process graph, spun in the background."""
    graph = _Spun()
    yield graph
    graph.close()


def _server(context: Context, *, state: bool) -> Node:
    """A controller stand-in: the ContactTask action server; controller/state if ``state``."""
    node = Node('controller', namespace='uvms', context=context)

    def execute(handle: ServerGoalHandle) -> ContactTask.Result:
        handle.succeed()
        return ContactTask.Result(error_code=ContactTask.Result.SUCCEEDED)

    node.server = ActionServer(  # type: ignore[attr-defined]
        node, ContactTask, 'controller/contact_task', execute_callback=execute)
    if state:
        publisher = node.create_publisher(ControllerState, 'controller/state', 10)
        node.create_timer(0.01, lambda: publisher.publish(ControllerState()))
    return node


def _mission(context: Context, wait_timeout_s: float) -> MissionNode:
    return MissionNode(tasks=parse_mission([TASK], 'mission.yaml'), namespace='uvms',
                       context=context, parameter_overrides=[
                           Parameter('wait_timeout_s', value=wait_timeout_s)])


def _wait(done: object, timeout_s: float) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if done():  # type: ignore[operator]
            return True
        time.sleep(0.02)
    return bool(done())  # type: ignore[operator]


def test_a_mission_without_a_controller_gives_up_naming_the_action_server(
        spun: _Spun) -> None:
    """Before, it waited for ever ('waiting for the action server and controller/state')."""
    started = time.monotonic()  # the bound counts from the node's creation
    mission = _mission(spun.context, 0.5)
    spun.add(mission)
    assert _wait(lambda: mission.finished, 10.0), 'the mission still waits'
    assert 0.5 <= time.monotonic() - started < 5.0
    assert mission.gave_up == 'action server /uvms/controller/contact_task'
    assert not mission.succeeded and not mission.sent_goals


def test_a_mission_whose_controller_sends_no_state_gives_up_naming_the_topic(
        spun: _Spun) -> None:
    """The server is there, the state never comes: the topic is named, no goal sent."""
    spun.add(_server(spun.context, state=False))
    mission = _mission(spun.context, 1.0)
    spun.add(mission)
    assert _wait(lambda: mission.finished, 10.0), 'the mission still waits'
    assert mission.gave_up == '/uvms/controller/state message'
    assert not mission.sent_goals


def test_a_mission_that_finds_its_controller_does_not_give_up(spun: _Spun) -> None:
    """The bound ends the wait for the start only: a goal that runs past it is followed."""
    spun.add(_server(spun.context, state=True))
    mission = _mission(spun.context, 0.5)
    spun.add(mission)
    assert _wait(lambda: mission.finished, 10.0)
    assert mission.succeeded and mission.gave_up == ''


def _env() -> dict[str, str]:
    return dict(os.environ, PYTHONUNBUFFERED='1')


def test_a_mission_process_without_a_controller_exits_1_naming_what_it_waited_for(
        tmp_path: Path) -> None:
    """As its own process (uvms launch's mission): one error line and status 1, in time."""
    mission_file = tmp_path / 'mission.yaml'
    mission_file.write_text(yaml.safe_dump({'mission': [TASK]}))
    command = [sys.executable, '-c', 'from uvms_common.node_entry import run_node_module; '
               "run_node_module('uvms_tasks.mission_node')", '--ros-args', '-r', '__ns:=/nobody',
               '-p', f'mission_file:={mission_file}', '-p', 'wait_timeout_s:=1.0']
    started = time.monotonic()
    result = subprocess.run(command, env=_env(), capture_output=True, text=True, timeout=60,
                            check=False)
    assert result.returncode == 1, result.stderr
    assert time.monotonic() - started < 30.0
    assert 'no action server /nobody/controller/contact_task within 1 s' in result.stderr, (
        result.stderr)
    assert 'Traceback' not in result.stderr


#: ``uvms task`` as its own process with rclpy's ActionClient.destroy made to hang, as the
#: DDS teardown was seen to.
_TASK_WITH_A_HANGING_TEARDOWN = textwrap.dedent("""
    import sys, time
    import rclpy.action.client
    rclpy.action.client.ActionClient.destroy = lambda self: time.sleep(3600)
    import runpy
    sys.argv = ['uvms_tasks.cli', *sys.argv[1:]]
    runpy.run_module('uvms_tasks.cli', run_name='__main__')
""")


def test_uvms_task_exits_with_its_status_although_the_dds_teardown_would_hang(
        tmp_path: Path) -> None:
    """Before, the process stayed in ActionClient.destroy after printing its result."""
    task_file = tmp_path / 'mission.yaml'
    task_file.write_text(yaml.safe_dump({'mission': [TASK]}))
    graph = _Spun()
    try:
        graph.add(_server(graph.context, state=True))
        started = time.monotonic()
        result = subprocess.run(
            [sys.executable, '-c', _TASK_WITH_A_HANGING_TEARDOWN, str(task_file),
             '--timeout', '20'], env=_env(), capture_output=True, text=True, timeout=30,
            check=False)
    except subprocess.TimeoutExpired as exc:
        pytest.fail(f'uvms task did not exit: {exc.stderr!r}')
    finally:
        graph.close()
    assert result.returncode == 0, result.stderr
    assert 'approach: SUCCEEDED' in result.stdout
    assert time.monotonic() - started < 30.0


#: The mission as ``uvms launch`` starts it, with rclpy's ActionClient.destroy made to hang.
_MISSION_WITH_A_HANGING_TEARDOWN = textwrap.dedent("""
    import time
    import rclpy.action.client
    rclpy.action.client.ActionClient.destroy = lambda self: time.sleep(3600)
    from uvms_common.node_entry import run_node_module
    run_node_module('uvms_tasks.mission_node')
""")


def test_a_mission_whose_task_succeeded_exits_0_although_the_dds_teardown_would_hang(
        tmp_path: Path) -> None:
    """Issue 48: ``Timeout (0:00:02)!`` in ``ActionClient.destroy`` and exit 1 after SUCCEEDED.

    The mission process leaves without the middleware's teardown: 0, at once, no stack.
    """
    mission_file = tmp_path / 'mission.yaml'
    mission_file.write_text(yaml.safe_dump({'mission': [TASK]}))
    graph = _Spun()
    try:
        graph.add(_server(graph.context, state=True))
        started = time.monotonic()
        result = subprocess.run(
            [sys.executable, '-c', _MISSION_WITH_A_HANGING_TEARDOWN, '--ros-args', '-r',
             '__ns:=/uvms', '-p', f'mission_file:={mission_file}'], env=_env(),
            capture_output=True, text=True, timeout=60, check=False)
    finally:
        graph.close()
    assert result.returncode == 0, result.stderr
    assert 'mission done: 1 of 1 task(s) succeeded' in result.stderr
    assert 'Timeout' not in result.stderr and 'Traceback' not in result.stderr, result.stderr
    assert time.monotonic() - started < 30.0
