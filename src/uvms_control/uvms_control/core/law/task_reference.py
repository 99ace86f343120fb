"""What the controller follows: a hold point or a task's path, and the task's force set-point.

Between tasks the reference holds a point (on activation: the end effector's position at the
first step) at rest, with no force set-point, so the impedance law holds it (paper eq. 29).
A task replaces it by a path that starts from the running reference without a jump in X_d,
Ẋ_d or Ẍ_d, and by a set-point of F_d along the task's normal that ramps up at first contact
(``ForceSetpoint``, paper sec. 5.2). At the end of a task, or on a cancel or a limit, the
set-point ramps down; a retreat also moves X_d back off the surface along -n.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from uvms_control.core.law.reference import ForcePhase, ForceSetpoint, ForceSetpointSample
from uvms_control.core.law.task_goal import ContactTaskGoal
from uvms_control.core.law.task_path import TaskPath

FloatArray = npt.NDArray[np.float64]

_NO_FORCE = ForceSetpointSample(0.0, 0.0, 0.0, ForcePhase.IDLE)


class TaskReference:
    """X_d(t) and F_d(t) of the running task, or the hold point between tasks.

    Args:
        contact_threshold_n: normal force that counts as contact (N).
        ramp_from_start: start the force ramp when the task starts instead of at first
            contact (the pure hybrid law, W = 0, needs it: along n it controls only force).
    """

    def __init__(self, contact_threshold_n: float, ramp_from_start: bool = False) -> None:
        self.contact_threshold_n = contact_threshold_n
        self.ramp_from_start = ramp_from_start
        self.path: TaskPath | None = None
        self.force: ForceSetpoint | None = None
        self._hold: list[float] | None = None
        self._hold_velocity: list[float] | None = None  # a pilot's moving hold point

    @property
    def has_force(self) -> bool:
        """A force set-point is defined (a task with force_n > 0 runs or releases)."""
        return self.force is not None

    @property
    def force_active(self) -> bool:
        """F_d is ramping up or held (not idle, not releasing)."""
        return self.force is not None and self.force.phase == ForcePhase.RAMP_UP

    @property
    def force_idle(self) -> bool:
        """No force is asked for, or the ramp-down has ended."""
        return self.force is None or self.force.phase == ForcePhase.IDLE

    def set_contact_threshold(self, contact_threshold_n: float) -> None:
        """Change the force that counts as contact (N), for the running set-point too."""
        self.contact_threshold_n = contact_threshold_n
        if self.force is not None:
            self.force.contact_threshold = contact_threshold_n

    def capture(self, X: Sequence[float]) -> None:
        """Hold X (m) if nothing is held yet (the first step after activation)."""
        if self.path is None and self._hold is None:
            self._hold = list(X)

    def hold(self, position: Sequence[float] | None = None) -> None:
        """Hold a point at rest with no force; None: capture X at the next step."""
        self.path = None
        self.force = None
        self._hold = None if position is None else list(position)
        self._hold_velocity = None

    def follow(self, position: Sequence[float], velocity: Sequence[float]) -> None:
        """Hold a moving point: X_d = position (m), Ẋ_d = velocity (m/s), Ẍ_d = 0 (a pilot).

        Ignored while a path runs; the force set-point is left as it is.
        """
        if self.path is None:
            self._hold = list(position)
            self._hold_velocity = None if not any(velocity) else list(velocity)

    def move_hold_toward(self, target: Sequence[float], max_distance_m: float) -> None:
        """Move the hold point toward a target by at most max_distance_m (m), at rest."""
        if self.path is not None or self._hold is None:
            return
        step = np.asarray(target, dtype=np.float64) - self._hold
        distance = float(np.linalg.norm(step))
        if distance > max_distance_m:
            step *= max_distance_m / distance
        self._hold = (np.asarray(self._hold) + step).tolist()

    def state(self, t: float) -> list[float]:
        """[X_d, Ẋ_d, Ẍ_d] at t (s) as nine floats; the hold point at rest between tasks."""
        if self.path is not None:
            return self.path.evaluate_floats(t)
        if self._hold is None:
            raise RuntimeError('the reference holds no point yet (no step since activation)')
        if self._hold_velocity is not None:
            return [*self._hold, *self._hold_velocity, 0.0, 0.0, 0.0]
        return [*self._hold, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]

    @property
    def ready(self) -> bool:
        """The reference holds a point or follows a path (a task may start from it)."""
        return self.path is not None or self._hold is not None

    def start(self, t: float, goal: ContactTaskGoal) -> None:
        """Follow a goal's path from t (s), from the running reference, with its force.

        A goal without force takes over a set-point still ramping down (a preempted goal's)
        and lets it end; a goal with force starts its own.
        """
        self.path = TaskPath.from_state(
            t, self.state(t), t + goal.times, goal.path, goal.velocities, goal.accelerations
        )
        self._hold = self._hold_velocity = None
        if goal.force_n <= 0.0:
            if self.force is not None and (self.force.phase != ForcePhase.RELEASE):
                self.force = None
            return
        # A task that takes over from a pressing one ramps from the running F_d, not from 0.
        running = self.force.desired(t) if self.force is not None else 0.0
        self.force = ForceSetpoint(goal.force_n, goal.force_ramp_s, self.contact_threshold_n,
                                   start_immediately=self.ramp_from_start, start_force=running)

    def release(self, t: float, ramp_s: float | None = None, final: bool = False) -> None:
        """Ramp F_d down to zero from t (s), over ``ramp_s`` or the task's ramp time.

        ``final``: the set-point never re-arms afterwards (``ForceSetpoint.release``).
        """
        if self.force is not None:
            self.force.release(t, ramp_s, final)

    def hold_releasing(self, t: float, position: Sequence[float], ramp_s: float) -> None:
        """Hold a point (m) at rest from t (s) while F_d ramps down over ramp_s (s), for good."""
        self.path = None
        self._hold = list(position)
        self._hold_velocity = None
        self.release(t, ramp_s, final=True)

    def hold_reached(self, t: float) -> None:
        """Hold X_d of t (s) at rest instead of the path (the path has ended), keeping F_d."""
        if self.path is not None:
            self._hold = self.path.evaluate_floats(t)[:3]
            self.path = None

    def drop_idle_force(self) -> None:
        """Forget a set-point released for good once its ramp-down is over."""
        if self.force is not None and self.force.final and self.force.phase == ForcePhase.IDLE:
            self.force = None

    def shift_hold(self, offset: Sequence[float]) -> None:
        """Move the hold point by offset (m), at rest (a back-off step)."""
        if self._hold is not None:
            self._hold = [h + o for h, o in zip(self._hold, offset, strict=True)]

    def retreat(self, t: float, X: Sequence[float], direction: FloatArray, distance_m: float,
                duration_s: float) -> None:
        """Back off from X (m, measured) at rest to X - distance direction over duration (s).

        F_d ramps to zero over the same time and never re-arms, even if the back-off meets
        a contact: the retreat starts where the end effector is, not where the reference
        was heading, so it neither continues the reference's motion nor jumps back to it.
        """
        start = [*X, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        target = np.asarray(X, dtype=np.float64) - distance_m * direction
        self.path = TaskPath.from_state(t, start, np.array([t + duration_s]),
                                        target[np.newaxis, :])
        self._hold = self._hold_velocity = None
        self.release(t, duration_s, final=True)

    def force_sample(self, t: float, f_normal: float, x_normal: float, x_d_normal: float,
                     x_d_dot_normal: float) -> ForceSetpointSample:
        """F_d and its derivatives at t (``ForceSetpoint.update``); zero without a task force."""
        if self.force is None:
            return _NO_FORCE
        return self.force.update(t, f_normal, x_normal, x_d_normal, x_d_dot_normal)
