"""Tasks as ContactTask goals, and the action's results and feedback as one-line text.

The only place of uvms_tasks where numpy meets ``uvms_msgs``: a ``TaskSpec`` (map_ned, SI)
becomes a ``ContactTask.Goal`` in frame map_ned, its ``start_time_s`` the header stamp on the
controller's clock (zero: when the goal is accepted).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Vector3
from std_msgs.msg import Header

from uvms_msgs.action import ContactTask
from uvms_tasks.errors import TaskGoalError
from uvms_tasks.task_file import FloatArray, TaskSpec

#: Frame of every goal's path, normal, velocities and accelerations.
GOAL_FRAME = 'map_ned'
NS_PER_S = 1_000_000_000

#: ContactTask.Result.error_code -> its constant's name.
ERROR_CODE_NAMES = {
    getattr(ContactTask.Result, name): name
    for name in ('SUCCEEDED', 'INVALID_GOAL', 'NO_CONTACT', 'FORCE_LIMIT', 'TRACKING_LIMIT',
                 'PREEMPTED', 'CANCELED', 'INACTIVE', 'INPUTS_STALE', 'ACTUATION_LOST',
                 'FORCE_NOT_SETTLED')
}
#: ContactTask.Feedback.phase -> name (the fuzzy switch's phase, paper sec. 4.3).
PHASE_NAMES = {
    ContactTask.Feedback.PHASE_FREE: 'free',
    ContactTask.Feedback.PHASE_TRANSITION: 'transition',
    ContactTask.Feedback.PHASE_CONSTRAINED: 'constrained',
}
#: ContactTask.Feedback.state -> name.
STATE_NAMES = {
    ContactTask.Feedback.STATE_WAITING: 'waiting',
    ContactTask.Feedback.STATE_FOLLOWING: 'following',
    ContactTask.Feedback.STATE_RELEASING: 'releasing',
    ContactTask.Feedback.STATE_RETREATING: 'retreating',
}
#: action_msgs GoalStatus.status -> name.
STATUS_NAMES = {
    GoalStatus.STATUS_UNKNOWN: 'UNKNOWN',
    GoalStatus.STATUS_ACCEPTED: 'ACCEPTED',
    GoalStatus.STATUS_EXECUTING: 'EXECUTING',
    GoalStatus.STATUS_CANCELING: 'CANCELING',
    GoalStatus.STATUS_SUCCEEDED: 'SUCCEEDED',
    GoalStatus.STATUS_CANCELED: 'CANCELED',
    GoalStatus.STATUS_ABORTED: 'ABORTED',
}


@dataclass(frozen=True)
class TaskOutcome:
    """How one goal ended.

    Attributes:
        name: The task's label.
        status: action_msgs GoalStatus of the goal (SUCCEEDED, ABORTED, CANCELED, ...).
        result: The server's result; None if the goal was rejected before it ran.
        rejected: Whether the server refused the goal at once (no result then).
        reason: Why, as the controller logged it (None: its log line was not seen).
    """

    name: str
    status: int
    result: ContactTask.Result | None = None
    rejected: bool = False
    reason: str | None = None

    @property
    def succeeded(self) -> bool:
        """The goal SUCCEEDED with error code SUCCEEDED."""
        return (self.status == GoalStatus.STATUS_SUCCEEDED and self.result is not None
                and self.result.error_code == ContactTask.Result.SUCCEEDED)

    @property
    def code(self) -> str:
        """The result's code name (``NO_CONTACT``), ``REJECTED``, or the goal status name."""
        if self.rejected:
            return 'REJECTED'
        if self.result is None:
            return STATUS_NAMES.get(self.status, f'status {self.status}')
        return ERROR_CODE_NAMES.get(self.result.error_code,
                                    f'error code {self.result.error_code}')

    @property
    def message(self) -> str:
        """The result's ``error_string``; for a refused goal, where to read why."""
        if self.rejected:
            return 'the controller refused the goal; its log says why'
        return str(self.result.error_string) if self.result is not None else ''

    def describe(self) -> str:
        """One line: name, status, error code and the result's numbers."""
        text = describe_result(self.status, self.result, self.rejected, self.reason)
        return f'{self.name}: {text}'


def stamp_from_seconds(t_s: float | None) -> Time:
    """builtin_interfaces Time of t_s seconds on the controller's clock; None: zero."""
    if t_s is None:
        return Time()
    sec, nanosec = divmod(round(t_s * NS_PER_S), NS_PER_S)
    return Time(sec=int(sec), nanosec=int(nanosec))


