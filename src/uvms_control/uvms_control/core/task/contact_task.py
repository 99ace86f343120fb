"""Contact tasks: the goal of the ContactTask action, its checks, limits and result figures.

A contact task moves the end effector along a timed path in map_ned and, wherever it meets
a surface, lets the fuzzy switch hand over from impedance to force control (paper sec. 4.3)
and presses with F_d along the normal (sec. 5.2). This module holds what does not depend on
ROS: the goal as plain arrays, its validation (every refusal names the field and value), the
safety limits, and the samples the result's figures are computed from (``force_figures``).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from uvms_control.core.law.task_goal import ContactTaskGoal
from uvms_control.core.law.task_path import (
    QUINTIC_PEAK_SPEED,
    TaskPath,
    transit_duration,
    with_transit,
)
from uvms_control.core.task.force_figures import force_figures

FloatArray = npt.NDArray[np.float64]

__all__ = ['QUINTIC_PEAK_SPEED', 'TRANSIT_TOLERANCE_M', 'ContactTaskGoal', 'SafetyLimits',
           'TaskCode', 'TaskFigures', 'TaskGoalError', 'TaskResult', 'planned_goal',
           'validate_goal']

#: A goal's first waypoint farther than this from the reference's X_d gets a transit (m).
TRANSIT_TOLERANCE_M = 1e-3


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
    INPUTS_STALE = 8
    ACTUATION_LOST = 9
    FORCE_NOT_SETTLED = 10


class TaskGoalError(ValueError):
    """A goal the controller refuses; the message names the field and its value."""

    def __init__(self, field: str, value: object, expected: str) -> None:
        self.field = field
        super().__init__(f'{field} = {value}: {expected}')


@dataclass(frozen=True)
class SafetyLimits:
    """Limits the controller enforces in every state, goal or no goal (parameters ``safety.*``).

    Attributes:
        max_contact_force_n: largest measured contact force |F_e| (N), whatever its direction;
            also caps force_n.
        sensor_range_n: wrist-sensor full scale per axis (N): a reading at 99.9 % of it is
            taken as saturated.
        max_position_error_m: largest |X_d - X| (m).
        max_path_distance_m: largest distance of a goal's interpolated path, and of a
            streamed target, from X at acceptance (m).
        retreat_m: back-off along -normal after a cancel or a breach (m).
        retreat_time_s: time of that back-off and of the force ramp-down with it (s).
        max_target_speed_m_s: speed limit of the streamed hold target (m/s).
        max_goal_delay_s: how far ahead of the controller clock a goal's stamp may be (s).
        max_path_speed_m_s: largest |Ẋ_d| of a goal's interpolated path (m/s).
        max_path_acceleration_m_s2: largest |Ẍ_d| of a goal's interpolated path (m/s²).
        min_ramp_s: shortest force ramp (a goal's force_ramp_s) and retreat_time_s (s).

    Raises:
        ValueError: retreat_time_s shorter than min_ramp_s, or a back-off (retreat_m over
            retreat_time_s, peak speed 1.875 retreat_m / retreat_time_s on its quintic)
            faster than max_path_speed_m_s.
    """

    max_contact_force_n: float = 400.0
    sensor_range_n: float = 400.0
    max_position_error_m: float = 0.2
    max_path_distance_m: float = 1.5
    retreat_m: float = 0.05
    retreat_time_s: float = 1.0
    max_target_speed_m_s: float = 0.1
    max_goal_delay_s: float = 60.0
    max_path_speed_m_s: float = 0.5
    max_path_acceleration_m_s2: float = 1.0
    min_ramp_s: float = 0.1

    def __post_init__(self) -> None:
        if self.retreat_time_s < self.min_ramp_s:
            raise ValueError(f'safety.retreat_time_s = {self.retreat_time_s} s must be at least '
                             f'safety.min_ramp_s = {self.min_ramp_s} s')
        speed = QUINTIC_PEAK_SPEED * self.retreat_m / self.retreat_time_s
        if speed > self.max_path_speed_m_s:
            raise ValueError(f'safety.retreat_m = {self.retreat_m} m over safety.retreat_time_s '
                             f'= {self.retreat_time_s} s peaks at {speed:.3g} m/s, more than '
                             f'safety.max_path_speed_m_s = {self.max_path_speed_m_s} m/s')


def _finite(field: str, values: npt.ArrayLike) -> FloatArray:
    array = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(array)):
        raise TaskGoalError(field, np.round(array, 6).tolist(), 'must be finite (no NaN or Inf)')
    return array


def planned_goal(goal: ContactTaskGoal, start: npt.ArrayLike | None,
                 limits: SafetyLimits) -> tuple[ContactTaskGoal, float]:
    """The goal as it will run from the reference's X_d = ``start`` at rest, and its transit (s).

    A first waypoint farther than ``TRANSIT_TOLERANCE_M`` from start is reached first by a
    transit: a straight rest-to-rest quintic from start to path[0] that peaks at
    ``limits.max_path_speed_m_s`` or ``limits.max_path_acceleration_m_s2``, whichever it
    reaches first (``task_path.transit_duration``); the goal's own path follows, its times
    shifted by the transit's duration, from rest at path[0]. Closer (or start None), the goal
    is returned unchanged with 0.0: its path starts from X_d, as it always did.

    Example:
        >>> goal = ContactTaskGoal(np.array([[0.1, 0, 0], [0.2, 0, 0]]), np.array([0.0, 2.0]),
        ...                        None, None, np.array([1.0, 0, 0]), 0.0, 1.0)
        >>> planned, transit_s = planned_goal(goal, [0.0, 0.0, 0.0], SafetyLimits())
        >>> round(transit_s, 3), planned.times.round(3).tolist()
        (0.76, [0.0, 0.76, 2.76])
    """
    if start is None:
        return goal, 0.0
    first = np.asarray(goal.path, dtype=np.float64)[0]
    distance = float(np.linalg.norm(first - np.asarray(start, dtype=np.float64)))
    if not distance > TRANSIT_TOLERANCE_M:
        return goal, 0.0
    transit_s = transit_duration(distance, limits.max_path_speed_m_s,
                                 limits.max_path_acceleration_m_s2)
    times, path, velocities, accelerations = with_transit(
        np.asarray(start, dtype=np.float64).tolist(), goal.times, goal.path, goal.velocities,
        goal.accelerations, transit_s)
    return replace(goal, path=path, times=times, velocities=velocities,
                   accelerations=accelerations), transit_s


def validate_goal(
    goal: ContactTaskGoal,
    X: FloatArray | None,
    limits: SafetyLimits,
    contact_threshold_n: float,
    now_s: float | None = None,
    start: FloatArray | None = None,
) -> None:
    """Check a goal before it may replace the running one.

    Args:
        goal: the goal.
        X: end-effector position at acceptance (m), map_ned; None (no state yet): only the
            checks that need no state (every field, the path from path[0] at rest).
        limits: the safety limits.
        contact_threshold_n: force that counts as contact (N); a non-zero force_n must
            exceed it.
        now_s: the controller clock (s): the stamp may be at most
            ``limits.max_goal_delay_s`` ahead of it; None: not checked.
        start: the reference position the path will start from, at rest (m); None: X. The
            path is checked as it will run from there, its transit included (``planned_goal``).

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
        if np.any(array[-1] != 0.0):
            raise TaskGoalError(f'{name}[{len(array) - 1}]', array[-1].tolist(),
                                'must be zero at the last waypoint (the path ends at rest)')
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
    if force > 0.0 and ramp < limits.min_ramp_s:
        raise TaskGoalError('force_ramp_s', ramp, f'must be at least safety.min_ramp_s = '
                                                  f'{limits.min_ramp_s} s when force_n > 0')
    if goal.start_time_s is not None:
        stamp = float(_finite('header.stamp', goal.start_time_s))
        if now_s is not None and stamp - now_s > limits.max_goal_delay_s:
            raise TaskGoalError(
                'header.stamp', f'{stamp:.3f} s',
                f'is {stamp - now_s:.3f} s ahead of the controller clock ({now_s:.3f} s), '
                f'more than safety.max_goal_delay_s = {limits.max_goal_delay_s} s')
    if X is not None:
        X = np.asarray(X, dtype=np.float64)
        distance = np.linalg.norm(path - X, axis=1)
        far = int(np.argmax(distance))
        if distance[far] > limits.max_path_distance_m:
            raise TaskGoalError(
                f'path[{far}]', np.round(path[far], 4).tolist(),
                f'is {distance[far]:.3f} m from the end effector, more than '
                f'safety.max_path_distance_m = {limits.max_path_distance_m} m')
        start = X if start is None else start
    _check_interpolated_path(goal, X, path[0] if start is None else start, limits)


def _check_interpolated_path(goal: ContactTaskGoal, X: FloatArray | None, start: npt.ArrayLike,
                             limits: SafetyLimits) -> None:
    """The path as it will run (from ``start`` at rest, user velocities included) within limits.

    Speed, acceleration and distance from X (unless None) are sampled 64 times per quintic
    segment, the transit to path[0] included (``planned_goal``); a violation names the
    waypoint that ends the segment (path[0] for the transit and a hold there).
    """
    planned, _ = planned_goal(goal, start, limits)
    state = [*np.asarray(start, dtype=np.float64).tolist(), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    path = TaskPath.from_state(0.0, state, np.asarray(planned.times, dtype=np.float64),
                               planned.path, planned.velocities, planned.accelerations)
    positions, velocities, accelerations = path.sample()
    # Segment s ends at the planned waypoint s (+1 when the start replaces waypoint 0); the
    # planned goal has the goal's waypoints after the transit's ones.
    shift = (0 if planned.times[0] > 0.0 else 1) - (len(planned.times) - len(goal.times))
    distances = (np.zeros(positions.shape[:2]) if X is None
                 else np.linalg.norm(positions - X, axis=2))
    checks = (
        (np.linalg.norm(velocities, axis=2), limits.max_path_speed_m_s, 'm/s',
         'reaches a speed of', 'safety.max_path_speed_m_s', 'time_from_start_s'),
        (np.linalg.norm(accelerations, axis=2), limits.max_path_acceleration_m_s2, 'm/s²',
         'reaches an acceleration of', 'safety.max_path_acceleration_m_s2',
         'time_from_start_s'),
        (distances, limits.max_path_distance_m, 'm',
         'swings away from the end effector by', 'safety.max_path_distance_m', 'path'),
    )
    for values, limit, unit, what, name, field in checks:
        segment, _ = np.unravel_index(int(np.argmax(values)), values.shape)
        peak = float(values[segment].max())
        if peak > limit:
            k = max(int(segment) + shift, 0)
            value = (float(goal.times[k]) if field == 'time_from_start_s'
                     else np.round(goal.path[k], 4).tolist())
            raise TaskGoalError(
                f'{field}[{k}]', value,
                f'the interpolated path (user velocities included) {what} {peak:.3g} {unit} '
                f'on its way to path[{k}], more than {name} = {limit} {unit}')


@dataclass(frozen=True)
class TaskResult:
    """How a task ended and its figures (the ContactTask result).

    ``start_s`` and ``end_s`` are the times of the first and last control step the figures
    were computed from (NaN for a task that never ran a step): a recording's task record
    carries them, so that `uvms report` computes the same figures from the same samples.
    ``transit_s`` is the duration of the transit put before the goal's path (s; 0: none).
    """

    code: TaskCode
    message: str
    contact_time_s: float
    peak_force_n: float
    rms_force_error_n: float
    settling_time_s: float
    start_s: float = math.nan
    end_s: float = math.nan
    transit_s: float = 0.0


class TaskFigures:
    """Samples of one task (t, force along the normal, contact) and their figures at the end.

    Each control step adds one sample to preallocated arrays, no allocation per step; they
    double when full (at 20, 40, 80 s ... of a 500 Hz task: ten minutes hold 300 000 samples,
    about 5 MB). ``result``
    computes contact time, peak, settling time and RMS error with ``force_figures``, the
    function `uvms report` uses, against F_d = force_n: settling runs from first contact until
    the force stays within 5 % of force_n (during the ramp too), the RMS error from there to
    the release (docs/figures.md#metrics).
    """

    #: Samples held before the first growth: 20 s at 500 Hz.
    INITIAL_CAPACITY = 10_000

    def __init__(self, force_n: float) -> None:
        self.force_n = force_n
        self.first_contact_s: float | None = None
        self._t = np.empty(self.INITIAL_CAPACITY)
        self._force = np.empty(self.INITIAL_CAPACITY)
        self._contact = np.empty(self.INITIAL_CAPACITY, dtype=bool)
        self._count = 0

    def update(self, t: float, dt: float, f_normal: float, in_contact: bool,
               at_setpoint: bool) -> None:
        """Add the sample of one control step at t (s).

        Args:
            t: time (s).
            dt: period (s); unused: durations come from the sample times.
            f_normal: measured force along the normal (N).
            in_contact: force at or above the contact threshold.
            at_setpoint: F_d has reached force_n; unused: settling is measured against
                force_n from first contact, ramp or not.
        """
        del dt, at_setpoint
        k = self._count
        if k == self._t.size:
            self._grow()
        self._t[k] = t
        self._force[k] = f_normal
        self._contact[k] = in_contact
        self._count = k + 1
        if in_contact and self.first_contact_s is None:
            self.first_contact_s = t

    def _grow(self) -> None:
        size = 2 * self._t.size
        self._t = np.resize(self._t, size)
        self._force = np.resize(self._force, size)
        self._contact = np.resize(self._contact, size)

    def result(self, code: TaskCode, message: str) -> TaskResult:
        """The result with the figures of the samples so far."""
        k = self._count
        figures = force_figures(self._t[:k], self._force[:k], self._contact[:k],
                                self.force_n if self.force_n > 0.0 else None)
        return TaskResult(
            code, message,
            contact_time_s=figures.contact_duration or 0.0,
            peak_force_n=0.0 if figures.peak_force is None else figures.peak_force,
            rms_force_error_n=_nan_if_none(figures.force_rms_error),
            settling_time_s=_nan_if_none(figures.settling_time),
            start_s=float(self._t[0]) if k else math.nan,
            end_s=float(self._t[k - 1]) if k else math.nan,
        )


def _nan_if_none(value: float | None) -> float:
    return math.nan if value is None else value
