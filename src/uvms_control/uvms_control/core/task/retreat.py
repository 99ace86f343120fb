"""The protected retreat of the task supervisor: back off, never into a contact, until released.

A retreat (a cancel, a safety limit) ramps F_d to zero over ``safety.retreat_time_s``, for
good, while X_d backs off ``safety.retreat_m`` from the measured position at rest, against the
measured force in contact, else along -n. Out of contact n is not verified: a reversed or
wrong normal would back off into the surface. So at every step:

- a contact whose force has a component along the back-off's motion (it moves into what it
  presses on) turns the back-off: it starts again from the measured position at rest, against
  the measured force, for a whole ``retreat_time_s``; a second such contact is a breach (the
  back-off keeps meeting a surface: the safe hold);
- when the time is up, a contact still measured (|F_e| at or above the release share of the
  contact threshold) keeps the retreat going: the hold point backs off against the measured
  force (``Release``) until the contact is gone or ``retreat_m`` more (beyond how far X_d is
  held inside the surface) has been travelled, and only then does the retreat end.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from uvms_control.core.law.controller_result import ControllerResult
from uvms_control.core.law.task_reference import TaskReference
from uvms_control.core.task.contact_task import SafetyLimits, TaskCode
from uvms_control.core.task.safety_checks import (
    RETREAT_FORCE_MARGIN,
    Breach,
    Release,
    force_direction,
)

FloatArray = npt.NDArray[np.float64]


def moves_into_contact(F_e: FloatArray, direction: FloatArray, threshold_n: float) -> bool:
    """A contact (|F_e| at or above threshold_n, N) pressed on by a back-off along -direction.

    F_e is the force the end effector exerts on the surface: it points into the surface, so
    a back-off moves into it when -direction·F_e > 0.
    """
    f0, f1, f2 = F_e.tolist()
    if f0 * f0 + f1 * f1 + f2 * f2 < threshold_n * threshold_n:
        return False
    d0, d1, d2 = direction.tolist()
    return bool(d0 * f0 + d1 * f1 + d2 * f2 < 0.0)


class Retreat:
    """One protected retreat, from its start to its end (``check`` returns True).

    Args:
        task: the reference that backs off.
        limits: the safety limits (``retreat_m``, ``retreat_time_s``, the force limit).
        t: start time (s).
        last: the last controller step (measured X and F_e).
        normal: the task's unit normal (the back-off's direction without contact).
        code: the result code of the goal it ends (CANCELED, FORCE_LIMIT, TRACKING_LIMIT).
        message: why it retreats (the result's message).
    """

    def __init__(self, task: TaskReference, limits: SafetyLimits, t: float,
                 last: ControllerResult, normal: FloatArray, code: TaskCode,
                 message: str) -> None:
        self.task = task
        self.limits = limits
        self.code = code
        self.message = message
        self.turned = False
        self.release: Release | None = None
        magnitude = float(np.linalg.norm(last.F_e))
        #: |F_e| (N) beyond which a breach during the retreat latches the safe hold.
        self.force_cap_n = RETREAT_FORCE_MARGIN * max(limits.max_contact_force_n, magnitude)
        self.direction = force_direction(last.F_e, normal, task.contact_threshold_n)
        #: When the back-off's time is up (s): a whole retreat_time_s after its (re)start.
        self.end_s = t + limits.retreat_time_s
        self._back_off(t, last.X)

    def _back_off(self, t: float, X: FloatArray) -> None:
        """Back off from X (m) at rest along -direction, over a whole retreat_time_s from t."""
        self.end_s = t + self.limits.retreat_time_s
        self.task.retreat(t, X.tolist(), self.direction, self.limits.retreat_m,
                          self.limits.retreat_time_s)

    def move(self, t: float, F_e: FloatArray, dt: float) -> None:
        """Before a step at t (s): the back-off after the time is up, if one runs."""
        if self.release is not None:
            self.release.step(t, F_e, dt)

    def check(self, t: float, result: ControllerResult, breach: Breach | None
              ) -> Breach | bool:
        """After a step: a breach that latches the safe hold, True once the retreat is done.

        A breach latches the safe hold if it is a tracking breach, a force beyond
        ``force_cap_n``, or still there when the time is up.
        """
        threshold_n = self.task.contact_threshold_n
        time_up = t >= self.end_s and self.task.force_idle
        if breach is not None and (breach.code == TaskCode.TRACKING_LIMIT or time_up
                                   or float(np.linalg.norm(result.F_e)) > self.force_cap_n):
            return Breach(breach.code, f'{breach.message}, during a retreat')
        if self.release is None and moves_into_contact(result.F_e, self.direction,
                                                       threshold_n):
            if self.turned:
                return Breach(self.code, (
                    f'the back-off met a contact along its way again (|F_e| = '
                    f'{float(np.linalg.norm(result.F_e)):.1f} N), during a retreat'))
            self.turned = True
            self.direction = result.F_e / float(np.linalg.norm(result.F_e))
            self._back_off(t, result.X)
            return False
        if not time_up:
            return False
        if self.release is None:
            if Release.released_from(result.F_e, threshold_n):
                return True
            # Contact left: back off on, against the measured force (X_d may be held inside).
            self.task.hold(result.X_d.tolist())
            into = result.F_e / float(np.linalg.norm(result.F_e))
            inside = max(float(into @ (result.X_d - result.X)), 0.0)
            self.release = Release(self.task, self.limits.retreat_m / self.limits.retreat_time_s,
                                   self.limits.retreat_m + inside, threshold_n)
            return False
        return self.release.done(result.F_e)

    def outcome(self, F_e: FloatArray) -> str:
        """The result's message at the end: the reason, and a contact left if any."""
        if Release.released_from(F_e, self.task.contact_threshold_n):
            return self.message
        return (f'{self.message}; |F_e| = {float(np.linalg.norm(F_e)):.1f} N left after '
                'backing off the whole retreat distance')
