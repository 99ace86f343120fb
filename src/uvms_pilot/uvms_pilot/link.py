"""The pilot tools' side of the graph: the pilot topics out, hold and tasks, the live state in.

``PilotLink`` lives on a node in the graph's namespace (/uvms) that an executor spins in a
thread of its own; the input loop calls ``publish``/``hold``/``start_task``/``cancel_task``
from its thread, and reads ``live`` (the latest state, replaced whole, never half-written).
The task's goal and cancel requests go out on the executor's thread (rclpy's ActionClient
is not safe to call from another one).
Topics and services: docs/piloting.md and the pilot interface contract (issue 51).
"""

from __future__ import annotations

import dataclasses
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Joy
from std_msgs.msg import Float64, String
from std_srvs.srv import Trigger

from uvms_pilot.command import PilotCommand
from uvms_pilot.conversions import (
    depth_heading_velocity,
    diagnostics_line,
    force_magnitude_n,
    jaw_message,
    joy_message,
    twist_stamped,
)

VEHICLE_TOPIC = 'pilot/vehicle_twist'
EE_TOPIC = 'pilot/ee_twist'
JAW_TOPIC = 'pilot/jaw'
MODE_TOPIC = 'controller/mode'
HOLD_SERVICE = 'controller/hold'
JOY_TOPIC = '/joy'
#: The pilot topics' QoS (contract): reliable, depth 10, volatile.
PILOT_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
#: The controller's mode: latched.
MODE_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


@dataclass(frozen=True)
class LiveState:
    """What the pilot sees of the robot; None: nothing received yet."""

    depth_m: float | None = None
    heading_deg: float | None = None
    velocity_m_s: tuple[float, float, float] | None = None
    force_n: float | None = None
    mode: str | None = None
    diagnostics: str | None = None
    task: str | None = None
    note: str | None = None


