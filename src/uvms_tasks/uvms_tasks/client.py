"""ContactTask client for scripts: send a goal to the controller, follow it, cancel it.

A thin wrapper of ``rclpy.action.ActionClient`` on a node the caller owns; the action name is
relative, so it resolves in the node's namespace (``/uvms/controller/contact_task`` for a node
in ``/uvms``). The ``*_async`` methods only start things and return futures, for a node that
spins on an executor anyway (``MissionNode``); the blocking ones spin the node themselves, on
the executor given or one of their own, in short turns.

Example (a script; ``uvms task`` does the same with a progress line and Ctrl-C)::

    import rclpy
    from rclpy.node import Node
    from uvms_tasks.client import ContactTaskClient
    from uvms_tasks.goals import describe_feedback, goal_from_task
    from uvms_tasks.task_file import load_task_file

    rclpy.init()
    node = Node('my_script', namespace='uvms')
    client = ContactTaskClient(node)
    if not client.wait_for_server(timeout_s=10.0):
        raise SystemExit('no controller')
    x0 = client.current_target(timeout_s=5.0)   # X_d of controller/state, for half circles
    for task in load_task_file('press.yaml'):
        outcome = client.run(goal_from_task(task, x0), name=task.name,
                             feedback_callback=lambda fb: print(describe_feedback(fb)))
        print(outcome.describe())
        x0 = client.current_target(timeout_s=5.0)
    client.destroy()
    node.destroy_node()
    rclpy.try_shutdown()
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from rcl_interfaces.msg import Log
from rclpy.action import ActionClient
from rclpy.action.client import ClientGoalHandle
from rclpy.callback_groups import CallbackGroup
from rclpy.executors import Executor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from rclpy.task import Future
from unique_identifier_msgs.msg import UUID
from uvms_common.node_main import make_executor

from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ControllerState
from uvms_tasks.errors import TaskClientError
from uvms_tasks.goals import TaskOutcome

#: The controller's action and state topic, relative to the node's namespace (/uvms).
ACTION_NAME = 'controller/contact_task'
STATE_TOPIC = 'controller/state'
#: Wall time to let discovery settle once the server is seen (s). The server's answer to a
#: goal is lost when the server has not yet matched this client's response reader:
#: rmw_fastrtps waits 100 ms for it, then drops the response (ros2/rmw_fastrtps#390, #467),
#: and a client that sends at once after discovery then waits for an answer forever. Nodes of
#: one context share a participant and match at once: no wait is needed there.
DISCOVERY_SETTLE_S = 0.5
#: Start of the controller's log line of a rejected goal (``uvms_control.task_server``'s
#: REJECTED_PREFIX, kept equal by a test): importing it took the controller's core and scipy
#: along, a second of every ``uvms task`` (issue 42).
REJECTED_PREFIX = 'contact task goal rejected: '
#: Longest single executor turn of the blocking methods (s): Ctrl-C is seen this fast.
SPIN_TURN_S = 0.1
#: Wall time to wait, after a rejection, for the controller's log line that says why (s).
REJECTION_WAIT_S = 2.0

FeedbackCallback = Callable[[ContactTask.Feedback], None]


class ContactTaskClient:
    """Client of the controller's ContactTask action on the caller's node.

    Args:
        node: The node to create the action client (and the state subscription) on.
        action_name: The action, relative to the node's namespace or absolute.
        state_topic: The controller's ControllerState topic, for ``current_target``.
        executor: What the blocking methods spin the node on; None: an executor of their own
            (``uvms_common.node_main.make_executor``), created at the first blocking call.
        callback_group: Of the action client and the subscription (None: the node's default).
    """

    def __init__(
        self,
        node: Node,
        action_name: str = ACTION_NAME,
        state_topic: str = STATE_TOPIC,
        executor: Executor | None = None,
        callback_group: CallbackGroup | None = None,
    ) -> None:
        self.node = node
        self._action_name = action_name
        self._action = ActionClient(node, ContactTask, action_name,
                                    callback_group=callback_group)
        # Taken raw and deserialized when read: the state comes every control period, read
        # once a goal (a deserialized ControllerState costs some 70 us of the loop's time).
        self._latest_state: bytes | None = None
        self._state_subscription = node.create_subscription(
            ControllerState, state_topic, self._on_state, QoSProfile(depth=1),
            callback_group=callback_group, raw=True)
        self._executor = executor
        self._own_executor = False
        self._rejections: list[tuple[float, str]] = []  # (monotonic s, reason)
        self._rosout: Any = None

    @property
    def action_name(self) -> str:
        """The action's fully resolved name."""
        return self.node.resolve_topic_name(self._action_name)

    def server_is_ready(self) -> bool:
        """Whether an action server is discovered (non-blocking)."""
        return bool(self._action.server_is_ready())

    @property
    def latest_state(self) -> ControllerState | None:
        """The last controller state received, or None."""
        data = self._latest_state
        return None if data is None else deserialize_message(data, ControllerState)

    @latest_state.setter
    def latest_state(self, state: None) -> None:
        self._latest_state = None

    def _on_state(self, data: bytes) -> None:
        self._latest_state = data

    def watch_rejections(self) -> None:
        """Listen on /rosout for the controller's lines on rejected goals (``rejection_reason``).

        A rejected goal gets no result message in ROS 2 actions; the controller logs why in
        one line (``uvms_control.task_server.REJECTED_PREFIX``), which this reads back.
        """
        if self._rosout is None:
            self._rosout = self.node.create_subscription(
                Log, '/rosout', self._on_log,
                QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))

    def _on_log(self, msg: Log) -> None:
        if msg.msg.startswith(REJECTED_PREFIX):
            self._rejections.append((time.monotonic(), msg.msg[len(REJECTED_PREFIX):]))

    def rejection_reason(self, since: float, timeout_s: float = REJECTION_WAIT_S) -> str | None:
        """Why the controller rejected a goal sent at ``since`` (time.monotonic(), s), or None.

        The first rejection line received after ``since`` (``watch_rejections`` must have been
        called before the goal was sent); None when none arrives within timeout_s. Another
        client's goal rejected at the same moment could be mistaken for this one.
        """
        def found() -> bool:
            return any(t >= since for t, _ in self._rejections)

        if self._rosout is None or not self.spin_until(found, timeout_s):
            return None
        return next(reason for t, reason in self._rejections if t >= since)

    # ------------------------------------------------------------------ non-blocking

    def send_goal_async(
        self, goal: ContactTask.Goal, feedback_callback: FeedbackCallback | None = None,
        goal_uuid: UUID | None = None,
    ) -> Future:
        """Send a goal; the future gives its ClientGoalHandle (``accepted`` tells).

        ``goal_uuid``: the goal id; None draws a random one (rclpy's default).
        """
        if feedback_callback is None:
            return self._action.send_goal_async(goal, goal_uuid=goal_uuid)
        return self._action.send_goal_async(
            goal, feedback_callback=lambda message: feedback_callback(message.feedback),
            goal_uuid=goal_uuid)

    @staticmethod
    def result_async(handle: ClientGoalHandle) -> Future:
        """The future of an accepted goal's result response (``.status``, ``.result``)."""
        return handle.get_result_async()

    @staticmethod
    def cancel_async(handle: ClientGoalHandle) -> Future:
        """Ask the server to cancel a goal; the future gives the CancelGoal response."""
        return handle.cancel_goal_async()

    # ------------------------------------------------------------------ blocking

    def spin_until(self, done: Callable[[], bool], timeout_s: float | None = None) -> bool:
        """Spin the node until ``done()`` or the timeout (wall clock, s); return ``done()``."""
        executor = self._blocking_executor()
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while not done() and self.node.context.ok():
            if deadline is not None and time.monotonic() >= deadline:
                break
            turn = SPIN_TURN_S if deadline is None else min(
                SPIN_TURN_S, max(0.0, deadline - time.monotonic()))
            executor.spin_once(timeout_sec=turn)
        return done()

    def wait_for_server(self, timeout_s: float | None = None,
                        settle_s: float = DISCOVERY_SETTLE_S) -> bool:
        """Wait until the action server is discovered, then ``settle_s``; False on timeout.

        Args:
            timeout_s: Longest wait for the server (s, wall clock); None: forever.
            settle_s: Further wait once it is seen, for the server to discover this client
                in turn (see ``DISCOVERY_SETTLE_S``); 0 for a server in the same context.
        """
        if not self.spin_until(self.server_is_ready, timeout_s):
            return False
        self.spin_until(lambda: False, settle_s)
        return self.server_is_ready()

    def current_target(self, timeout_s: float | None = None) -> tuple[float, float, float]:
        """X_d (m, map_ned) of the next controller/state message: X0 of a half circle.

        Raises:
            TaskClientError: No state within the timeout.
        """
        self.latest_state = None
        if not self.spin_until(lambda: self._latest_state is not None, timeout_s):
            msg = f'no {self.node.resolve_topic_name(STATE_TOPIC)} message in {timeout_s} s'
            raise TaskClientError(msg)
        state = self.latest_state
        assert state is not None
        p = state.desired_position
        return (p.x, p.y, p.z)

    def send_goal(
        self,
        goal: ContactTask.Goal,
        feedback_callback: FeedbackCallback | None = None,
        timeout_s: float | None = 10.0,
    ) -> ClientGoalHandle:
        """Send a goal and wait for the server's answer; return the goal handle.

        Raises:
            TaskClientError: No answer within the timeout (s). A rejected goal is returned
                with ``accepted`` False, not raised.
        """
        future = self.send_goal_async(goal, feedback_callback)
        if not self.spin_until(future.done, timeout_s):
            msg = f'{self.action_name}: no answer to the goal in {timeout_s} s'
            raise TaskClientError(msg)
        handle: ClientGoalHandle = future.result()
        return handle

    def wait_for_result(self, handle: ClientGoalHandle,
                        timeout_s: float | None = None) -> tuple[int, ContactTask.Result]:
        """Wait for an accepted goal to end: (GoalStatus status, result).

        Raises:
            TaskClientError: No result within the timeout (s); the goal keeps running.
        """
        future = self.result_async(handle)
        if not self.spin_until(future.done, timeout_s):
            msg = f'{self.action_name}: no result in {timeout_s} s'
            raise TaskClientError(msg)
        response: Any = future.result()
        return int(response.status), response.result

    def cancel(self, handle: ClientGoalHandle, timeout_s: float | None = 5.0) -> bool:
        """Ask the server to cancel a goal; whether it accepted the request in time."""
        future = self.cancel_async(handle)
        if not self.spin_until(future.done, timeout_s):
            return False
        response: Any = future.result()
        return len(response.goals_canceling) > 0

    def run(
        self,
        goal: ContactTask.Goal,
        name: str = 'task',
        feedback_callback: FeedbackCallback | None = None,
        timeout_s: float | None = None,
    ) -> TaskOutcome:
        """Send a goal and wait for its end; a rejected goal is an outcome too.

        Raises:
            TaskClientError: No answer or no result within the timeout (s).
        """
        since = time.monotonic()
        handle = self.send_goal(goal, feedback_callback)
        if not handle.accepted:
            return TaskOutcome(name=name, status=int(handle.status), rejected=True,
                               reason=self.rejection_reason(since))
        status, result = self.wait_for_result(handle, timeout_s)
        return TaskOutcome(name=name, status=status, result=result)

    def destroy(self) -> None:
        """Destroy the action client and subscription (and the client's own executor).

        The client's own executor lets go of the node first, as ``run_node`` does: an
        entity destroyed while an EventsExecutor still holds its callbacks can be reached
        by a DDS thread mid-destruction.
        """
        if self._own_executor and self._executor is not None:
            self._executor.remove_node(self.node)
            self._executor.shutdown()
            self._executor = None
        self._action.destroy()
        self.node.destroy_subscription(self._state_subscription)
        if self._rosout is not None:
            self.node.destroy_subscription(self._rosout)

    def _blocking_executor(self) -> Executor:
        """The executor of the blocking methods, with the node on it."""
        if self._executor is None:
            self._executor = make_executor(context=self.node.context)
            self._executor.add_node(self.node)
            self._own_executor = True
        return self._executor
