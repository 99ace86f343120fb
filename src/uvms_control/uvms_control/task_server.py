"""The ContactTask action server of the controller: goals in, feedback and results out.

A thin adapter between rclpy's ActionServer and the task core (``TaskSupervisor``): its goal
callback rejects a goal that fails the checks (``TaskSupervisor.check``, the pure
``validate_goal`` that runs again when the goal is taken and when it starts) and logs why in
one line, ``contact task goal rejected: <field> = <value>: <limit>`` (a rejected goal gets
no result message in ROS 2 actions: the log, on /rosout, is where a client reads the reason).
It hands an accepted goal to the supervisor (which still ends it INVALID_GOAL when the state
changed in between, or during a retreat, or lets it preempt the running task), and answers
when the control loop says the task ended. The control loop drives everything:
rclpy's coroutine execute callback would poll the executor while a task runs, so the goal
stays ACCEPTED while it runs and ``execute`` is called only to deliver its result. Each
task that ran a step is also published once on ``controller/task_record`` (goal id, F_d,
normal, contact threshold, first and last step), which `uvms report` reads from a recording.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.action.server import ServerGoalHandle
from rclpy.callback_groups import CallbackGroup
from rclpy.node import Node

from uvms_control.core.task.contact_task import (
    ContactTaskGoal,
    TaskCode,
    TaskGoalError,
    TaskResult,
)
from uvms_control.core.task.task_supervisor import TaskEvent, TaskSupervisor
from uvms_control.health_conversions import ActuationWatch
from uvms_control.task_conversions import (
    contact_task_feedback,
    contact_task_goal,
    contact_task_record,
    contact_task_result,
)
from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ContactTaskRecord

#: Feedback period on the controller's clock (s): 20 Hz, above the 10 Hz the contract asks.
FEEDBACK_PERIOD_S = 0.05
#: Start of the log line (/rosout) of a rejected goal; its reason follows.
REJECTED_PREFIX = 'contact task goal rejected: '


def _goal_key(handle: ServerGoalHandle) -> bytes:
    return bytes(handle.goal_id.uuid)


class ContactTaskServer:
    """Serves ``~/contact_task`` for a controller node.

    Args:
        node: the controller node.
        supervisor: returns the running ``TaskSupervisor``, or None while the node is not
            active (goals then end INACTIVE at once).
        now_s: the controller's clock (s).
        callback_group: where the action's callbacks run.
        on_error: told of an exception in a goal or cancel callback (where, error); the goal
            then ends INVALID_GOAL naming it, a cancel is rejected.
    """

    def __init__(self, node: Node, supervisor: Callable[[], TaskSupervisor | None],
                 now_s: Callable[[], float], callback_group: CallbackGroup | None = None,
                 on_error: Callable[[str, Exception], None] | None = None) -> None:
        self._node = node
        self._on_error = on_error
        self._supervisor = supervisor
        self._now_s = now_s
        self._handles: dict[bytes, ServerGoalHandle] = {}
        self._results: dict[bytes, ContactTask.Result] = {}
        self._goals: dict[bytes, tuple[ContactTaskGoal, float]] = {}
        # One record per task that ran, so that a recording tells its tasks apart.
        self._records = node.create_publisher(ContactTaskRecord, 'controller/task_record', 10)
        self._last_feedback_s = -float('inf')
        # Real-time health: control periods, missed periods, late steps since start-up; a
        # goal's are the difference between its end and its acceptance (``count_step``).
        self._health = [0, 0, 0]
        self._health_at: dict[bytes, tuple[int, ...]] = {}
        self._last_step_ns: tuple[int, int] | None = None
        self.goals_received = 0
        self.goals_rejected = 0
        self.last_outcome = 'none'
        self._server = ActionServer(
            node, ContactTask, 'controller/contact_task',
            execute_callback=self._deliver,
            goal_callback=self._check,
            handle_accepted_callback=self._accepted,
            cancel_callback=self._cancel,
            callback_group=callback_group,
        )
        # Thruster faults (issue 32): a goal ends ACTUATION_LOST once the thrusters are short.
        self.actuation = ActuationWatch(node, supervisor, self.finish)

    def destroy(self) -> None:
        """End every open goal (INACTIVE) and remove the action server."""
        self.finish_all(TaskCode.INACTIVE, 'the controller shut down')
        self._server.destroy()

    def open_goal_forces(self) -> list[float]:
        """force_n of every goal not ended yet (N)."""
        return [float(handle.request.force_n) for handle in self._handles.values()]

    def count_step(self, t_ns: int, steady_ns: int, period_ns: int) -> None:
        """Count one control step at t_ns (controller clock) run at steady_ns (steady clock).

        A step k periods after the last (controller clock) missed k - 1 periods (states not
        answered); a step run more than 1.5 periods (steady clock) after the last, for a
        one-period advance of the controller clock, is late: in real time its command reaches
        the simulator a physics step or more after its state (in lockstep the simulator
        waits for it, so lateness only slows the run).
        """
        last, self._last_step_ns = self._last_step_ns, (t_ns, steady_ns)
        if last is None or t_ns <= last[0]:
            return
        elapsed = max(1, round((t_ns - last[0]) / period_ns))
        self._health[0] += elapsed
        self._health[1] += elapsed - 1
        self._health[2] += (steady_ns - last[1]) - (t_ns - last[0]) > period_ns // 2

    def _check(self, request: ContactTask.Goal) -> GoalResponse:
        """Reject a goal that fails the checks, logging why; accept the rest.

        An inactive controller accepts (the goal then ends INACTIVE with its result).
        """
        try:
            supervisor = self._supervisor()
            if supervisor is not None:
                supervisor.check(contact_task_goal(request), self._now_s())
        except TaskGoalError as error:
            return self._reject(str(error))
        except Exception as error:  # nothing escapes into the executor
            if self._on_error is not None:
                self._on_error('contact task goal callback', error)
            return self._reject(f'the controller could not check the goal: '
                                f'{type(error).__name__}: {error}')
        return GoalResponse.ACCEPT

    def _reject(self, reason: str) -> GoalResponse:
        self.goals_rejected += 1
        self.last_outcome = f'REJECTED: {reason}'
        self._node.get_logger().warn(f'{REJECTED_PREFIX}{reason}')
        return GoalResponse.REJECT

    def _accepted(self, handle: ServerGoalHandle) -> None:
        try:
            self._take(handle)
        except Exception as error:  # nothing escapes into the executor
            self._finish(_goal_key(handle), TaskResult(
                TaskCode.INVALID_GOAL, f'the controller could not take the goal: '
                f'{type(error).__name__}: {error}', 0.0, 0.0, float('nan'), float('nan')))
            if self._on_error is not None:
                self._on_error('contact task goal callback', error)

    def _take(self, handle: ServerGoalHandle) -> None:
        key = _goal_key(handle)
        self._handles[key] = handle
        self.goals_received += 1
        supervisor = self._supervisor()
        if supervisor is None:
            self._finish(key, TaskResult(TaskCode.INACTIVE, 'the controller is not active',
                                         0.0, 0.0, float('nan'), float('nan')))
            return
        try:
            goal = contact_task_goal(handle.request)
        except TaskGoalError as error:
            self._finish(key, TaskResult(TaskCode.INVALID_GOAL, str(error), 0.0, 0.0,
                                         float('nan'), float('nan')))
            return
        self._goals[key] = (goal, supervisor.controller.task.contact_threshold_n)
        self._health_at[key] = tuple(self._health)
        self.finish(supervisor.submit(key, goal, self._now_s()))
        if key in self._handles:
            self._node.get_logger().info(
                f'contact task accepted: {len(goal.times)} waypoints over '
                f'{goal.times[-1]:.2f} s, F_d {goal.force_n:g} N')

    def _cancel(self, handle: ServerGoalHandle) -> CancelResponse:
        try:
            supervisor = self._supervisor()
            if supervisor is not None and supervisor.cancel(_goal_key(handle)):
                return CancelResponse.ACCEPT
        except Exception as error:  # nothing escapes into the executor
            if self._on_error is not None:
                self._on_error('contact task cancel callback', error)
        return CancelResponse.REJECT

    def publish_feedback(self, supervisor: TaskSupervisor, now_s: float) -> None:
        """Feedback of the running task, at most once per ``FEEDBACK_PERIOD_S``."""
        if now_s - self._last_feedback_s < FEEDBACK_PERIOD_S:
            return
        progress, step = supervisor.progress(), supervisor.last_result
        if progress is None or step is None:
            return
        handle = self._handles.get(progress.goal_id)  # type: ignore[call-overload]
        if handle is not None:
            self._last_feedback_s = now_s
            handle.publish_feedback(contact_task_feedback(progress, step))

    def finish(self, events: Iterable[TaskEvent]) -> None:
        """Deliver the results of tasks that ended."""
        for event in events:
            self._finish(event.goal_id, event.result)  # type: ignore[arg-type]

    def finish_all(self, code: TaskCode, message: str) -> None:
        """End every open goal with ``code`` (deactivation, shutdown)."""
        for key in list(self._handles):
            self._finish(key, TaskResult(code, message, 0.0, 0.0, float('nan'), float('nan')))

    def _finish(self, key: bytes, result: TaskResult) -> None:
        handle = self._handles.pop(key, None)
        accepted = self._goals.pop(key, None)
        if handle is None:
            return  # ended already (its result is on its way)
        if accepted is not None:
            # The threshold at the end (a runtime parameter), else at acceptance (deactivated).
            supervisor = self._supervisor()
            threshold = (accepted[1] if supervisor is None
                         else supervisor.controller.task.contact_threshold_n)
            record = contact_task_record(key, accepted[0], result, threshold)
            if record is not None:
                self._records.publish(record)
        message = self._results[key] = contact_task_result(result)
        since = self._health_at.pop(key, None)
        if since is not None:
            message.control_periods, message.missed_periods, message.late_steps = (
                now - then for now, then in zip(self._health, since, strict=True))
        self.last_outcome = f'{result.code.name}: {result.message}'
        text = f'contact task ended {result.code.name}: {result.message}'
        if result.code == TaskCode.SUCCEEDED:  # rclpy wants one severity per call site
            self._node.get_logger().info(text)
        else:
            self._node.get_logger().warn(text)
        handle.execute()  # _deliver, from the executor, sets the final state

    def _deliver(self, handle: ServerGoalHandle) -> Any:
        result = self._results.pop(_goal_key(handle))
        if result.error_code == TaskCode.SUCCEEDED:
            handle.succeed()
        elif handle.is_cancel_requested and result.error_code == TaskCode.CANCELED:
            handle.canceled()
        else:
            handle.abort()
        return result