class PilotLink:
    """Publishers, clients and subscriptions of the pilot tools on ``node``.

    Args:
        node: A node in the graph's namespace (/uvms).
        ee_frame: frame_id of the end-effector twists (base_link_frd or map_ned).
        vehicle_frame: frame_id of the vehicle twists ('' means the vehicle body frame).
        joy: Whether to publish sensor_msgs/Joy on /joy (a gamepad is read).
        task_file: The task or mission file of the start-task action, or None.
    """

    def __init__(self, node: Node, ee_frame: str, vehicle_frame: str = '', joy: bool = False,
                 task_file: Path | None = None) -> None:
        self.node = node
        self.ee_frame = ee_frame
        self.vehicle_frame = vehicle_frame
        self.task_file = task_file
        self.live = LiveState()
        self._live_lock = threading.Lock()
        self._vehicle = node.create_publisher(TwistStamped, VEHICLE_TOPIC, PILOT_QOS)
        self._ee = node.create_publisher(TwistStamped, EE_TOPIC, PILOT_QOS)
        self._jaw = node.create_publisher(Float64, JAW_TOPIC, PILOT_QOS)
        self._joy = node.create_publisher(Joy, JOY_TOPIC, 10) if joy else None
        self._hold = node.create_client(Trigger, HOLD_SERVICE)
        node.create_subscription(String, MODE_TOPIC, self._on_mode, MODE_QOS)
        node.create_subscription(Odometry, 'odometry', self._on_odometry, 10)
        node.create_subscription(WrenchStamped, 'wrench', self._on_wrench, 10)
        node.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)
        from uvms_tasks.client import ContactTaskClient

        self._tasks = ContactTaskClient(node)
        self._queue: list[Any] = []
        self._goal: Any = None
        #: A cancel asked while the goal's acceptance was still on its way: sent on acceptance.
        self._cancel_on_accept = False
        #: The input loop's cancel and the executor's acceptance decide under it, so that an
        #: acceptance between the cancel's look and its note cannot lose the cancel.
        self._goal_lock = threading.Lock()
        self._task_name = ''  # the running task's, on its feedback lines
        #: The action client's calls, made on the executor's thread: rclpy's ActionClient
        #: registers a goal's (or a cancel's) answer only after sending its request, so an
        #: answer taken by the executor in between is dropped ("Ignoring unexpected goal
        #: response") and the goal runs with the pilot never told it was accepted.
        self._for_executor: deque[Callable[[], Any]] = deque()
        self._wake_executor = node.create_guard_condition(self._run_for_executor)

    def _update(self, **changes: Any) -> None:
        with self._live_lock:  # the executor's thread and the input loop's both write
            self.live = dataclasses.replace(self.live, **changes)

    def note(self, text: str) -> None:
        """Show one line of what just happened (an answer, a refusal)."""
        self._update(note=text)

    def _on_executor_thread(self, job: Callable[[], Any]) -> None:
        """Run ``job`` on the executor's thread, soon (the input loop's way to the client)."""
        self._for_executor.append(job)
        self._wake_executor.trigger()

    def _run_for_executor(self) -> None:
        while self._for_executor:
            self._for_executor.popleft()()

    # ------------------------------------------------------------------ out

    def publish(self, parts: tuple[str, ...], cmd: PilotCommand) -> None:
        """Publish the command's parts ('vehicle', 'arm', 'jaw'), stamped now."""
        stamp = self.node.get_clock().now().to_msg()
        if 'vehicle' in parts:
            u, v, w, p, q, r = cmd.vehicle_twist
            self._vehicle.publish(twist_stamped(stamp, self.vehicle_frame, (u, v, w), (p, q, r)))
        if 'arm' in parts:
            self._ee.publish(twist_stamped(stamp, self.ee_frame, cmd.ee_velocity_m_s,
                                           (0.0, 0.0, 0.0)))
        if 'jaw' in parts:
            self._jaw.publish(jaw_message(cmd.jaw_m_s))

    def publish_joy(self, axes: list[float], buttons: list[int], frame_id: str) -> None:
        """Publish the gamepad's state on /joy (when the link was made with joy=True)."""
        if self._joy is not None:
            self._joy.publish(joy_message(self.node.get_clock().now().to_msg(), frame_id,
                                          axes, buttons))

    def hold(self) -> None:
        """Ask the controller to hold the present pose; the answer comes as a note."""
        if not self._hold.service_is_ready():
            name = self.node.resolve_service_name(HOLD_SERVICE)
            self.note(f'hold: no service {name} (is the controller running?)')
            return
        future = self._hold.call_async(Trigger.Request())
        future.add_done_callback(self._on_hold)
        self.note('hold: asked')

    def _on_hold(self, future: Any) -> None:
        response = future.result()
        if response is None:
            self.note('hold: no answer')
        elif response.success:
            self.note(f'hold: {response.message or "holding"}')
        else:
            self.note(f'hold refused: {response.message}')

    # ------------------------------------------------------------------ tasks

    def start_task(self) -> None:
        """Send the task file's tasks in order (the next when one SUCCEEDED), as uvms task."""
        from uvms_tasks.errors import TaskFileError
        from uvms_tasks.task_file import load_task_file

        if self.task_file is None:
            self.note('no task file: start uvms pilot with --task FILE.yaml')
            return
        if self._goal is not None or self._queue:
            self.note('a task is running: c cancels it')
            return
        if not self._tasks.server_is_ready():
            self.note(f'no action server {self._tasks.action_name}')
            return
        try:
            self._queue = list(load_task_file(self.task_file))
        except TaskFileError as exc:
            self.note(f'task file refused: {exc}')
            return
        self._on_executor_thread(self._send_next)

    def _send_next(self) -> None:
        from uvms_tasks.errors import TaskError
        from uvms_tasks.goals import describe_task, goal_from_task

        with self._goal_lock:
            if not self._queue:
                return  # cancelled before it went out
            task = self._queue.pop(0)
            self._goal = task
        state = self._tasks.latest_state
        start = None if state is None else (state.desired_position.x,
                                            state.desired_position.y,
                                            state.desired_position.z)
        try:
            goal = goal_from_task(task, start)
        except TaskError as exc:  # on the executor's thread: said on screen, not raised
            with self._goal_lock:
                self._goal, self._queue, self._cancel_on_accept = None, [], False
            self._update(task=f'not sent: {exc}')
            return
        self._update(task=f'sending {describe_task(task)}')
        self._task_name = task.name
        future = self._tasks.send_goal_async(goal, self._on_feedback)
        future.add_done_callback(lambda f: self._on_answer(task, f))

    def _on_feedback(self, feedback: Any) -> None:
        from uvms_tasks.goals import describe_feedback

        self._update(task=f'{self._task_name}: {describe_feedback(feedback)}')

    def _on_answer(self, task: Any, future: Any) -> None:
        from uvms_tasks.goals import TaskOutcome

        handle = future.result()
        with self._goal_lock:
            cancel, self._cancel_on_accept = self._cancel_on_accept, False
            if not handle.accepted:
                self._goal, self._queue = None, []
            else:
                self._goal = handle
        if not handle.accepted:
            self._update(task=TaskOutcome(task.name, int(handle.status), rejected=True).describe())
            return
        self._tasks.result_async(handle).add_done_callback(lambda f: self._on_result(task, f))
        if cancel:
            self._tasks.cancel_async(handle)
            self.note('cancel: asked')

    def _on_result(self, task: Any, future: Any) -> None:
        from uvms_tasks.goals import TaskOutcome

        response = future.result()
        outcome = TaskOutcome(task.name, int(response.status), response.result)
        with self._goal_lock:
            self._goal = None
        self._update(task=outcome.describe())
        if outcome.succeeded and self._queue:
            self._send_next()
        else:
            self._queue = []

    def cancel_task(self) -> None:
        """Cancel the running task (the controller backs the arm off as on any cancel)."""
        with self._goal_lock:
            self._queue = []
            goal = self._goal
            # Sent, its acceptance not yet here: the acceptance sends the cancel.
            waiting = goal is not None and not hasattr(goal, 'cancel_goal_async')
            self._cancel_on_accept = self._cancel_on_accept or waiting
        if goal is None:
            self.note('no task to cancel')
        elif waiting:
            self.note('cancel: asked, sent once the goal is accepted')
        else:
            self._on_executor_thread(lambda: self._tasks.cancel_async(goal))
            self.note('cancel: asked')

    # ------------------------------------------------------------------ in

    def _on_mode(self, msg: String) -> None:
        self._update(mode=msg.data)

    def _on_odometry(self, msg: Odometry) -> None:
        depth, heading, velocity = depth_heading_velocity(msg)
        self._update(depth_m=depth, heading_deg=heading, velocity_m_s=velocity)

    def _on_wrench(self, msg: WrenchStamped) -> None:
        self._update(force_n=force_magnitude_n(msg))

    def _on_diagnostics(self, msg: DiagnosticArray) -> None:
        line = diagnostics_line(msg)
        if line is not None:
            self._update(diagnostics=line)

    def destroy(self) -> None:
        """Destroy the task client (the node's other entities go with the node)."""
        self._tasks.destroy()
