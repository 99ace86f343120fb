"""The life of contact tasks around the control step: start, limits, release, results.

One goal runs at a time. ``submit`` checks a goal (``validate_goal``) and lets it replace
the running one (which ends PREEMPTED); the goal waits for its start time, follows its path,
and when the path ends with a force still applied, F_d ramps down before the result. A
cancel, a force beyond ``safety.max_contact_force_n``, a saturated wrist sensor or a
tracking error beyond ``safety.max_position_error_m`` end the task the same way: F_d ramps
to zero while X_d backs off ``safety.retreat_m`` along -n, and the result comes when that
retreat is done. Everything happens inside ``step``, on the control loop's own clock, so a
lockstep run stays deterministic.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Hashable
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from uvms_control.core.contact_task import (
    ContactTaskGoal,
    SafetyLimits,
    TaskCode,
    TaskFigures,
    TaskGoalError,
    TaskResult,
    validate_goal,
)
from uvms_control.core.unified_controller import ControllerResult, UnifiedForceController

FloatArray = npt.NDArray[np.float64]

#: A wrist-sensor axis at this share of its range counts as saturated.
SATURATION_SHARE = 0.999


class TaskState(enum.IntEnum):
    """Where the running task is (values of ContactTask.Feedback.STATE_*)."""

    WAITING = 0
    FOLLOWING = 1
    RELEASING = 2
    RETREATING = 3


@dataclass(frozen=True)
class TaskEvent:
    """A task that ended, with its result."""

    goal_id: Hashable
    result: TaskResult


@dataclass(frozen=True)
class TaskProgress:
    """The running task at the last step (the action's feedback)."""

    goal_id: Hashable
    state: TaskState
    progress: float
    force_n: float
    force_desired_n: float


@dataclass
class _Running:
    goal_id: Hashable
    goal: ContactTaskGoal
    normal: FloatArray
    figures: TaskFigures
    state: TaskState = TaskState.WAITING
    start_s: float | None = None
    end_code: TaskCode = TaskCode.SUCCEEDED
    end_message: str = ''


def _empty_result(code: TaskCode, message: str) -> TaskResult:
    return TaskResult(code, message, 0.0, 0.0, math.nan, math.nan)


class TaskSupervisor:
    """Runs contact tasks on a controller, one at a time, checking the safety limits.

    Args:
        controller: the unified force controller.
        limits: the safety limits (replaceable at run time: ``limits``).
    """

    def __init__(self, controller: UnifiedForceController, limits: SafetyLimits) -> None:
        self.controller = controller
        self.limits = limits
        self._running: _Running | None = None
        self._cancel_requested = False
        self._last: ControllerResult | None = None
        self._t_last: float | None = None
        self.breach: str | None = None
        self._target: list[float] | None = None
        self._queued: list[tuple[Hashable, ContactTaskGoal]] = []

    @property
    def goal_id(self) -> Hashable | None:
        """The running goal's id, or None."""
        return None if self._running is None else self._running.goal_id

    @property
    def last_result(self) -> ControllerResult | None:
        """The last controller step's output."""
        return self._last

    def submit(self, goal_id: Hashable, goal: ContactTaskGoal, now_s: float) -> list[TaskEvent]:
        """Take a new goal at time now_s (s); return the tasks that ended by it.

        An invalid goal ends at once (INVALID_GOAL, the field named) and leaves the running
        task alone; a valid one preempts it (PREEMPTED) and starts at its start time, or at
        the next step if that has passed. A goal that arrives before the first step (no
        state yet) is checked at that step.
        """
        if self._last is None:
            self._queued.append((goal_id, goal))
            return []
        try:
            validate_goal(goal, self._last.X, self.limits,
                          self.controller.task.contact_threshold_n)
        except TaskGoalError as error:
            return [TaskEvent(goal_id, _empty_result(TaskCode.INVALID_GOAL, str(error)))]
        events = self._end_running(TaskCode.PREEMPTED, 'preempted by a new goal')
        normal = np.asarray(goal.normal, dtype=np.float64)
        self._running = _Running(goal_id, goal, normal / float(np.linalg.norm(normal)),
                                 TaskFigures(goal.force_n))
        self._running.start_s = goal.start_time_s
        self._cancel_requested = False
        self._target = None
        return events

    def set_target(self, target: list[float]) -> bool:
        """Stream a new hold target (m, map_ned); refused (False) while a task runs.

        The hold point moves toward it at most ``limits.max_target_speed_m_s``.
        """
        if self._running is not None:
            return False
        self._target = list(target)
        return True

    def cancel(self, goal_id: Hashable) -> bool:
        """Ask the running task to end CANCELED (F_d down, back off); False if not running."""
        if self._running is None or self._running.goal_id != goal_id:
            return False
        self._cancel_requested = True
        return True

    def abort_all(self, code: TaskCode, message: str) -> list[TaskEvent]:
        """End the running task at once (deactivation: INACTIVE) and hold where X_d is."""
        events = self._end_running(code, message)
        if self._t_last is not None and self._last is not None:
            self.controller.task.hold(self._last.X_d.tolist())
        return events

    def reset(self) -> list[TaskEvent]:
        """End queued and running goals INACTIVE, clear the target; capture the hold anew."""
        events = self._end_running(TaskCode.INACTIVE, 'the controller was reset')
        events += [TaskEvent(goal_id, _empty_result(TaskCode.INACTIVE, 'the controller was reset'))
                   for goal_id, _ in self._queued]
        self._queued, self._target = [], None
        self.controller.reset()
        self.recapture_hold()
        return events

    def recapture_hold(self) -> None:
        """Hold the measured position from the next step (goals wait for that step)."""
        self.controller.task.hold()
        self._last = self._t_last = None

    def step(self, t: float, q: npt.ArrayLike, w: npt.ArrayLike,
             f_sensor: npt.ArrayLike) -> tuple[ControllerResult, list[TaskEvent]]:
        """One control step at t (s) from the sensors (``step_from_sensors``) and its events."""
        self._before_step(t)
        result = self.controller.step_from_sensors(t, q, w, f_sensor)
        self._last = result
        dt = 0.0 if self._t_last is None else max(t - self._t_last, 0.0)
        self._t_last = t
        events = self._after_step(t, dt, result, np.asarray(f_sensor, dtype=np.float64))
        queued, self._queued = self._queued, []
        for goal_id, goal in queued:
            events += self.submit(goal_id, goal, t)
        return result, events

    def progress(self) -> TaskProgress | None:
        """The running task's feedback, or None."""
        running, last = self._running, self._last
        if running is None or last is None:
            return None
        path = self.controller.task.path
        share = (path.progress(self._t_last or 0.0)
                 if path is not None and running.state != TaskState.WAITING else 0.0)
        return TaskProgress(running.goal_id, running.state, share,
                            float(running.normal @ last.F_e), float(running.normal @ last.F_d))

    def _before_step(self, t: float) -> None:
        running = self._running
        if running is None:
            if self._target is not None and self._t_last is not None:
                self.controller.task.move_hold_toward(
                    self._target, self.limits.max_target_speed_m_s * max(t - self._t_last, 0.0))
            return
        task = self.controller.task
        if running.state == TaskState.WAITING and (running.start_s is None
                                                   or t >= running.start_s):
            self.controller.start_task(t, running.goal)
            running.start_s = t
            running.state = TaskState.FOLLOWING
        if self._cancel_requested and running.state != TaskState.RETREATING:
            self._cancel_requested = False
            if running.state == TaskState.WAITING:
                running.end_code, running.end_message = TaskCode.CANCELED, 'canceled'
                running.state = TaskState.RETREATING  # nothing moved: ends at this step
                return
            self._retreat(t, TaskCode.CANCELED, 'canceled: force released, backing off')
        if running.state == TaskState.FOLLOWING and task.path is not None \
                and t >= task.path.end_time:
            task.release(t)  # F_d down over the task's ramp (nothing to do without force)
            running.state = TaskState.RELEASING

    def _retreat(self, t: float, code: TaskCode, message: str) -> None:
        running = self._running
        assert running is not None and self._last is not None
        running.end_code, running.end_message = code, message
        running.state = TaskState.RETREATING
        self.controller.task.retreat(t, self._last.X.tolist(), running.normal,
                                     self.limits.retreat_m, self.limits.retreat_time_s)

    def _check_limits(self, result: ControllerResult, f_sensor: FloatArray,
                      f_normal: float) -> tuple[TaskCode, str] | None:
        """The first limit breached at this step, with its message; None within all.

        Plain floats: this runs at every control step.
        """
        limits = self.limits
        if f_normal > limits.max_contact_force_n:
            return TaskCode.FORCE_LIMIT, (f'contact force {f_normal:.1f} N exceeds '
                                          f'safety.max_contact_force_n = '
                                          f'{limits.max_contact_force_n} N')
        reading = max(abs(value) for value in f_sensor.tolist())
        if reading >= SATURATION_SHARE * limits.sensor_range_n:
            return TaskCode.FORCE_LIMIT, (f'wrist sensor saturated: {reading:.1f} N of its '
                                          f'{limits.sensor_range_n} N range')
        error = math.dist(result.X_d.tolist(), result.X.tolist())
        if error > limits.max_position_error_m:
            return TaskCode.TRACKING_LIMIT, (f'position error |X_d - X| = {error:.3f} m '
                                             f'exceeds safety.max_position_error_m = '
                                             f'{limits.max_position_error_m} m')
        return None

    def _after_step(self, t: float, dt: float, result: ControllerResult,
                    f_sensor: FloatArray) -> list[TaskEvent]:
        running = self._running
        normal = running.normal if running is not None else self.controller.n
        f_normal = float(normal @ result.F_e)
        breach = self._check_limits(result, f_sensor, f_normal)
        self.breach = None if breach is None else breach[1]
        if running is None:
            return []
        task = self.controller.task
        running.figures.update(t, dt, f_normal, f_normal >= task.contact_threshold_n,
                               task.force_active and self._at_setpoint(result, running))
        if breach is not None and running.state in (TaskState.FOLLOWING, TaskState.RELEASING):
            self._retreat(t, *breach)
            return []
        done = (running.state in (TaskState.RELEASING, TaskState.RETREATING)
                and task.force_idle
                and (task.path is None or t >= task.path.end_time))
        if not done:
            return []
        code, message = running.end_code, running.end_message
        if code == TaskCode.SUCCEEDED:
            if running.goal.require_contact and running.figures.first_contact_s is None:
                code, message = TaskCode.NO_CONTACT, 'the path ended without contact'
            else:
                message = 'path done'
        return self._finish(code, message)

    def _at_setpoint(self, result: ControllerResult, running: _Running) -> bool:
        """F_d has reached force_n (the ramp is over)."""
        return abs(float(running.normal @ result.F_d) - running.goal.force_n) \
            <= 1e-9 * running.goal.force_n

    def _finish(self, code: TaskCode, message: str) -> list[TaskEvent]:
        running = self._running
        assert running is not None
        self._running = None
        self._cancel_requested = False
        if self._last is not None:
            self.controller.task.hold(self._last.X_d.tolist())
        return [TaskEvent(running.goal_id, running.figures.result(code, message))]

    def _end_running(self, code: TaskCode, message: str) -> list[TaskEvent]:
        if self._running is None:
            return []
        running = self._running
        self._running = None
        self._cancel_requested = False
        return [TaskEvent(running.goal_id, running.figures.result(code, message))]


def with_limits(limits: SafetyLimits, **changes: float) -> SafetyLimits:
    """A copy of the limits with some values changed (runtime parameters)."""
    return replace(limits, **changes)
