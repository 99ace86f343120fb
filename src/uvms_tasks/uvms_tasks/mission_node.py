"""The mission node: sends a mission's ContactTask goals to the controller, one after another.

It waits for the controller's action server and its first ``controller/state`` (whose
``desired_position``, the hold target X_d, is X0 of a half circle), sends the first goal,
and sends each next one when the previous result arrives, from the X_d then current. Each
result is logged in one line. The wait is bounded (parameter ``wait_timeout_s``, wall
clock from the node's start): past it the mission gives up with one error line naming what
it did not find (the action server by its full name, or a ``controller/state``) and ends
(``gave_up``; exit 1 as its own process, as a node that could not start).
``finished``/``results`` let an in-process graph runner stop when the mission is done.
Names are relative: run it in /uvms.

In process::

    node = MissionNode(tasks=load_task_file('mission.yaml'), namespace='uvms',
                       context=context)   # or parameter mission_file, read here
    executor.add_node(node)               # spin until node.finished; node.results

As its own process: ``ros2 run uvms_tasks mission --ros-args -r __ns:=/uvms
-p mission_file:=mission.yaml`` (exit 0 when every goal SUCCEEDED, 3 when one did not,
``uvms_tasks.mission_outcome.EXIT_MISSION_FAILED``; 1 when the node could not start, did
not find the controller within ``wait_timeout_s``, or crashed). With
``-p outcome_file:=F.json`` it writes how the mission ended there
(``uvms_tasks.mission_outcome``): ``uvms launch`` reads it to say what failed.
"""

from __future__ import annotations

import hashlib
import sys
import time
from collections.abc import Sequence
from typing import Any

from action_msgs.msg import GoalStatus
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rclpy.action.client import ClientGoalHandle
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from rclpy.subscription import Subscription
from rclpy.task import Future
from std_msgs.msg import Bool
from unique_identifier_msgs.msg import UUID
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.raw_clock import take_clock_raw

from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ControllerState
from uvms_tasks.client import DISCOVERY_SETTLE_S, STATE_TOPIC, ContactTaskClient
from uvms_tasks.errors import TaskError, TaskFileError
from uvms_tasks.goals import TaskOutcome, describe_task, goal_from_task
from uvms_tasks.mission_outcome import (
    EXIT_MISSION_FAILED,
    MISSION_READY_TOPIC,
    MissionOutcome,
    write_outcome,
)
from uvms_tasks.task_file import TaskSpec, load_task_file

#: Period of the wall-clock check for the action server until the first goal is sent (s).
DISCOVERY_POLL_S = 0.05
#: Default of parameter ``wait_timeout_s``: wall time from the node's start to find the
#: action server and the first controller/state (s). The controller's start-up (imports,
#: model, kernels) took over 10 s on a machine at load 14; found within 3 s beside 2 busy
#: loops (bench/bench_soak.py).
WAIT_TIMEOUT_S = 30.0


def mission_goal_uuid(index: int, name: str) -> UUID:
    """The goal id of a mission's task ``index`` named ``name``: the same in every run.

    rclpy draws a random id per goal; a mission's ids are derived from its tasks instead, so
    that a recording (``controller/task_record`` carries the id) stays byte-identical between
    runs of one scenario and seed. Distinct tasks of one mission get distinct ids.
    """
    digest = hashlib.sha256(f'uvms mission task {index}: {name}'.encode()).digest()
    return UUID(uuid=list(digest[:16]))

