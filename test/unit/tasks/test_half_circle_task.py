"""The half-circle task: waypoints on the paper's circle with the reference's exact derivatives."""

from __future__ import annotations

import numpy as np
import pytest
from uvms_control.core.law.reference import HalfCircleReference
from uvms_tasks.task_file import HalfCircle, parse_task_document

X0S = [(1.6, 0.0, 0.2), (0.0, 0.0, 0.0), (-2.0, 3.5, 10.0)]


def expanded(x0: tuple[float, float, float], **half_circle: object) -> tuple[np.ndarray, ...]:
    """Times, path, velocity and acceleration of a half-circle task from x0."""
    (task,) = parse_task_document(
        {'half_circle': {'duration_s': 20, **half_circle}, 'normal': [1, 0, 0]}, 'test.yaml')
    done = task.expanded(x0)
    assert not done.needs_start and done.velocity is not None and done.acceleration is not None
    return done.time_from_start_s, done.path, done.velocity, done.acceleration


@pytest.mark.parametrize('x0', X0S)
def test_waypoints_lie_on_the_half_circle_from_x0(x0: tuple[float, float, float]) -> None:
    """|X - c| = r with c = X0 + r d, in the plane of n and d, from X0 to X0 + 2 r d."""
    _, path, _, _ = expanded(x0, radius_m=0.1)
    x0_, n, d = np.array(x0), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    center = x0_ + 0.1 * d
    np.testing.assert_allclose(np.linalg.norm(path - center, axis=1), 0.1, atol=1e-12)
    np.testing.assert_allclose((path - x0_) @ np.cross(n, d), 0.0, atol=1e-12)
    assert np.all((path - x0_) @ n >= -1e-12)  # toward the wall, never behind X0
    np.testing.assert_allclose(path[0], x0_, atol=1e-12)
    np.testing.assert_allclose(path[-1], x0_ + 0.2 * d, atol=1e-12)
    np.testing.assert_allclose(path[len(path) // 2], x0_ + 0.1 * n + 0.1 * d, atol=1e-12)


@pytest.mark.parametrize('x0', X0S)
def test_derivatives_are_the_references_exact_ones(x0: tuple[float, float, float]) -> None:
    """X_d, X_d_dot and X_d_ddot at each waypoint time are HalfCircleReference's."""
    times, path, velocity, acceleration = expanded(x0, radius_m=0.15, points=21)
    reference = HalfCircleReference(radius=0.15, duration=20.0, start_delay=0.0)
    for k, t in enumerate(times):
        x_d, x_d_dot, x_d_ddot = reference.evaluate(float(t), np.array(x0))
        np.testing.assert_allclose(path[k], x_d, atol=1e-15)
        np.testing.assert_allclose(velocity[k], x_d_dot, atol=1e-15)
        np.testing.assert_allclose(acceleration[k], x_d_ddot, atol=1e-15)


def test_velocity_is_the_derivative_of_the_waypoints() -> None:
    """An independent check: finite differences of dense waypoints give the velocities."""
    times, path, velocity, acceleration = expanded((1.6, 0.0, 0.2), points=2001)
    np.testing.assert_allclose(np.gradient(path, times, axis=0)[1:-1], velocity[1:-1],
                               atol=1e-6)
    np.testing.assert_allclose(np.gradient(velocity, times, axis=0)[1:-1],
                               acceleration[1:-1], atol=1e-6)


def test_half_circle_starts_and_ends_at_rest() -> None:
    """Zero velocity and acceleration at both ends (the paper's rest-to-rest reference)."""
    times, _, velocity, acceleration = expanded((0.0, 0.0, 0.0))
    assert times[0] == 0.0 and times[-1] == 20.0 and len(times) == 81
    for end in (0, -1):
        np.testing.assert_allclose(velocity[end], 0.0, atol=1e-15)
        np.testing.assert_allclose(acceleration[end], 0.0, atol=1e-15)


def test_toward_defaults_to_the_normal_and_can_differ() -> None:
    """The circle moves toward the task's normal unless ``toward`` is given."""
    along_normal = HalfCircle(duration_s=4.0, points=3).sample([0, 0, 0], [0.0, 2.0, 0.0])[1]
    np.testing.assert_allclose(along_normal[1], [0.0, 0.1, 0.1], atol=1e-12)
    other = HalfCircle(duration_s=4.0, points=3, toward=(1.0, 0.0, 0.0))
    np.testing.assert_allclose(other.sample([0, 0, 0], [0.0, 2.0, 0.0])[1][1], [0.1, 0.0, 0.1],
                               atol=1e-12)


def test_a_path_task_is_not_changed_by_expansion() -> None:
    """Explicit waypoints do not depend on X0."""
    (task,) = parse_task_document(
        {'path': [[0, 0, 0], [1, 0, 0]], 'time_from_start_s': [0, 1], 'normal': [1, 0, 0]},
        'test.yaml')
    assert task.expanded((5.0, 5.0, 5.0)) is task
