"""Task paths: X_d, Ẋ_d and Ẍ_d through timed waypoints, continuous up to the acceleration.

The impedance and hybrid laws (paper eq. 29-31, 37) feed the reference velocity and
acceleration forward, so a path must be twice continuously differentiable: each segment
between two waypoints is the quintic that matches position, velocity and acceleration at
both of its ends (scipy's ``BPoly.from_derivatives``), which makes the path C² through every
waypoint whatever the values chosen there. Where a goal gives no velocities, they are
shape-preserving (scipy's PCHIP derivative: zero where the path turns back or holds, so a
hold between two equal waypoints stays still, with no ringing of a global spline) and the
accelerations zero; the path is at rest at both ends unless a start state is given (a
preempting goal starts from the running reference's velocity and acceleration).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


def _interpolate() -> Any:
    """scipy.interpolate, imported at the first path built, not with this module.

    Its import takes 0.8-1.0 s of CPU (scipy.optimize, scipy.special come with it); the
    allocator and the mission import this module through ``uvms_control.conversions`` and
    ``uvms_control.task_server`` and never build a path before the first simulated step.
    """
    import scipy.interpolate  # type: ignore[import-untyped]

    return scipy.interpolate


def load_interpolation() -> None:
    """Import scipy.interpolate now: the controller does at configure, before its loop runs.

    Imported at the first goal instead, its 0.8-1.0 s of CPU stalled the control loop for
    0.3 s and the goal ended INPUTS_STALE (a launched case1_estimated in CI, 2026-12-04).
    """
    _interpolate()


def shape_preserving_velocities(times: FloatArray, points: FloatArray) -> FloatArray:
    """Waypoint velocities (n, 3) (m/s): PCHIP's derivative inside, zero at both ends.

    Example:
        >>> v = shape_preserving_velocities(np.array([0.0, 1.0, 2.0]),
        ...                                 np.array([[0.0, 0, 0], [1.0, 0, 0], [1.0, 0, 0]]))
        >>> v[:, 0].tolist()
        [0.0, 0.0, 0.0]
    """
    velocities = np.zeros_like(points)
    if len(times) > 2:
        pchip = _interpolate().PchipInterpolator(times, points, axis=0)
        velocities[1:-1] = pchip.derivative()(times[1:-1])
    return velocities


class TaskPath:
    """A C² path through timed waypoints (quintic segments), held at its ends outside them.

    Args:
        times: waypoint times (n,) (s), strictly increasing.
        points: waypoints (n, 3) (m).
        velocities: waypoint velocities (n, 3) (m/s); None: ``shape_preserving_velocities``.
        accelerations: waypoint accelerations (n, 3) (m/s²); None: zero.

    Example:
        >>> path = TaskPath(np.array([0.0, 2.0]), np.array([[0.0, 0, 0], [1.0, 0, 0]]))
        >>> [round(v, 6) for v in path.evaluate_floats(1.0)[:4]]
        [0.5, 0.0, 0.0, 0.9375]
    """

    def __init__(
        self,
        times: FloatArray,
        points: FloatArray,
        velocities: FloatArray | None = None,
        accelerations: FloatArray | None = None,
    ) -> None:
        times = np.asarray(times, dtype=np.float64)
        points = np.asarray(points, dtype=np.float64)
        if velocities is None:
            velocities = shape_preserving_velocities(times, points)
        if accelerations is None:
            accelerations = np.zeros_like(points)
        knots = np.stack((points, velocities, accelerations), axis=1)  # (n, 3 orders, 3 axes)
        interpolate = _interpolate()
        polynomial = interpolate.PPoly.from_bernstein_basis(
            interpolate.BPoly.from_derivatives(times, knots, orders=5))
        self.times: FloatArray = times
        self.points: FloatArray = points
        self.start_time: float = float(times[0])
        self.end_time: float = float(times[-1])
        self._breaks: list[float] = times.tolist()
        # coefficients[i][axis] = (c5, ..., c0) of segment i in powers of (t - t_i), highest first.
        self._coefficient_array: FloatArray = np.transpose(polynomial.c, (1, 2, 0))
        self._coefficients: list[list[list[float]]] = self._coefficient_array.tolist()
        self._end: list[float] = points[-1].tolist()
        self._start: list[float] = [*points[0].tolist(), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]

    @classmethod
    def hold(cls, position: Sequence[float], time: float = 0.0) -> TaskPath:
        """A path that stays at ``position`` (m) from ``time`` (s) on."""
        point = np.asarray(position, dtype=np.float64)
        return cls(np.array([time, time + 1.0]), np.stack((point, point)))

    @classmethod
    def from_state(
        cls,
        time: float,
        state: Sequence[float],
        times: FloatArray,
        points: FloatArray,
        velocities: FloatArray | None = None,
        accelerations: FloatArray | None = None,
    ) -> TaskPath:
        """A path that starts at ``time`` from a reference state [X_d, Ẋ_d, Ẍ_d] (9 floats).

        The first waypoint is replaced by the state's position when its time is ``time``,
        otherwise the state is prepended; the state's velocity and acceleration are kept, so
        a preempting goal continues the running reference without a jump in any of them. A
        goal's first waypoint away from X_d gets a transit before it comes here
        (``contact_task.planned_goal``), so the replaced waypoint is X_d itself.
        """
        start = np.asarray(state, dtype=np.float64).reshape(3, 3)
        times = np.asarray(times, dtype=np.float64)
        points = np.array(points, dtype=np.float64)
        if velocities is not None:
            velocities = np.array(velocities, dtype=np.float64)
        if accelerations is not None:
            accelerations = np.array(accelerations, dtype=np.float64)
        if times[0] > time:
            times = np.concatenate(([time], times))
            points = np.concatenate((start[:1], points))
            if velocities is not None:
                velocities = np.concatenate((start[1:2], velocities))
            if accelerations is not None:
                accelerations = np.concatenate((start[2:3], accelerations))
        points[0] = start[0]
        if velocities is None:
            velocities = shape_preserving_velocities(times, points)
        if accelerations is None:
            accelerations = np.zeros_like(points)
        velocities[0], accelerations[0] = start[1], start[2]
        return cls(times, points, velocities, accelerations)

    @property
    def duration(self) -> float:
        """Time from the first to the last waypoint (s)."""
        return self.end_time - self.start_time

    def progress(self, t: float) -> float:
        """Share of the path's time elapsed at t, in [0, 1]."""
        if self.duration <= 0.0:
            return 1.0
        return min(max((t - self.start_time) / self.duration, 0.0), 1.0)

    def evaluate_floats(self, t: float) -> list[float]:
        """[X_d, Ẋ_d, Ẍ_d] at time t (s) as nine plain floats (m, m/s, m/s²).

        Before the first waypoint the path rests there; after the last it holds the last
        waypoint (at rest when the goal ends at rest, as every goal does).
        """
        if not math.isfinite(t) or t < self.start_time:
            return list(self._start)
        if t >= self.end_time:
            return [*self._end, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        i = bisect.bisect_right(self._breaks, t) - 1
        x = t - self._breaks[i]
        out = [0.0] * 9
        for axis, (c5, c4, c3, c2, c1, c0) in enumerate(self._coefficients[i]):
            out[axis] = ((((c5 * x + c4) * x + c3) * x + c2) * x + c1) * x + c0
            out[3 + axis] = (((5.0 * c5 * x + 4.0 * c4) * x + 3.0 * c3) * x + 2.0 * c2) * x + c1
            out[6 + axis] = ((20.0 * c5 * x + 12.0 * c4) * x + 6.0 * c3) * x + 2.0 * c2
        return out

    def sample(self, per_segment: int = 64) -> tuple[FloatArray, FloatArray, FloatArray]:
        """X_d, Ẋ_d, Ẍ_d at ``per_segment`` + 1 evenly spaced times of every segment.

        Returns:
            Three arrays (segments, per_segment + 1, 3) (m, m/s, m/s²): the checks of a goal's
            interpolated path (speed, acceleration, excursion) read them.

        Example:
            >>> path = TaskPath(np.array([0.0, 2.0]), np.array([[0.0, 0, 0], [1.0, 0, 0]]))
            >>> _, velocity, _ = path.sample(2)
            >>> velocity[0, :, 0].tolist()  # the quintic's peak 1.875 / 2 s at the middle
            [0.0, 0.9375, 0.0]
        """
        widths = np.diff(self.times)
        x = widths[:, np.newaxis] * np.linspace(0.0, 1.0, per_segment + 1)  # (segments, k)
        c = self._coefficient_array[:, :, :, np.newaxis]  # (segments, 3, 6, 1)
        x = x[:, np.newaxis, :]  # (segments, 1, k)
        c5, c4, c3, c2, c1, c0 = (c[:, :, i] for i in range(6))
        position = ((((c5 * x + c4) * x + c3) * x + c2) * x + c1) * x + c0
        velocity = (((5.0 * c5 * x + 4.0 * c4) * x + 3.0 * c3) * x + 2.0 * c2) * x + c1
        acceleration = ((20.0 * c5 * x + 12.0 * c4) * x + 6.0 * c3) * x + 2.0 * c2
        return (np.transpose(position, (0, 2, 1)), np.transpose(velocity, (0, 2, 1)),
                np.transpose(acceleration, (0, 2, 1)))


#: Peak |s̈| of the quintic rest-to-rest time scaling 10σ³ - 15σ⁴ + 6σ⁵ over T = 1 s
#: (at σ = 1/2 ± √3/6): 10/√3.
QUINTIC_PEAK_ACCELERATION = 10.0 / math.sqrt(3.0)
#: Peak |ṡ| of that scaling over T = 1 s (at σ = 1/2).
QUINTIC_PEAK_SPEED = 1.875
#: Margin on the transit's duration, so that its sampled peaks stay strictly under the limits.
_TRANSIT_MARGIN = 1.0 + 1e-6


def transit_duration(distance_m: float, max_speed_m_s: float,
                     max_acceleration_m_s2: float) -> float:
    """Shortest rest-to-rest quintic over distance_m within a speed and acceleration limit (s).

    The quintic peaks at 1.875 d/T in speed and (10/√3) d/T² in acceleration, so
    T = max(1.875 d / v_max, √(5.774 d / a_max)).

    Example:
        >>> round(transit_duration(0.26, 0.5, 1.0), 3)
        1.225
    """
    if distance_m <= 0.0:
        return 0.0
    return _TRANSIT_MARGIN * max(QUINTIC_PEAK_SPEED * distance_m / max_speed_m_s,
                                 math.sqrt(QUINTIC_PEAK_ACCELERATION * distance_m
                                           / max_acceleration_m_s2))


def with_transit(
    start: Sequence[float],
    times: FloatArray,
    points: FloatArray,
    velocities: FloatArray | None,
    accelerations: FloatArray | None,
    transit_s: float,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Waypoints with a rest-to-rest transit from ``start`` to points[0] put before them.

    The transit takes transit_s (s) from time 0; the waypoints follow with their times shifted
    by transit_s and their own velocities (shape-preserving ones when None: zero at both ends
    of the path, as without the transit) and accelerations. The path rests at points[0] from
    the transit's end until the path's own time of points[0] (its times[0] after the transit).

    Example:
        >>> t, x, v, _ = with_transit([0.0, 0, 0], np.array([0.0, 2.0]),
        ...                           np.array([[0.2, 0, 0], [0.3, 0, 0]]), None, None, 1.0)
        >>> t.tolist(), x[:, 0].tolist(), v[:, 0].tolist()
        ([0.0, 1.0, 3.0], [0.0, 0.2, 0.3], [0.0, 0.0, 0.0])

    Returns:
        times (n + 1,) (s), points (n + 1, 3) (m), velocities and accelerations (n + 1, 3).
    """
    times = np.asarray(times, dtype=np.float64)
    points = np.asarray(points, dtype=np.float64)
    if velocities is None:
        velocities = shape_preserving_velocities(times, points)
    velocities = np.array(velocities, dtype=np.float64)
    accelerations = (np.zeros_like(points) if accelerations is None
                     else np.array(accelerations, dtype=np.float64))
    velocities[0] = accelerations[0] = 0.0  # the transit ends at rest
    origin = np.asarray(start, dtype=np.float64).reshape(1, 3)
    rest = np.zeros((1, 3))
    if times[0] > 0.0:  # at rest on points[0] from the transit's end to the path's times[0]
        times = np.concatenate(([0.0], times))
        points = np.concatenate((points[:1], points))
        velocities = np.concatenate((rest, velocities))
        accelerations = np.concatenate((rest, accelerations))
    return (np.concatenate(([0.0], transit_s + times)), np.concatenate((origin, points)),
            np.concatenate((rest, velocities)), np.concatenate((rest, accelerations)))