class MissionNode(Node):
    """Sends a mission through the controller's ContactTask action (node name ``mission``).

    Args:
        tasks: The mission, in order; None reads the file of parameter ``mission_file``.
        server_settle_s: Default of parameter ``server_settle_s``: wall time between seeing
            the action server and sending the first goal, for the server to discover this
            node in turn (``uvms_tasks.client.DISCOVERY_SETTLE_S``, what ``main`` uses for a
            process of its own). 0 (the default) in process: nodes of one context match at
            once, and a lockstep run then sends its goals at the same simulated time every run.
        **kwargs: Passed to ``rclpy.node.Node`` (namespace, context, cli_args,
            parameter_overrides, ...).

    Raises:
        TaskFileError: No tasks given, or the mission file is unreadable or invalid.
    """

    @destroyed_if_construction_fails
    def __init__(self, tasks: Sequence[TaskSpec] | None = None,
                 server_settle_s: float = 0.0, **kwargs: Any) -> None:
        super().__init__('mission', **kwargs)
        self._clock_source = take_clock_raw(self)  # /clock raw under use_sim_time
        mission_file = self.declare_parameter(
            'mission_file', '', ParameterDescriptor(
                description='Task or mission YAML file (uvms_tasks.task_file); ignored when '
                            'the tasks are given in process', read_only=True)).value
        self.continue_on_failure: bool = self.declare_parameter(
            'continue_on_failure', False, ParameterDescriptor(
                description='Send the next goal also after one that did not succeed',
                read_only=True)).value
        self.server_settle_s: float = self.declare_parameter(
            'server_settle_s', float(server_settle_s), ParameterDescriptor(
                description='Wall time between discovering the action server and sending the '
                            'first goal (s); 0 when the server is in the same process',
                read_only=True, floating_point_range=[
                    FloatingPointRange(from_value=0.0, to_value=10.0, step=0.0)])).value
        self.wait_timeout_s: float = self.declare_parameter(
            'wait_timeout_s', WAIT_TIMEOUT_S, ParameterDescriptor(
                description="Wall time from the node's start to wait for the controller's "
                            'action server and its first controller/state (s); past it the '
                            'mission gives up naming what it did not find', read_only=True,
                floating_point_range=[
                    FloatingPointRange(from_value=0.1, to_value=3600.0, step=0.0)])).value
        self.outcome_file: str = self.declare_parameter(
            'outcome_file', '', ParameterDescriptor(
                description='File to write the outcome of the mission to when it ends (JSON, '
                            'uvms_tasks.mission_outcome); empty: none', read_only=True)).value
        if tasks is None:
            if not mission_file:
                msg = 'mission: no tasks: set parameter mission_file to a task or mission file'
                raise TaskFileError(msg)
            tasks = load_task_file(mission_file)
        if not tasks:
            msg = 'mission: the mission holds no tasks'
            raise TaskFileError(msg)
        self.tasks: list[TaskSpec] = list(tasks)
        #: Outcome of each goal sent so far, in order.
        self.results: list[TaskOutcome] = []
        #: The goals as sent (half circles expanded from the X_d of that moment).
        self.sent_goals: list[ContactTask.Goal] = []
        self.last_feedback: ContactTask.Feedback | None = None
        self.finished = False
        #: What the mission gave up waiting for (the action server, controller/state), or ''.
        self.gave_up = ''
        self._state_seen = False
        self._target: tuple[float, float, float] | None = None
        self._busy = False
        self._server_seen_s: float | None = None
        self._created_s = time.monotonic()
        self._handle: ClientGoalHandle | None = None
        self.client = ContactTaskClient(self)
        # The state topic drives the mission: every control step is a chance to start. Taken
        # raw, and decoded only when a goal is to go out; unsubscribed while a goal runs (its
        # 500 messages per second cost a lockstep graph time for nothing).
        self._state_subscription: Subscription | None = None
        self._listen_to_state()
        self.get_logger().info(
            f'mission of {len(self.tasks)} task(s) for {self.client.action_name}; waiting for '
            'the action server and controller/state')
        # On the steady clock: discovery runs on wall time, also before /clock ticks.
        # Latched: a simulator that holds physics until the mission is ready (issue 48) reads
        # it whenever it subscribes.
        self._ready_publisher = self.create_publisher(Bool, MISSION_READY_TOPIC, QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self._discovery_timer = self.create_timer(
            DISCOVERY_POLL_S, self._watch_start, clock=Clock(clock_type=ClockType.STEADY_TIME))

    @property
    def succeeded(self) -> bool:
        """Whether every task of the mission ended SUCCEEDED."""
        return (self.finished and len(self.results) == len(self.tasks)
                and all(outcome.succeeded for outcome in self.results))

    def _listen_to_state(self) -> None:
        if self._state_subscription is None:
            self._state_subscription = self.create_subscription(
                ControllerState, 'controller/state', self._on_state, 1, raw=True)

    def _stop_listening_to_state(self) -> None:
        if self._state_subscription is not None:
            self.destroy_subscription(self._state_subscription)
            self._state_subscription = None

    def _on_state(self, data: bytes) -> None:
        if self._busy or self.finished or not self._server_settled():
            return
        self._state_seen = True  # the start's wait is over (a goal may still be held)
        state = deserialize_message(data, ControllerState)
        send_at_s = self.tasks[len(self.results)].send_at_s
        stamp = state.header.stamp
        if send_at_s is not None and stamp.sec + stamp.nanosec * 1e-9 < send_at_s:
            return  # held until the controller's clock reaches it (after a pilot session)
        p = state.desired_position
        self._target = (p.x, p.y, p.z)
        self._send_next()

    def _watch_start(self) -> None:
        """Look for the action server; give up past ``wait_timeout_s`` without it or a state.

        On the steady clock: discovery runs on wall time, also before /clock ticks.
        """
        if self._state_seen or self.finished:
            self.destroy_timer(self._discovery_timer)
            return
        self._server_settled()
        if time.monotonic() - self._created_s < self.wait_timeout_s:
            return
        self.destroy_timer(self._discovery_timer)
        self._stop_listening_to_state()
        self.gave_up = (f'action server {self.client.action_name}'
                        if self._server_seen_s is None else
                        f'{self.resolve_topic_name(STATE_TOPIC)} message')
        self.finished = True
        self.get_logger().error(
            f'mission not started: no {self.gave_up} within {self.wait_timeout_s:g} s of the '
            "node's start (wall clock, parameter wait_timeout_s): is the controller running "
            'in this namespace and ROS domain?')

    def _server_settled(self) -> bool:
        """The action server is discovered, and has had server_settle_s to discover us."""
        if not self.client.server_is_ready():
            return False
        # Discovery runs on wall time, whatever clock the node uses.
        now = time.monotonic()
        if self._server_seen_s is None:
            self._server_seen_s = now
            # One line that says when (bench/bench_soak.py reads the discovery time from it).
            self.get_logger().info(
                f'found the action server {self.client.action_name} '
                f'{now - self._created_s:.2f} s after the node started')
            self._ready_publisher.publish(Bool(data=True))
        return now - self._server_seen_s >= self.server_settle_s

    def _send_next(self) -> None:
        """Send the next task's goal, its half circle (if any) from the current X_d."""
        task = self.tasks[len(self.results)]
        try:
            goal = goal_from_task(task, self._target)
        except TaskError as exc:
            self._finish_task(TaskOutcome(task.name, GoalStatus.STATUS_ABORTED, rejected=True))
            self.get_logger().error(str(exc))
            return
        self._busy = True
        self.sent_goals.append(goal)
        self.get_logger().info(f'sending {describe_task(task)}')
        future = self.client.send_goal_async(goal, self._on_feedback,
                                             mission_goal_uuid(len(self.results), task.name))
        future.add_done_callback(self._on_goal_response)

    def _on_feedback(self, feedback: ContactTask.Feedback) -> None:
        self.last_feedback = feedback

    def _on_goal_response(self, future: Future) -> None:
        handle: ClientGoalHandle = future.result()
        # Not in _send_next: that runs inside the state callback, whose subscription this is.
        self._stop_listening_to_state()
        if not handle.accepted:
            self._finish_task(TaskOutcome(self._current_name(), int(handle.status),
                                          rejected=True))
            return
        self._handle = handle
        self.client.result_async(handle).add_done_callback(self._on_result)

    def _on_result(self, future: Future) -> None:
        response: Any = future.result()
        self._handle = None
        self._finish_task(TaskOutcome(self._current_name(), int(response.status),
                                      response.result))

    def _current_name(self) -> str:
        return self.tasks[len(self.results)].name

    def _finish_task(self, outcome: TaskOutcome) -> None:
        """Log and keep a goal's outcome; send the next goal or end the mission."""
        self.results.append(outcome)
        # rclpy refuses one call site logging at two severities: one line per severity.
        if outcome.succeeded:
            self.get_logger().info(outcome.describe())
        else:
            self.get_logger().error(outcome.describe())
        done = len(self.results) == len(self.tasks)
        if not done and (outcome.succeeded or self.continue_on_failure):
            self._busy = False  # the next state message sends it, from the X_d of then
            self._listen_to_state()
            return
        self._busy = False
        self.finished = True
        passed = sum(result.succeeded for result in self.results)
        summary = (f'mission {"done" if self.succeeded else "failed"}: {passed} of '
                   f'{len(self.tasks)} task(s) succeeded')
        if self.succeeded:
            self.get_logger().info(summary)
        else:
            self.get_logger().error(summary)
        if self.outcome_file:
            write_outcome(self.outcome_file, self.outcome())

    def outcome(self) -> MissionOutcome:
        """How the mission ended: succeeded, or the first failed task's code and message."""
        failed = next((result for result in self.results if not result.succeeded), None)
        if failed is None:
            return MissionOutcome(self.succeeded)
        return MissionOutcome(False, failed.name, failed.code, failed.message)

    def destroy_node(self) -> None:
        """Ask the controller to cancel a goal still running, then destroy the node."""
        if self._handle is not None:
            self.get_logger().warning(f'stopping: canceling {self._current_name()}')
            self.client.cancel_async(self._handle)
            self._handle = None
        self.client.destroy()
        super().destroy_node()



def main(args: list[str] | None = None) -> None:
    """Run the mission node until its mission ends or SIGINT/SIGTERM."""
    nodes: list[MissionNode] = []

    def make_node() -> MissionNode:
        nodes.append(MissionNode(server_settle_s=DISCOVERY_SETTLE_S))
        return nodes[-1]

    status = run_node(make_node, args, 'mission', (TaskError, ParameterException),
                      finished=lambda node: getattr(node, 'finished', False))
    if status == 0 and nodes and nodes[0].gave_up:
        status = 1  # the mission never started: as a node that could not start
    elif status == 0 and nodes and nodes[0].finished and not nodes[0].succeeded:
        status = EXIT_MISSION_FAILED
    sys.exit(status)


if __name__ == '__main__':
    main()
