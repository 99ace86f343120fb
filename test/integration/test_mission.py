"""Missions and scripts against a fake ContactTask server: order, X0, stamps, cancel, exits."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
import rclpy
import yaml
from action_msgs.msg import GoalStatus
from rclpy.action import ActionServer, CancelResponse
from rclpy.action.server import ServerGoalHandle
from rclpy.context import Context
from rclpy.node import Node
from uvms_common.node_main import make_executor
from uvms_common.stop_event import StopEvent
from uvms_control.core.law.reference import HalfCircleReference
from uvms_tasks.client import ContactTaskClient
from uvms_tasks.goals import goal_from_task, goal_waypoints
from uvms_tasks.mission_node import MissionNode, mission_goal_uuid
from uvms_tasks.task_file import parse_mission

from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ControllerState
from uvms_tasks import cli

HOLD = (1.6, 0.0, 0.2)
MISSION = [
    {'name': 'approach', 'path': [[1.6, 0, 0.2], [1.65, 0, 0.2]], 'time_from_start_s': [0, 1],
     'normal': [1, 0, 0], 'start_time_s': 1.5},
    {'name': 'press', 'half_circle': {'duration_s': 20, 'points': 41}, 'normal': [1, 0, 0],
     'force_n': 150},
    {'name': 'leave', 'path': [[1.65, 0, 0.4], [1.5, 0, 0.4]], 'time_from_start_s': [0, 2],
     'normal': [1, 0, 0]},
]


class FakeController:
    """Stand-in of the controller's action server, on a timer as the control loop would be.

    It accepts every goal, keeps it ACCEPTED while it "runs" (``ticks`` feedback messages), then
    holds X_d at the path's end for a few more states and ends the goal with the code scripted
    for it (SUCCEEDED by default), or CANCELED once a cancel is requested; rclpy's execute is
    deferred to that end, as the real server does. ``ticks=None`` runs until canceled.
    """

    def __init__(self, context: Context, codes: dict[int, int] | None = None,
                 ticks: int | None = 3) -> None:
        self.node = Node('controller', namespace='uvms', context=context)
        self.server = ActionServer(
            self.node, ContactTask, 'controller/contact_task', execute_callback=self._execute,
            handle_accepted_callback=self._accepted,
            cancel_callback=lambda _: CancelResponse.ACCEPT)
        self.state = self.node.create_publisher(ControllerState, 'controller/state', 10)
        self.codes = codes or {}
        self.ticks = ticks
        self.goals: list[ContactTask.Goal] = []
        self.goal_ids: list[bytes] = []
        self.cancel_requests = 0
        #: Called when a goal is accepted (a test's Ctrl-C).
        self.on_accept: Callable[[], None] | None = None
        self.x_d = HOLD
        self._active: ServerGoalHandle | None = None
        self._count = 0
        self.node.create_timer(0.01, self._tick)

    def _accepted(self, handle: ServerGoalHandle) -> None:
        self.goals.append(handle.request)
        self.goal_ids.append(bytes(handle.goal_id.uuid))
        self._active, self._count = handle, 0
        if self.on_accept is not None:
            self.on_accept()

    def _tick(self) -> None:
        state = ControllerState()
        state.desired_position.x, state.desired_position.y, state.desired_position.z = self.x_d
        self.state.publish(state)
        handle = self._active
        if handle is None:
            return
        self._count += 1
        if handle.is_cancel_requested:
            self.cancel_requests += 1
            self._end(handle)
        elif self.ticks is None or self._count <= self.ticks:
            handle.publish_feedback(ContactTask.Feedback(
                state=ContactTask.Feedback.STATE_FOLLOWING, weight=1.0, progress=0.5))
        else:
            # The path has ended: X_d holds its last waypoint for a few steps before the result.
            end = handle.request.path[-1]
            self.x_d = (end.x, end.y, end.z)
            if self._count > self.ticks + 3:
                self._end(handle)

    def _end(self, handle: ServerGoalHandle) -> None:
        self._active = None
        handle.execute()

    def _execute(self, handle: ServerGoalHandle) -> ContactTask.Result:
        index = self.goals.index(handle.request)
        code = self.codes.get(index, ContactTask.Result.SUCCEEDED)
        if handle.is_cancel_requested:
            handle.canceled()
            code = ContactTask.Result.CANCELED
        elif code == ContactTask.Result.SUCCEEDED:
            handle.succeed()
        else:
            handle.abort()
        return ContactTask.Result(error_code=code, contact_time_s=1.0, peak_force_n=150.0,
                                  rms_force_error_n=0.5, settling_time_s=0.3)


class Graph:
    """A context with an EventsExecutor (make_executor) spinning the nodes of one test."""

    def __init__(self) -> None:
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor = make_executor('events', context=self.context)
        self.nodes: list[Node] = []

    def add(self, node: Node) -> None:
        """Spin a node."""
        self.executor.add_node(node)
        self.nodes.append(node)

    def spin_until(self, done: Callable[[], bool], timeout_s: float = 10.0) -> bool:
        """Spin until done() or the wall-clock timeout."""
        deadline = time.monotonic() + timeout_s
        while not done() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)
        return done()

    def close(self) -> None:
        """Destroy the nodes and shut the context down."""
        for node in reversed(self.nodes):
            self.executor.remove_node(node)
            node.destroy_node()
        self.executor.shutdown()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def graph() -> Iterator[Graph]:
    """A fresh in-process graph."""
    g = Graph()
    yield g
    g.close()


def test_mission_sends_goals_in_order_from_the_current_hold_target(graph: Graph) -> None:
    """Goal k+1 goes out after result k; the half circle starts at the X_d held then."""
    fake = FakeController(graph.context)
    graph.add(fake.node)
    tasks = parse_mission(MISSION, 'mission.yaml')
    mission = MissionNode(tasks=tasks, namespace='uvms', context=graph.context)
    graph.add(mission)
    assert graph.spin_until(lambda: mission.finished)
    assert mission.succeeded
    assert [outcome.name for outcome in mission.results] == ['approach', 'press', 'leave']
    assert len(fake.goals) == 3
    first, circle, last = fake.goals
    np.testing.assert_array_equal(goal_waypoints(first), MISSION[0]['path'])
    assert (first.header.stamp.sec, first.header.stamp.nanosec) == (1, 500_000_000)
    assert (circle.header.stamp.sec, circle.header.stamp.nanosec) == (0, 0)
    assert {goal.header.frame_id for goal in fake.goals} == {'map_ned'}
    # X0 of the half circle: the end of the first path, where the controller held X_d.
    x0 = np.array([1.65, 0.0, 0.2])
    reference = HalfCircleReference(radius=0.1, duration=20.0, start_delay=0.0)
    expected = np.array([reference.evaluate(t, x0)[0] for t in np.linspace(0, 20, 41)])
    np.testing.assert_allclose(goal_waypoints(circle), expected, atol=1e-12)
    assert len(circle.velocity) == len(circle.acceleration) == 41
    np.testing.assert_array_equal(goal_waypoints(last), MISSION[2]['path'])
    assert mission.last_feedback is not None


def test_mission_goal_ids_are_the_same_in_every_run(graph: Graph) -> None:
    """The goal ids come from the tasks, not from chance: a recording repeats byte for byte.

    Before, rclpy drew a random UUID per goal, and controller/task_record (which carries it)
    differed between two runs of one scenario and seed.
    """
    fake = FakeController(graph.context)
    graph.add(fake.node)
    tasks = parse_mission(MISSION, 'mission.yaml')
    mission = MissionNode(tasks=tasks, namespace='uvms', context=graph.context)
    graph.add(mission)
    assert graph.spin_until(lambda: mission.finished)
    expected = [bytes(mission_goal_uuid(k, task.name).uuid) for k, task in enumerate(tasks)]
    assert fake.goal_ids == expected
    assert len(set(expected)) == len(tasks)


def test_mission_stops_after_a_goal_that_fails(graph: Graph) -> None:
    """An ABORTED goal ends the mission: the next one is not sent."""
    fake = FakeController(graph.context, codes={1: ContactTask.Result.FORCE_LIMIT})
    graph.add(fake.node)
    mission = MissionNode(tasks=parse_mission(MISSION, 'mission.yaml'), server_settle_s=0.5,
                          namespace='uvms', context=graph.context)
    graph.add(mission)
    assert graph.spin_until(lambda: mission.finished)
    assert not mission.succeeded and len(fake.goals) == 2
    assert [outcome.status for outcome in mission.results] == [
        GoalStatus.STATUS_SUCCEEDED, GoalStatus.STATUS_ABORTED]
    assert 'FORCE_LIMIT' in mission.results[1].describe()


def test_mission_file_parameter_is_read(graph: Graph, tmp_path: Path) -> None:
    """Without tasks in process, parameter mission_file names the file."""
    path = tmp_path / 'mission.yaml'
    path.write_text(yaml.safe_dump({'mission': MISSION[:1]}))
    fake = FakeController(graph.context)
    graph.add(fake.node)
    mission = MissionNode(namespace='uvms', context=graph.context,
                          parameter_overrides=[rclpy.parameter.Parameter('mission_file',
                                                                         value=str(path))])
    graph.add(mission)
    assert graph.spin_until(lambda: mission.finished) and mission.succeeded


def test_script_client_runs_and_cancels_goals(graph: Graph) -> None:
    """ContactTaskClient: X0 from the state, a goal to its result with feedback, a cancel."""
    fake = FakeController(graph.context)
    graph.add(fake.node)
    script = Node('script', namespace='uvms', context=graph.context)
    graph.add(script)
    client = ContactTaskClient(script, executor=graph.executor)
    assert client.action_name == '/uvms/controller/contact_task'
    assert client.wait_for_server(timeout_s=10.0)
    assert client.current_target(timeout_s=5.0) == HOLD
    tasks = parse_mission(MISSION, 'mission.yaml')
    feedback: list[ContactTask.Feedback] = []
    outcome = client.run(goal_from_task(tasks[0]), 'approach', feedback.append, timeout_s=10.0)
    assert outcome.succeeded and feedback
    fake.ticks = None
    handle = client.send_goal(goal_from_task(tasks[1], client.current_target(5.0)))
    assert handle.accepted
    assert client.cancel(handle)
    status, result = client.wait_for_result(handle, timeout_s=10.0)
    assert status == GoalStatus.STATUS_CANCELED and result.error_code == result.CANCELED
    client.destroy()


class BackgroundGraph:
    """The fake controller spun in a thread, for ``uvms task`` in the main thread."""

    def __init__(self, ticks: int | None = 3, codes: dict[int, int] | None = None) -> None:
        self.graph = Graph()
        self.fake = FakeController(self.graph.context, codes, ticks)
        self.graph.add(self.fake.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.graph.executor.spin_once(timeout_sec=0.01)

    def close(self) -> None:
        """Stop spinning and shut down."""
        self._stop.set()
        self._thread.join()
        self.graph.close()


def task_file(tmp_path: Path, tasks: list[dict[str, object]]) -> str:
    """A mission file of the tasks."""
    path = tmp_path / 'mission.yaml'
    path.write_text(yaml.safe_dump({'mission': tasks}))
    return str(path)


def test_uvms_task_prints_each_result_and_exits_0(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Every task SUCCEEDED: one result line each on stdout, exit 0."""
    background = BackgroundGraph()
    try:
        status = cli.main([task_file(tmp_path, MISSION[:2])])
    finally:
        background.close()
    out = capsys.readouterr().out.splitlines()
    assert status == 0
    assert [line.split(':')[0] for line in out] == ['approach', 'press']
    assert all('SUCCEEDED' in line for line in out)
    np.testing.assert_allclose(goal_waypoints(background.fake.goals[1])[0], [1.65, 0.0, 0.2])


