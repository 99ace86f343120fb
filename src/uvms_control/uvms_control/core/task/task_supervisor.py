"""The life of contact tasks around the control step: one state machine with the limits always on.

States (``SupervisorState``): HOLD (no goal: the hold point at rest), WAITING (a goal waits for
its stamp), FOLLOWING (its path), RELEASING (F_d ramps down at the path's end, then X_d backs
off until the contact is gone), RETREATING (a cancel or a limit: back off from the measured
position, against the measured force, turning at a contact met on the way, until the contact
is gone: ``retreat.Retreat``) and SAFE_HOLD (a limit breached during a retreat: F_d = 0,
X_d = X at rest, following X while in contact, until ``reset``). The limits
(``safety_checks.check_limits``: |F_e|, sensor saturation, |X_d - X|) are checked at every
step in every state. A breach outside a retreat starts a protected retreat that no goal can
preempt: a goal arriving then is refused (INVALID_GOAL, the message names the retreat), and
the running goal's result (with the breach's code) comes when the retreat is done.
All inside ``step``, on the control loop's clock (lockstep stays deterministic); the
diagram: docs/interfaces.md, "Safety". A first waypoint away from X_d gets a transit.
"""

from __future__ import annotations

import math
from collections.abc import Hashable
from dataclasses import replace

import numpy as np
import numpy.typing as npt

from uvms_control.core.law.unified_controller import ControllerResult, UnifiedForceController
from uvms_control.core.task.contact_task import (
    ContactTaskGoal,
    SafetyLimits,
    TaskCode,
    TaskFigures,
    TaskGoalError,
    planned_goal,
    validate_goal,
)
from uvms_control.core.task.force_figures import SETTLING_BAND, SETTLING_MIN_HOLD_S
from uvms_control.core.task.retreat import Retreat
from uvms_control.core.task.safety_checks import (
    MAX_MOTION_STEP_S,
    SATURATION_SHARE,
    Breach,
    Release,
    check_limits,
    force_direction,
)
from uvms_control.core.task.task_states import (
    TASK_STATE,
    RunningTask,
    SupervisorState,
    TaskEvent,
    TaskProgress,
    TaskState,
    empty_result,
)

__all__ = ['SATURATION_SHARE', 'SupervisorState', 'TaskEvent', 'TaskProgress', 'TaskState',
           'TaskSupervisor', 'with_limits']

FloatArray = npt.NDArray[np.float64]


