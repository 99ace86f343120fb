"""The task supervisor's safety checks: the limits at every step, and the release of a contact.

``check_limits`` reads one controller step against ``SafetyLimits`` (|F_e|, wrist-sensor
saturation, |X_d - X|); ``Release`` is what "released" means at the end of a goal, after a
preemption and at the end of a retreat still in contact: F_d ramps down for good, then X_d
backs off against the measured force until it is under half the contact threshold. The
retreat itself: ``retreat.Retreat``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from uvms_control.core.law.task_reference import TaskReference
from uvms_control.core.law.unified_controller import ControllerResult
from uvms_control.core.task.contact_task import SafetyLimits, TaskCode

FloatArray = npt.NDArray[np.float64]

#: A wrist-sensor axis at this share of its range counts as saturated.
SATURATION_SHARE = 0.999

#: During a retreat the force limit trips (SAFE_HOLD) once |F_e| grows beyond this share of
#: the larger of the limit and the force at the retreat's start: the force that tripped the
#: retreat may still rise for a few periods while the arm decelerates, growing further means
#: the back-off is not working. At the retreat's end any breach trips.
RETREAT_FORCE_MARGIN = 1.25

#: Longest time (s) one step moves a hold point (streamed target, back-off) and adds to the
#: figures: a gap in the inputs is not integrated as one long step.
MAX_MOTION_STEP_S = 0.1

#: The contact counts as released once |F_e| is under this share of the contact threshold (the
#: same hysteresis as the force set-point's re-arming).
RELEASED_SHARE = 0.5


@dataclass(frozen=True)
class Breach:
    """A safety limit breached at one step."""

    code: TaskCode
    message: str


def check_limits(result: ControllerResult, f_sensor: FloatArray, f_normal: float,
                 limits: SafetyLimits) -> Breach | None:
    """The first limit breached at this step; None within all.

    The force limit applies to |F_e| whatever its direction (a reversed or wrong normal, a
    sideways or pulling force), with n·F_e in the message. Plain floats: this runs at every
    control step.

    Args:
        result: the controller step.
        f_sensor: the wrist-sensor reading (N), per axis.
        f_normal: n·F_e along the running task's normal (or the controller's) (N).
        limits: the safety limits.
    """
    f0, f1, f2 = result.F_e.tolist()
    magnitude = math.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
    if not magnitude <= limits.max_contact_force_n:
        return Breach(TaskCode.FORCE_LIMIT, (
            f'contact force |F_e| = {beyond(magnitude, limits.max_contact_force_n, 1)} N '
            f'(n·F_e = {f_normal:.1f} N) exceeds '
            f'safety.max_contact_force_n = {limits.max_contact_force_n} N'))
    reading = max(abs(value) for value in f_sensor.tolist())
    if reading >= SATURATION_SHARE * limits.sensor_range_n:
        return Breach(TaskCode.FORCE_LIMIT, (f'wrist sensor saturated: {reading:.1f} N of its '
                                             f'{limits.sensor_range_n} N range'))
    error = math.dist(result.X_d.tolist(), result.X.tolist())
    if not error <= limits.max_position_error_m:
        return Breach(TaskCode.TRACKING_LIMIT, (
            f'position error |X_d - X| = {beyond(error, limits.max_position_error_m, 3)} m '
            f'exceeds safety.max_position_error_m = {limits.max_position_error_m} m'))
    return None


def beyond(value: float, limit: float, decimals: int) -> str:
    """``value`` with at least ``decimals`` decimals, more until it reads apart from ``limit``.

    A breach message must show why: ``0.0031 m exceeds ... = 0.003 m``, never ``0.003 m``
    twice. At most 9 decimals.
    """
    digits = decimals
    while digits < 9 and f'{value:.{digits}f}' == f'{limit:.{digits}f}':
        digits += 1
    return f'{value:.{digits}f}'


def force_direction(F_e: FloatArray, normal: FloatArray, threshold_n: float) -> FloatArray:
    """The unit direction into the surface: along the measured force in contact, else n.

    A retreat starts along minus this, so a wrong normal (reversed, tilted) still moves the
    end effector off the surface it actually presses on; out of contact n is not verified, and
    the retreat turns if it meets a contact on its way (``retreat.Retreat``).
    """
    magnitude = float(np.linalg.norm(F_e))
    if magnitude >= threshold_n:
        unit: FloatArray = F_e / magnitude
        return unit
    return normal


class Release:
    """F_d ramping down for good, then X_d backing off until the contact is gone.

    The back-off moves against the force measured at each step (the contact it is in), never
    along a normal it was given: a reversed or wrong normal does not move it into the surface.

    Args:
        task: the reference whose hold point backs off.
        speed_m_s: back-off speed (m/s): retreat_m / retreat_time_s.
        max_distance_m: the back-off ends here even with a force left (m).
        threshold_n: the contact threshold (N).
    """

    def __init__(self, task: TaskReference, speed_m_s: float, max_distance_m: float,
                 threshold_n: float) -> None:
        self.task = task
        self.speed_m_s = speed_m_s
        self.max_distance_m = max_distance_m
        self.threshold_n = threshold_n
        self.travelled_m = 0.0

    @staticmethod
    def released_from(F_e: FloatArray, threshold_n: float) -> bool:
        """|F_e| (N) under ``RELEASED_SHARE`` of the contact threshold threshold_n (N)."""
        f0, f1, f2 = F_e.tolist()
        return math.sqrt(f0 * f0 + f1 * f1 + f2 * f2) < RELEASED_SHARE * threshold_n

    def released(self, F_e: FloatArray) -> bool:
        """|F_e| (N) under half the contact threshold."""
        return self.released_from(F_e, self.threshold_n)

    def step(self, t: float, F_e: FloatArray, dt: float) -> None:
        """Back X_d off by speed dt against F_e once F_d is zero, while in contact."""
        if not self.task.force_idle or self.released(F_e) \
                or self.travelled_m >= self.max_distance_m:
            return
        self.task.hold_reached(t)
        distance = min(self.speed_m_s * dt, self.max_distance_m - self.travelled_m)
        scale = distance / float(np.linalg.norm(F_e))
        self.task.shift_hold([-scale * f for f in F_e.tolist()])
        self.travelled_m += distance

    def done(self, F_e: FloatArray) -> bool:
        """F_d is zero and the contact released, or the back-off went its whole way."""
        return self.task.force_idle and (self.released(F_e)
                                         or self.travelled_m >= self.max_distance_m)
