"""Tests of the C² task paths through timed waypoints (core/task_path.py)."""

from __future__ import annotations

import numpy as np
import pytest
from uvms_control.core.law.reference import HalfCircleReference
from uvms_control.core.law.task_path import TaskPath

H = 1e-4  # finite-difference step (s)

TIMES = np.array([0.0, 0.7, 1.5, 2.0, 3.4])
POINTS = np.array([
    [1.70, 0.00, 0.10],
    [1.74, 0.02, 0.12],
    [1.76, -0.01, 0.18],
    [1.71, 0.03, 0.21],
    [1.68, 0.00, 0.15],
])  # fmt: skip
VELOCITIES = np.array([
    [0.0, 0.0, 0.0],
    [0.05, -0.02, 0.06],
    [-0.04, 0.01, 0.08],
    [-0.03, 0.02, -0.02],
    [0.0, 0.0, 0.0],
])  # fmt: skip
ACCELERATIONS = np.array([
    [0.0, 0.0, 0.0],
    [0.1, 0.05, -0.2],
    [-0.3, 0.0, 0.1],
    [0.2, -0.1, 0.05],
    [0.0, 0.0, 0.0],
])  # fmt: skip

PATHS = {
    'chosen velocities': lambda: TaskPath(TIMES, POINTS),
    'given derivatives': lambda: TaskPath(TIMES, POINTS, VELOCITIES, ACCELERATIONS),
}


