"""Contact tasks: the goal of the ContactTask action, its checks, limits and result figures.

A contact task moves the end effector along a timed path in map_ned and, wherever it meets
a surface, lets the fuzzy switch hand over from impedance to force control (paper sec. 4.3)
and presses with F_d along the normal (sec. 5.2). This module holds what does not depend on
ROS: the goal as plain arrays, its validation (every refusal names the field and value), the
safety limits, and the running figures of the result (contact time, peak, RMS error).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

#: A force within this share of F_d counts as settled (the result's RMS error starts there).
SETTLED_BAND = 0.05


class TaskCode(enum.IntEnum):
    """How a task ended (values of ContactTask.Result.error_code)."""

    SUCCEEDED = 0
    INVALID_GOAL = 1
    NO_CONTACT = 2
    FORCE_LIMIT = 3
    TRACKING_LIMIT = 4
    PREEMPTED = 5
    CANCELED = 6
    INACTIVE = 7
    ACTUATION_LOST = 9


class TaskGoalError(ValueError):
    """A goal the controller refuses; the message names the field and its value."""

    def __init__(self, field: str, value: object, expected: str) -> None:
        self.field = field
        super().__init__(f'{field} = {value}: {expected}')


@dataclass(frozen=True)
class ContactTaskGoal:
    """A ContactTask goal as arrays (map_ned, SI units).

    Attributes:
        path: waypoints X_d (n, 3) (m).
        times: time of each waypoint from the path's start (n,) (s).
        velocities: Ẋ_d at each waypoint (n, 3) (m/s), or None (chosen by the path).
        accelerations: Ẍ_d at each waypoint (n, 3) (m/s²), or None (zero).
        normal: force direction into the surface (3,) (-), not necessarily unit.
        force_n: F_d along the normal while in contact (N); 0: motion only.
        force_ramp_s: ramp of F_d after first contact and down at release (s).
        require_contact: end with NO_CONTACT if the path ends without contact.
        start_time_s: when the path's time 0 is on the controller's clock (s); None: at once.
    """

    path: FloatArray
    times: FloatArray
    velocities: FloatArray | None
    accelerations: FloatArray | None
    normal: FloatArray
    force_n: float
    force_ramp_s: float
    require_contact: bool = False
    start_time_s: float | None = None


@dataclass(frozen=True)
class SafetyLimits:
    """Limits the controller enforces on every task (parameters ``safety.*``).

    Attributes:
        max_contact_force_n: largest measured force along the normal (N); also caps force_n.
        sensor_range_n: wrist-sensor full scale per axis (N): a reading at 99.9 % of it is
            taken as saturated.
        max_position_error_m: largest |X_d - X| (m).
        max_path_distance_m: largest distance of a goal's waypoint from X at acceptance (m).
        retreat_m: back-off along -normal after a cancel or a breach (m).
        retreat_time_s: time of that back-off and of the force ramp-down with it (s).
        max_target_speed_m_s: speed limit of the streamed hold target (m/s).
    """

    max_contact_force_n: float = 400.0
    sensor_range_n: float = 400.0
    max_position_error_m: float = 0.2
    max_path_distance_m: float = 1.5
    retreat_m: float = 0.05
    retreat_time_s: float = 1.0
    max_target_speed_m_s: float = 0.1


def _finite(field: str, values: npt.ArrayLike) -> FloatArray:
    array = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(array)):
        raise TaskGoalError(field, np.round(array, 6).tolist(), 'must be finite (no NaN or Inf)')
    return array


def validate_goal(
    goal: ContactTaskGoal,
    X: FloatArray,
    limits: SafetyLimits,
    contact_threshold_n: float,
) -> None:
    """Check a goal before it may replace the running one.

    Args:
        goal: the goal.
        X: end-effector position at acceptance (m), map_ned.
        limits: the safety limits.
        contact_threshold_n: force that counts as contact (N); a non-zero force_n must
            exceed it.

    Raises:
        TaskGoalError: naming the first field that is wrong, with its value.
    """
    path = _finite('path', goal.path)
    times = _finite('time_from_start_s', goal.times)
    if path.ndim != 2 or path.shape[1] != 3 or path.shape[0] < 2:
        raise TaskGoalError('path', f'{path.shape[0] if path.ndim else 0} points',
                            'needs at least 2 waypoints')
    if times.shape != (path.shape[0],):
        raise TaskGoalError('time_from_start_s', f'{times.size} values',
                            f'needs one per waypoint ({path.shape[0]})')
    if times[0] < 0.0:
        raise TaskGoalError('time_from_start_s[0]', float(times[0]), 'must be >= 0 s')
    steps = np.diff(times)
    if np.any(steps <= 0.0):
        k = int(np.argmax(steps <= 0.0)) + 1
        raise TaskGoalError(f'time_from_start_s[{k}]', float(times[k]),
                            f'must be greater than time_from_start_s[{k - 1}] = {times[k - 1]}')
    for name, values in (('velocity', goal.velocities), ('acceleration', goal.accelerations)):
        if values is None:
            continue
        array = _finite(name, values)
        if array.shape != path.shape:
            raise TaskGoalError(name, f'{len(array)} vectors',
                                f'needs none or one per waypoint ({path.shape[0]})')
    normal = _finite('normal', goal.normal)
    if normal.shape != (3,) or float(np.linalg.norm(normal)) < 1e-9:
        raise TaskGoalError('normal', normal.tolist(), 'must be a non-zero 3-vector')
    force = float(_finite('force_n', goal.force_n))
    if force < 0.0:
        raise TaskGoalError('force_n', force, 'must be >= 0 N (0: motion only)')
    if force > limits.max_contact_force_n:
        raise TaskGoalError('force_n', force, f'exceeds safety.max_contact_force_n = '
                                              f'{limits.max_contact_force_n} N')
    if 0.0 < force <= contact_threshold_n:
        raise TaskGoalError('force_n', force, f'must exceed the contact threshold '
                                              f'{contact_threshold_n} N (or be 0)')
    ramp = float(_finite('force_ramp_s', goal.force_ramp_s))
    if force > 0.0 and ramp <= 0.0:
        raise TaskGoalError('force_ramp_s', ramp, 'must be > 0 s when force_n > 0')
    if goal.start_time_s is not None:
        _finite('header.stamp', goal.start_time_s)
    distance = np.linalg.norm(path - np.asarray(X, dtype=np.float64), axis=1)
    far = int(np.argmax(distance))
    if distance[far] > limits.max_path_distance_m:
        raise TaskGoalError(
            f'path[{far}]', np.round(path[far], 4).tolist(),
            f'is {distance[far]:.3f} m from the end effector, more than '
            f'safety.max_path_distance_m = {limits.max_path_distance_m} m')


@dataclass(frozen=True)
class TaskResult:
    """How a task ended and its figures (the ContactTask result)."""

    code: TaskCode
    message: str
    contact_time_s: float
    peak_force_n: float
    rms_force_error_n: float
    settling_time_s: float


class TaskFigures:
    """Running figures of one task: contact time, peak force, settling and RMS error.

    The RMS force error counts from settling (the force first within ``SETTLED_BAND`` of
    F_d after the ramp has reached it) to release, as the paper's steady-state tracking.
    """

    def __init__(self, force_n: float) -> None:
        self.force_n = force_n
        self.contact_time_s = 0.0
        self.peak_force_n = 0.0
        self.first_contact_s: float | None = None
        self.settled_s: float | None = None
        self._squared_error = 0.0
        self._settled_time = 0.0

    def update(self, t: float, dt: float, f_normal: float, in_contact: bool,
               at_setpoint: bool) -> None:
        """Add one control period of length dt (s) ending at t (s).

        Args:
            t: time (s).
            dt: period (s).
            f_normal: measured force along the normal (N).
            in_contact: force at or above the contact threshold.
            at_setpoint: F_d has reached force_n and is not being released.
        """
        self.peak_force_n = max(self.peak_force_n, f_normal)
        if in_contact:
            self.contact_time_s += dt
            if self.first_contact_s is None:
                self.first_contact_s = t
        if self.force_n <= 0.0 or not at_setpoint:
            return
        error = f_normal - self.force_n
        if self.settled_s is None and abs(error) <= SETTLED_BAND * self.force_n:
            self.settled_s = t
        if self.settled_s is not None:
            self._squared_error += error * error * dt
            self._settled_time += dt

    def result(self, code: TaskCode, message: str) -> TaskResult:
        """The result with these figures."""
        rms = (math.sqrt(self._squared_error / self._settled_time)
               if self._settled_time > 0.0 else math.nan)
        settling = (self.settled_s - self.first_contact_s
                    if self.settled_s is not None and self.first_contact_s is not None
                    else math.nan)
        return TaskResult(code, message, self.contact_time_s, self.peak_force_n, rms,
                          settling)