class TaskSupervisor:
    """Runs contact tasks on a controller, one at a time, with the safety limits always on.

    Args:
        controller: the unified force controller.
        limits: the safety limits (replaceable at run time: ``limits``).
    """

    def __init__(self, controller: UnifiedForceController, limits: SafetyLimits) -> None:
        self.controller = controller
        self.limits = limits
        self.state = SupervisorState.HOLD
        #: The breach of the last step, or the one that latched SAFE_HOLD (ERROR on /diagnostics).
        self.breach: str | None = None
        #: Why the last ``set_target`` was refused.
        self.refusal: str | None = None
        self._running: RunningTask | None = None
        self._queued: list[tuple[Hashable, ContactTaskGoal]] = []
        self._pending: list[TaskEvent] = []
        self._cancel_requested = False
        self._last: ControllerResult | None = None
        self._t_last: float | None = None
        self._target: list[float] | None = None
        self._release: Release | None = None
        self._retreating: Retreat | None = None
        self._safe_hold_reason: str | None = None
        self._capturing = True  # the hold point is captured at the next step

    @property
    def goal_id(self) -> Hashable | None:
        """The running goal's id, or None."""
        return None if self._running is None else self._running.goal_id

    @property
    def last_result(self) -> ControllerResult | None:
        """The last controller step's output (None before the first step after a reset)."""
        return self._last

    @property
    def safe_hold(self) -> bool:
        """In SAFE_HOLD (latched until ``reset``)."""
        return self.state == SupervisorState.SAFE_HOLD

    def progress(self) -> TaskProgress | None:
        """The running task's feedback, or None."""
        running, last = self._running, self._last
        if running is None or last is None:
            return None
        path, t = self.controller.task.path, self._t_last or 0.0
        path = path if self.state == SupervisorState.FOLLOWING else None
        share = (path.progress(t) if path is not None
                 else 1.0 if self.state == SupervisorState.RELEASING else 0.0)
        in_transit = path is not None and t < path.start_time + running.transit_s
        return TaskProgress(running.goal_id, TASK_STATE[self.state], share,
                            float(running.normal @ last.F_e), float(running.normal @ last.F_d),
                            running.transit_s, in_transit)

    def submit(self, goal_id: Hashable, goal: ContactTaskGoal, now_s: float) -> list[TaskEvent]:
        """Take a new goal at time now_s (s); return the tasks that ended by it.

        An invalid goal ends at once (INVALID_GOAL, the field named) and leaves the running
        task alone; so does any goal during a retreat or the safe hold (the message says
        which). A valid one preempts the running task (PREEMPTED): its force ramps down over
        ``retreat_time_s`` while X_d holds the measured position at rest and then backs off
        until the contact is gone; the new goal starts from there at its stamp. A goal that
        arrives before the first step after activation or a stale-input abort (no state yet)
        is checked at that step.
        """
        if self._last is None:
            self._queued.append((goal_id, goal))
            return []
        if self._retreating is not None:
            return [TaskEvent(goal_id, empty_result(TaskCode.INVALID_GOAL, (
                f'refused: the arm is retreating ({self._retreating.message}) until at least '
                f't = {self._retreating.end_s:.3f} s; no goal preempts a retreat, send it again '
                'after it')))]
        if self.state == SupervisorState.SAFE_HOLD:
            return [TaskEvent(goal_id, empty_result(TaskCode.INVALID_GOAL, (
                f'refused: the controller is in safe hold ({self._safe_hold_reason}); '
                'clear it with `uvms lifecycle controller reset` (deactivate, activate)')))]
        try:
            self.check(goal, now_s)
        except TaskGoalError as error:
            return [TaskEvent(goal_id, empty_result(TaskCode.INVALID_GOAL, str(error)))]
        events: list[TaskEvent] = []
        if self._running is not None:
            if self.state in (SupervisorState.FOLLOWING, SupervisorState.RELEASING):
                self._begin_release(now_s, self._running.normal, hold_measured=True)
            events = self._end_running(TaskCode.PREEMPTED, 'preempted by a new goal')
        normal = np.asarray(goal.normal, dtype=np.float64)
        self._running = RunningTask(goal_id, goal, normal / float(np.linalg.norm(normal)),
                                    TaskFigures(goal.force_n), goal.start_time_s)
        self.state = SupervisorState.WAITING
        self._cancel_requested = False
        self._target = None
        return events

    def check(self, goal: ContactTaskGoal, now_s: float) -> None:
        """``validate_goal`` as ``submit`` takes it now (also the action's goal callback).

        From the hold point (else X), transit included; before the first step, no state.
        Raises ``TaskGoalError`` naming the field and its value.
        """
        last, task = self._last, self.controller.task
        holding = self.state in (SupervisorState.HOLD, SupervisorState.WAITING) and task.ready
        start = None if last is None else task.state(now_s)[:3] if holding else last.X
        validate_goal(goal, None if last is None else last.X, self.limits,
                      task.contact_threshold_n, now_s=now_s,
                      start=None if start is None else np.asarray(start))

    def set_target(self, target: list[float]) -> bool:
        """Stream a new hold target (m, map_ned); False (``refusal`` says why) unless holding.

        Refused while a goal runs, during a retreat or the safe hold, before the first step,
        and when farther than ``limits.max_path_distance_m`` from the end effector. The hold
        point moves toward it at most ``limits.max_target_speed_m_s``.
        """
        if self.state != SupervisorState.HOLD or self._last is None:
            self.refusal = (f'target_position refused in state {self.state.name}'
                            if self._last is not None else
                            'target_position refused: no state since activation')
            return False
        distance = math.dist(target, self._last.X.tolist())
        if not math.isfinite(distance) or distance > self.limits.max_path_distance_m:
            self.refusal = (f'target_position {[round(v, 4) for v in target]} is '
                            f'{distance:.3f} m from the end effector, more than '
                            f'safety.max_path_distance_m = {self.limits.max_path_distance_m} m')
            return False
        self.refusal = None
        self._target = list(target)
        return True

    def cancel(self, goal_id: Hashable) -> bool:
        """Ask a goal to end CANCELED; False if it is neither running nor queued.

        A waiting or queued goal ends at the next step; a moving or pressing one releases its
        force and backs off first (``retreat_time_s``); a retreating one ends with the
        retreat's own code.
        """
        for k, (queued_id, _) in enumerate(self._queued):
            if queued_id == goal_id:
                del self._queued[k]
                self._pending.append(TaskEvent(goal_id, empty_result(TaskCode.CANCELED,
                                                                      'canceled')))
                return True
        if self._running is None or self._running.goal_id != goal_id:
            return False
        self._cancel_requested = True
        return True

    def abort_all(self, code: TaskCode, message: str) -> list[TaskEvent]:
        """End every goal at once (deactivation: INACTIVE; stale inputs: INPUTS_STALE).

        The supervisor then holds, with no force, the position measured at the next step
        (a SAFE_HOLD stays latched); goals arriving until then wait for that step.
        """
        events = self._take_pending() + self._end_running(code, message)
        events += [TaskEvent(goal_id, empty_result(code, message))
                   for goal_id, _ in self._queued]
        self._queued = []
        self.recapture_hold()
        self._last = None
        return events

    def recapture_hold(self) -> None:
        """Hold the position measured at the next step, at rest, with no force (on resume).

        Meant after ``abort_all``; a goal still running ends INPUTS_STALE at the next step. If
        that step finds a contact, the hold point then backs off as a release does, until the
        contact is let go (a hold captured in contact would otherwise press on through the
        impedance law).
        """
        if self._running is not None:
            self._pending += self._end_running(TaskCode.INPUTS_STALE,
                                               'the hold point was re-captured')
        self.controller.task.hold()
        self._capturing = True
        self._release = self._retreating = None
        self._target = None
        self._t_last = None
        if self.state != SupervisorState.SAFE_HOLD:
            self.state = SupervisorState.HOLD

    def reset(self) -> list[TaskEvent]:
        """Start afresh (activation): every goal ends INACTIVE, the safe hold is cleared.

        The hold point is re-captured at the next step; goals arriving before it are queued.
        """
        events = self.abort_all(TaskCode.INACTIVE, 'the controller was reset (activated)')
        self.state = SupervisorState.HOLD
        self.breach = self._safe_hold_reason = None
        self.controller.task.hold()
        return events

    def step(self, t: float, q: npt.ArrayLike, w: npt.ArrayLike, f_sensor: npt.ArrayLike,
             f_t: float | None = None) -> tuple[ControllerResult, list[TaskEvent]]:
        """One control step at t (s) from the sensors (``step_from_sensors``) and its events."""
        dt = 0.0 if self._t_last is None else min(max(t - self._t_last, 0.0), MAX_MOTION_STEP_S)
        events = self._take_pending() + self._before_step(t, dt)
        result = self.controller.step_from_sensors(t, q, w, f_sensor, f_t)
        self._last = result
        self._t_last = t
        events += self._after_step(t, dt, result, np.asarray(f_sensor, dtype=np.float64))
        queued, self._queued = self._queued, []
        for goal_id, goal in queued:
            events += self.submit(goal_id, goal, t)
        return result, events

    def _before_step(self, t: float, dt: float) -> list[TaskEvent]:
        """Transitions that change this step's reference: starts, cancels, path ends."""
        task, running, state = self.controller.task, self._running, self.state
        if state == SupervisorState.HOLD and self._target is not None and self._release is None:
            task.move_hold_toward(self._target, self.limits.max_target_speed_m_s * dt)
        if self._release is not None and self._last is not None:
            self._release.step(t, self._last.F_e, dt)
        if self._retreating is not None and self._last is not None:
            self._retreating.move(t, self._last.F_e, dt)
        if running is None:
            return []
        if self._cancel_requested and state != SupervisorState.RETREATING:
            self._cancel_requested = False
            if state == SupervisorState.WAITING:
                self.state = SupervisorState.HOLD
                return self._end_running(TaskCode.CANCELED, 'canceled before it started')
            self._retreat(t, TaskCode.CANCELED, 'canceled: force released, backing off')
            return []
        if state == SupervisorState.WAITING and (running.start_s is None or t >= running.start_s) \
                and task.ready:
            return self._start(t, running)
        if state == SupervisorState.FOLLOWING and task.path is not None \
                and t >= task.path.end_time:
            self.state = SupervisorState.RELEASING
            self._begin_release(t, running.normal, hold_measured=False,
                                ramp_s=running.goal.force_ramp_s)
        return []

    def _start(self, t: float, running: RunningTask) -> list[TaskEvent]:
        """Start a waiting goal from the reference at rest (a transit first: ``planned_goal``)."""
        assert self._last is not None
        start = np.asarray(self.controller.task.state(t)[:3])
        try:
            validate_goal(replace(running.goal, start_time_s=None), self._last.X, self.limits,
                          self.controller.task.contact_threshold_n, start=start)
        except TaskGoalError as error:
            self.state = SupervisorState.HOLD
            return self._end_running(TaskCode.INVALID_GOAL, f'at its start: {error}')
        self._release = None
        planned, running.transit_s = planned_goal(running.goal, start, self.limits)
        self.controller.start_task(t, planned)
        running.start_s = t
        self.state = SupervisorState.FOLLOWING
        return []

    def _begin_release(self, t: float, normal: FloatArray, hold_measured: bool,
                       ramp_s: float | None = None) -> None:
        """F_d down (for good), then back off from the contact (``Release``)."""
        assert self._last is not None
        task = self.controller.task
        if hold_measured:
            task.hold_releasing(t, self._last.X.tolist(), self.limits.retreat_time_s)
        else:
            task.release(t, ramp_s, final=True)
        direction = force_direction(self._last.F_e, normal, task.contact_threshold_n)
        speed = self.limits.retreat_m / self.limits.retreat_time_s
        # How far X_d is held inside the surface beyond X: the back-off may need it too.
        penetration = (0.0 if hold_measured else
                       max(float(direction @ (self._last.X_d - self._last.X)), 0.0))
        self._release = Release(task, speed, self.limits.retreat_m + penetration,
                                task.contact_threshold_n)

    def _retreat(self, t: float, code: TaskCode, message: str) -> None:
        """Back off from the measured position, protected (``Retreat``)."""
        assert self._last is not None
        normal = self._running.normal if self._running is not None else self.controller.n
        self.state = SupervisorState.RETREATING
        self._release = None
        self._target = None
        self._retreating = Retreat(self.controller.task, self.limits, t, self._last, normal,
                                   code, message)

    def _enter_safe_hold(self, code: TaskCode, reason: str) -> list[TaskEvent]:
        """F_d = 0 at once and X_d = X at rest, latched until ``reset``."""
        assert self._last is not None
        self.state = SupervisorState.SAFE_HOLD
        self._safe_hold_reason = reason
        self.breach = f'safe hold: {reason}'
        self._release = self._retreating = None
        self.controller.task.hold(self._last.X.tolist())
        return self._end_running(code, f'safe hold: {reason}')

    def _after_step(self, t: float, dt: float, result: ControllerResult,
                    f_sensor: FloatArray) -> list[TaskEvent]:
        """Limits, figures and the ends of releases and retreats, after the step."""
        running, task, state = self._running, self.controller.task, self.state
        normal = running.normal if running is not None else self.controller.n
        f_normal = float(normal @ result.F_e)
        breach = check_limits(result, f_sensor, f_normal, self.limits)
        if running is not None and state != SupervisorState.WAITING:  # from its start
            running.figures.update(t, dt, f_normal, f_normal >= task.contact_threshold_n,
                                   task.force_active and self._at_setpoint(result, running))
        if state == SupervisorState.SAFE_HOLD:
            # In contact or far from X_d the hold follows X: the arm yields to the surface (no
            # pressing on through the impedance law) and never pulls back toward a stale point.
            if (breach is not None and breach.code == TaskCode.TRACKING_LIMIT) \
                    or float(np.linalg.norm(result.F_e)) >= task.contact_threshold_n:
                task.hold(result.X.tolist())
            return []
        self.breach = None if breach is None else breach.message
        if self._capturing:
            self._capturing = False
            # Captured in contact (activation, resume after stale inputs): let the contact go.
            if breach is None and state == SupervisorState.HOLD and self._release is None \
                    and float(np.linalg.norm(result.F_e)) >= task.contact_threshold_n:
                self._begin_release(t, self.controller.n, hold_measured=True)
        if state == SupervisorState.RETREATING:
            return self._check_retreat(t, result, breach)
        if breach is not None:
            self._retreat(t, breach.code, breach.message)
            return []
        release = self._release
        if release is not None and release.done(result.F_e):
            self._release = None
            task.drop_idle_force()
            if state == SupervisorState.RELEASING:
                return self._finish_goal(release.released(result.F_e))
        return []

    def _check_retreat(self, t: float, result: ControllerResult,
                       breach: Breach | None) -> list[TaskEvent]:
        """A breach during a retreat goes to SAFE_HOLD; a retreat done ends its goal."""
        retreat = self._retreating
        assert retreat is not None
        outcome = retreat.check(t, result, breach)
        if isinstance(outcome, Breach):
            return self._enter_safe_hold(outcome.code, outcome.message)
        if not outcome:
            return []
        self._retreating = None
        self.controller.task.hold(result.X_d.tolist())
        self.state = SupervisorState.HOLD
        return self._end_running(retreat.code, retreat.outcome(result.F_e))

    def _finish_goal(self, released: bool) -> list[TaskEvent]:
        """End a released goal by its criterion (NO_CONTACT, FORCE_NOT_SETTLED, SUCCEEDED)."""
        running = self._running
        assert running is not None and self._last is not None
        self.controller.task.hold(self._last.X_d.tolist())
        self.state = SupervisorState.HOLD
        figures = running.figures  # FORCE_NOT_SETTLED: contact made, F never in its band
        if running.goal.require_contact and figures.first_contact_s is None:
            return self._end_running(TaskCode.NO_CONTACT, 'the path ended without contact')
        left = ('contact released' if released else f'|F_e| = '
                f'{float(np.linalg.norm(self._last.F_e)):.1f} N left after backing off the '
                'whole release distance')
        if running.goal.force_n > 0.0 and figures.first_contact_s is not None \
                and math.isnan(figures.result(TaskCode.SUCCEEDED, '').settling_time_s):
            return self._end_running(TaskCode.FORCE_NOT_SETTLED, (
                f'path done, {left}; the force never stayed within {SETTLING_BAND:.0%} of '
                f'F_d = {running.goal.force_n:g} N for {SETTLING_MIN_HOLD_S:g} s'))
        return self._end_running(TaskCode.SUCCEEDED, f'path done, {left}')

    def _at_setpoint(self, result: ControllerResult, running: RunningTask) -> bool:
        """F_d has reached force_n (the ramp is over)."""
        return abs(float(running.normal @ result.F_d) - running.goal.force_n) \
            <= 1e-9 * running.goal.force_n

    def _end_running(self, code: TaskCode, message: str) -> list[TaskEvent]:
        if self._running is None:
            return []
        running = self._running
        self._running = None
        self._cancel_requested = False
        return [TaskEvent(running.goal_id, replace(running.figures.result(code, message),
                                                   transit_s=running.transit_s))]

    def _take_pending(self) -> list[TaskEvent]:
        events, self._pending = self._pending, []
        return events


def with_limits(limits: SafetyLimits, **changes: float) -> SafetyLimits:
    """A copy of the limits with some values changed (runtime parameters)."""
    return replace(limits, **changes)