def state(path: TaskPath, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """X_d, Ẋ_d, Ẍ_d of the path at t."""
    values = np.array(path.evaluate_floats(t)).reshape(3, 3)
    return values[0], values[1], values[2]


def left_derivative(f, t: float) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Second-order backward difference of f at t (uses only f before t and at t)."""
    return (3.0 * f(t) - 4.0 * f(t - H) + f(t - 2.0 * H)) / (2.0 * H)  # type: ignore[no-any-return]


def right_derivative(f, t: float) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Second-order forward difference of f at t (uses only f at t and after t)."""
    return (-3.0 * f(t) + 4.0 * f(t + H) - f(t + 2.0 * H)) / (2.0 * H)  # type: ignore[no-any-return]


@pytest.mark.parametrize('kind', list(PATHS))
@pytest.mark.parametrize('k', [1, 2, 3])
def test_path_is_twice_continuously_differentiable_at_every_waypoint(kind: str, k: int) -> None:
    """X_d, Ẋ_d, Ẍ_d have no jump at a waypoint, and Ẋ_d, Ẍ_d are the derivatives either side."""
    path = PATHS[kind]()
    t = float(TIMES[k])
    x, v, a = state(path, t)
    # 1 ns either side: a continuous value moves by at most 1e-9 s times its rate (< 1e-6).
    before, after = state(path, t - 1e-9), state(path, t + 1e-9)
    for value, left, right in zip((x, v, a), before, after, strict=True):
        np.testing.assert_allclose(left, value, atol=1e-6)
        np.testing.assert_allclose(right, value, atol=1e-6)

    def position(s: float) -> np.ndarray:
        return state(path, s)[0]

    def velocity(s: float) -> np.ndarray:
        return state(path, s)[1]

    for f, derivative, atol in ((position, v, 1e-7), (velocity, a, 1e-6)):
        np.testing.assert_allclose(left_derivative(f, t), derivative, atol=atol)
        np.testing.assert_allclose(right_derivative(f, t), derivative, atol=atol)


@pytest.mark.parametrize('t', [0.3, 1.1, 1.77, 2.9])
def test_velocity_and_acceleration_are_derivatives_inside_segments(t: float) -> None:
    """Ẋ_d and Ẍ_d match central differences of X_d and Ẋ_d between waypoints."""
    path = TaskPath(TIMES, POINTS, VELOCITIES, ACCELERATIONS)
    _, v, a = state(path, t)
    np.testing.assert_allclose(
        (state(path, t + H)[0] - state(path, t - H)[0]) / (2.0 * H), v, atol=1e-8
    )
    np.testing.assert_allclose(
        (state(path, t + H)[1] - state(path, t - H)[1]) / (2.0 * H), a, atol=1e-7
    )


def test_path_passes_through_its_waypoints_with_the_given_derivatives() -> None:
    """At each waypoint time X_d, Ẋ_d, Ẍ_d are the goal's position, velocity and acceleration."""
    path = TaskPath(TIMES, POINTS, VELOCITIES, ACCELERATIONS)
    for k in range(len(TIMES) - 1):
        x, v, a = state(path, float(TIMES[k]))
        np.testing.assert_allclose(x, POINTS[k], atol=1e-12)
        np.testing.assert_allclose(v, VELOCITIES[k], atol=1e-12)
        np.testing.assert_allclose(a, ACCELERATIONS[k], atol=1e-11)


@pytest.mark.parametrize('t', [TIMES[0] - 5.0, TIMES[0], TIMES[-1], TIMES[-1] + 5.0])
def test_path_is_at_rest_at_both_ends(t: float) -> None:
    """Without given derivatives the path starts and ends at rest and holds its end points."""
    path = TaskPath(TIMES, POINTS)
    x, v, a = state(path, t)
    np.testing.assert_allclose(x, POINTS[0] if t <= TIMES[0] else POINTS[-1], atol=1e-12)
    np.testing.assert_allclose(v, 0.0, atol=1e-12)
    np.testing.assert_allclose(a, 0.0, atol=1e-12)


@pytest.mark.parametrize('t', np.linspace(1.0, 2.5, 13).tolist())
def test_hold_between_equal_waypoints_stays_still(t: float) -> None:
    """Two equal waypoints in a row make the path wait there at rest (no overshoot or ringing)."""
    times = np.array([0.0, 1.0, 2.5, 4.0])
    points = np.array([[1.7, 0.0, 0.1], [1.8, 0.05, 0.1], [1.8, 0.05, 0.1], [1.7, 0.0, 0.3]])
    x, v, a = state(TaskPath(times, points), t)
    np.testing.assert_allclose(x, points[1], atol=1e-12)
    np.testing.assert_allclose(v, 0.0, atol=1e-12)
    np.testing.assert_allclose(a, 0.0, atol=1e-12)


@pytest.mark.parametrize('first_time', [5.0, 6.0])
def test_from_state_starts_from_the_running_state(first_time: float) -> None:
    """A path from a running state starts at its X_d, Ẋ_d and Ẍ_d, then reaches the waypoints.

    first_time 5.0: the state replaces the first waypoint; 6.0: it is prepended at t = 5 s.
    """
    running = [1.72, 0.01, 0.14, 0.03, -0.02, 0.05, 0.2, 0.1, -0.3]
    times = first_time + np.array([0.0, 1.0, 2.0])
    points = np.array([[1.75, 0.0, 0.15], [1.8, 0.0, 0.2], [1.8, 0.0, 0.25]])
    path = TaskPath.from_state(5.0, running, times, points)
    x, v, a = state(path, 5.0)
    np.testing.assert_allclose(x, running[0:3], atol=1e-12)
    np.testing.assert_allclose(v, running[3:6], atol=1e-12)
    np.testing.assert_allclose(a, running[6:9], atol=1e-11)

    def position(s: float) -> np.ndarray:
        return state(path, s)[0]

    def velocity(s: float) -> np.ndarray:
        return state(path, s)[1]

    np.testing.assert_allclose(right_derivative(position, 5.0), running[3:6], atol=1e-7)
    np.testing.assert_allclose(right_derivative(velocity, 5.0), running[6:9], atol=1e-6)
    np.testing.assert_allclose(state(path, float(times[1]))[0], points[1], atol=1e-12)
    np.testing.assert_allclose(state(path, float(times[-1]))[0], points[-1], atol=1e-12)


def test_half_circle_from_81_samples_is_reproduced() -> None:
    """The paper's half circle, 81 samples with exact derivatives, is the path within 1e-9 m."""
    x0 = [1.7, 0.0, 0.1]
    reference = HalfCircleReference(radius=0.1, duration=16.0, start_delay=0.0)
    times = np.linspace(0.0, 16.0, 81)
    samples = np.array([reference.evaluate_floats(float(t), x0) for t in times])
    path = TaskPath(times, samples[:, 0:3], samples[:, 3:6], samples[:, 6:9])
    for t in np.linspace(0.0, 16.0, 4001)[1:-1] + 0.013:  # mostly between the samples
        exact = np.array(reference.evaluate_floats(float(t), x0))
        np.testing.assert_allclose(path.evaluate_floats(float(t))[0:3], exact[0:3], atol=1e-9)