def test_uvms_task_exits_1_when_a_goal_fails(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A FORCE_LIMIT result: printed, the rest not sent, exit 1."""
    background = BackgroundGraph(codes={0: ContactTask.Result.FORCE_LIMIT})
    try:
        status = cli.main([task_file(tmp_path, MISSION)])
    finally:
        background.close()
    assert status == 1 and len(background.fake.goals) == 1
    assert 'ABORTED (FORCE_LIMIT)' in capsys.readouterr().out


@pytest.mark.parametrize('delay_s', [0.0, 0.5], ids=['before-the-answer', 'while-running'])
def test_uvms_task_ctrl_c_cancels_the_running_goal(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], delay_s: float) -> None:
    """A stop signal once the goal is accepted: cancel request, CANCELED printed, exit 130."""
    background = BackgroundGraph(ticks=None)
    stop = StopEvent()
    background.fake.on_accept = lambda: threading.Timer(delay_s, stop.set).start()
    try:
        status = cli.main([task_file(tmp_path, MISSION[:1])])
    finally:
        stop.restore()
        background.close()
    assert status == 130 and background.fake.cancel_requests == 1
    assert 'approach: CANCELED' in capsys.readouterr().out


def test_uvms_task_bad_file_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A file that breaks the schema: one line naming file and key, exit 2, no ROS."""
    path = task_file(tmp_path, [{**MISSION[0], 'force_n': -1}])
    assert cli.main([path]) == 2
    assert capsys.readouterr().err.strip() == (
        f"uvms task: error: {path}: key 'mission[0].force_n': expected a finite number >= 0 "
        '(N), got int -1')


def test_uvms_task_without_a_server_exits_1(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """No controller on the graph: one line after the timeout, exit 1."""
    status = cli.main([task_file(tmp_path, MISSION[:1]), '--namespace', '/nobody',
                       '--timeout', '0.5'])
    assert status == 1
    assert 'no action server /nobody/controller/contact_task' in capsys.readouterr().err