def goal_from_task(task: TaskSpec, start: Sequence[float] | None = None) -> ContactTask.Goal:
    """The ContactTask goal of a task; a half circle is expanded from its own start or ``start``.

    Raises:
        TaskGoalError: A half circle without either.
    """
    if task.needs_start and start is None:
        msg = f'{task.name}: a half circle needs its start X0 (the controller X_d)'
        raise TaskGoalError(msg)
    task = task.expanded(start)
    goal = ContactTask.Goal()
    goal.header = Header(stamp=stamp_from_seconds(task.start_time_s), frame_id=GOAL_FRAME)
    goal.path = [Point(x=x, y=y, z=z) for x, y, z in task.path.tolist()]
    goal.time_from_start_s = task.time_from_start_s.tolist()
    goal.velocity = _vectors(task.velocity)
    goal.acceleration = _vectors(task.acceleration)
    nx, ny, nz = task.normal.tolist()
    goal.normal = Vector3(x=nx, y=ny, z=nz)
    goal.force_n = task.force_n
    goal.force_ramp_s = task.force_ramp_s
    goal.require_contact = task.require_contact
    return goal


def goal_waypoints(goal: ContactTask.Goal) -> FloatArray:
    """The goal's path as an (n, 3) array (m)."""
    return np.array([[p.x, p.y, p.z] for p in goal.path], dtype=np.float64).reshape(-1, 3)


def describe_task(task: TaskSpec) -> str:
    """One line on what a task asks: path length and duration, force, start."""
    if task.half_circle is not None:
        shape = (f'half circle r {task.half_circle.radius_m:g} m over '
                 f'{task.half_circle.duration_s:g} s')
    else:
        shape = (f'{len(task.path)} waypoints over {float(task.time_from_start_s[-1]):g} s')
    force = f'F_d {task.force_n:g} N' if task.force_n > 0.0 else 'motion only'
    start = ('on acceptance' if task.start_time_s is None
             else f'at t = {task.start_time_s:g} s')
    return f'{task.name}: {shape}, {force}, starting {start}'


def describe_result(status: int, result: ContactTask.Result | None,
                    rejected: bool = False, reason: str | None = None) -> str:
    """One line of a goal's end: ``SUCCEEDED: contact 12.30 s, peak 151.2 N, ...``.

    A rejected goal: ``REJECTED: <reason>`` (the controller's log line), or a pointer to the
    controller's log when the reason was not seen. A transit before the path is named last.
    """
    if rejected:
        if reason is None:
            return 'REJECTED by the server (the controller log says why)'
        return f'REJECTED: {reason}'
    if result is None:
        return STATUS_NAMES.get(status, f'status {status}')
    code = ERROR_CODE_NAMES.get(result.error_code, f'error code {result.error_code}')
    text = code if STATUS_NAMES.get(status) == code else f'{STATUS_NAMES.get(status)} ({code})'
    numbers = (f'contact {result.contact_time_s:.2f} s, peak {result.peak_force_n:.1f} N, '
               f'RMS error {_maybe(result.rms_force_error_n, "N")}, '
               f'settled in {_maybe(result.settling_time_s, "s")}')
    detail = f': {result.error_string}' if result.error_string else ''
    transit = (f'; transit to path[0] first: {result.transit_s:.2f} s'
               if result.transit_s > 0.0 else '')
    health = (f'; real time: {result.missed_periods} of {result.control_periods} control '
              f'periods missed, {result.late_steps} steps late' if result.control_periods else '')
    return f'{text}{detail}; {numbers}{transit}{health}'


def describe_feedback(feedback: ContactTask.Feedback) -> str:
    """One line of progress: state (``transit`` on the way to path[0]), phase, W, F, progress."""
    state = ('transit' if feedback.in_transit
             else STATE_NAMES.get(feedback.state, f'state {feedback.state}'))
    phase = PHASE_NAMES.get(feedback.phase, f'phase {feedback.phase}')
    return (f'{state:<10} {phase:<11} W {feedback.weight:4.2f}  '
            f'F {feedback.force_n:7.1f} / {feedback.force_desired_n:6.1f} N  '
            f'{100.0 * feedback.progress:5.1f} %')


def _maybe(value: float, unit: str) -> str:
    """A number with its unit, or ``none`` for NaN (never settled, no contact)."""
    return 'none' if math.isnan(value) else f'{value:.2f} {unit}'


def _vectors(values: FloatArray | None) -> list[Vector3]:
    """Vector3 per row of an (n, 3) array; empty for None (the server chooses)."""
    if values is None:
        return []
    return [Vector3(x=x, y=y, z=z) for x, y, z in values.tolist()]
