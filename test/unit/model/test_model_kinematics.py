"""Kinematics of uvms_model: J1, J2, B (paper sec. 3.2), EE Jacobian (eq. 22, 23), IK, frames."""

from __future__ import annotations

import numpy as np
import pytest
from model_oracles import random_state
from scipy.spatial.transform import Rotation
from uvms_model.kinematics import (
    euler_from_rotation,
    euler_rate_matrix,
    euler_rate_matrix_inverse,
    rot_ned_from_body,
    skew,
)

from uvms_model import SingularAttitudeError, UnreachableError, UvmsModel

ATTITUDES = [(0.0, 0.0, 0.0), (0.3, -0.2, 1.4), (-1.0, 0.5, -3.0), (2.9, 1.3, 0.7)]
STATES = range(12)
MODEL = UvmsModel()
RECOMMENDED_Q_ARM = np.array([0.0, np.arctan2(4.0, 3.0), -np.pi / 2])


@pytest.mark.parametrize('rpy', ATTITUDES)
def test_rotation_is_orthonormal(rpy: tuple[float, float, float]) -> None:
    """R^T R = I and det R = +1 for any non-singular attitude."""
    rot = rot_ned_from_body(*rpy)
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize('rpy', ATTITUDES)
def test_j1_is_the_zyx_euler_rotation_of_scipy(rpy: tuple[float, float, float]) -> None:
    """J1 of sec. 3.2 equals scipy's intrinsic Z-Y-X rotation (yaw, pitch, roll)."""
    phi, theta, psi = rpy
    expected = Rotation.from_euler('ZYX', [psi, theta, phi]).as_matrix()
    np.testing.assert_allclose(rot_ned_from_body(*rpy), expected, atol=1e-12)


@pytest.mark.parametrize('rpy', ATTITUDES)
def test_j2_maps_body_rates_to_euler_rates(rpy: tuple[float, float, float]) -> None:
    """Moving the Euler angles by J2 omega dt rotates the body by omega dt (R_dot = R [omega]x)."""
    omega = np.array([0.4, -0.7, 1.1])
    dt = 1e-6
    eta = np.array(rpy)
    step = euler_rate_matrix(eta[0], eta[1]) @ omega * dt
    rot_dot_fd = (rot_ned_from_body(*(eta + step)) - rot_ned_from_body(*(eta - step))) / (2 * dt)
    np.testing.assert_allclose(rot_dot_fd, rot_ned_from_body(*eta) @ skew(omega), atol=1e-8)


@pytest.mark.parametrize('rpy', ATTITUDES)
def test_j2_inverse_is_the_inverse_of_j2(rpy: tuple[float, float, float]) -> None:
    """J2^-1 J2 = I away from pitch +-90 deg."""
    product = euler_rate_matrix_inverse(rpy[0], rpy[1]) @ euler_rate_matrix(rpy[0], rpy[1])
    np.testing.assert_allclose(product, np.eye(3), atol=1e-12)


@pytest.mark.parametrize('pitch', [np.pi / 2, -np.pi / 2, np.pi / 2 - 1e-5])
def test_pitch_at_ninety_degrees_raises_singular_attitude(pitch: float) -> None:
    """B(q) and a step at pitch +-90 deg raise SingularAttitudeError naming the pitch."""
    q = np.zeros(9)
    q[4] = pitch
    with pytest.raises(SingularAttitudeError, match='pitch'):
        MODEL.velocity_transform(q)
    with pytest.raises(SingularAttitudeError, match='pitch'):
        MODEL.step(q, np.zeros(9), np.zeros(9), None, 1e-3)


@pytest.mark.parametrize('seed', STATES)
def test_ee_jacobian_is_the_derivative_of_forward_kinematics(seed: int) -> None:
    """J (eq. 22) equals central differences of X(q), column by column."""
    q, _ = random_state(seed)
    h = 1e-6
    columns = [
        (MODEL.ee_position(q + h * e) - MODEL.ee_position(q - h * e)) / (2 * h) for e in np.eye(9)
    ]
    np.testing.assert_allclose(MODEL.ee_jacobian(q), np.array(columns).T, atol=1e-8)


@pytest.mark.parametrize('seed', STATES)
def test_ee_jacobian_dot_qdot_is_the_derivative_of_j_along_qdot(seed: int) -> None:
    """J_dot q_dot (eq. 23) equals (J(q + h q_dot) - J(q - h q_dot)) q_dot / 2h."""
    q, q_dot = random_state(seed)
    h = 1e-6
    jac_dot = (MODEL.ee_jacobian(q + h * q_dot) - MODEL.ee_jacobian(q - h * q_dot)) / (2 * h)
    np.testing.assert_allclose(MODEL.ee_jacobian_dot_qdot(q, q_dot), jac_dot @ q_dot, atol=1e-7)


@pytest.mark.parametrize('seed', STATES)
def test_ee_velocity_from_quasi_velocities_matches_j_times_b(seed: int) -> None:
    """The EE velocity after a tiny step of q_dot = B w is J B w."""
    q, w = random_state(seed)
    q_dot = MODEL.velocity_transform(q) @ w
    h = 1e-6
    x_dot_fd = (MODEL.ee_position(q + h * q_dot) - MODEL.ee_position(q - h * q_dot)) / (2 * h)
    np.testing.assert_allclose(MODEL.ee_jacobian(q) @ q_dot, x_dot_fd, atol=1e-7)


@pytest.mark.parametrize('seed', STATES)
def test_frame_poses_place_ee_link_at_ee_position(seed: int) -> None:
    """ee_link and ft_sensor_link sit at X(q) with rot_ned_from_ee; all rotations orthonormal."""
    q, _ = random_state(seed)
    poses = MODEL.frame_poses(q)
    assert tuple(poses) == MODEL.frame_names == (
        'base_link_frd', 'link_1', 'link_2', 'link_3', 'ee_link', 'ft_sensor_link')
    np.testing.assert_allclose(poses['ee_link'][0], MODEL.ee_position(q), atol=1e-12)
    np.testing.assert_allclose(poses['ft_sensor_link'][1], MODEL.ee_rotation(q), atol=1e-12)
    for _, rot in poses.values():
        np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)


def test_links_point_along_body_x_at_zero_configuration() -> None:
    """At q = 0 the arm is straight ahead: EE at mount + 1.5 m along base_link_frd x."""
    np.testing.assert_allclose(MODEL.ee_position(np.zeros(9)), [2.0, 0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(
    'target', [[1.70, 0.0, -0.10], [1.80, 0.0, 0.0], [1.70, 0.0, 0.10], [1.75, 0.05, 0.02]]
)
def test_inverse_kinematics_reaches_the_paper_half_circle(target: list[float]) -> None:
    """IK puts the EE on the half circle of radius 0.1 m at x = 1.70..1.80 m (vehicle at 0)."""
    q_arm = MODEL.joint_positions_for_ee_position(np.zeros(6), target, RECOMMENDED_Q_ARM)
    np.testing.assert_allclose(
        MODEL.ee_position(np.concatenate((np.zeros(6), q_arm))), target, atol=1e-9
    )


def test_recommended_initial_configuration_puts_ee_at_point_a() -> None:
    """q_arm = (0, atan(4/3), -pi/2) puts the EE at A = (1.70, 0, -0.10) m (docs/model.md)."""
    q = np.concatenate((np.zeros(6), RECOMMENDED_Q_ARM))
    np.testing.assert_allclose(MODEL.ee_position(q), [1.70, 0.0, -0.10], atol=1e-12)


@pytest.mark.parametrize('angle', np.linspace(0.0, np.pi, 7))
def test_arm_jacobian_is_well_conditioned_on_the_half_circle(angle: float) -> None:
    """Along the paper's half circle the arm's 3x3 Jacobian keeps sigma_min > 0.2 m."""
    target = np.array([1.70 + 0.1 * np.sin(angle), 0.0, -0.1 * np.cos(angle)])
    q_arm = MODEL.joint_positions_for_ee_position(np.zeros(6), target, RECOMMENDED_Q_ARM)
    jac = MODEL.ee_jacobian(np.concatenate((np.zeros(6), q_arm)))[:, 6:]
    assert np.linalg.svd(jac, compute_uv=False).min() > 0.2


def test_inverse_kinematics_raises_for_an_unreachable_point() -> None:
    """A point 3 m ahead is out of reach (arm + mount reach 2 m): UnreachableError."""
    with pytest.raises(UnreachableError, match='x_ned'):
        MODEL.joint_positions_for_ee_position(np.zeros(6), [3.0, 0.0, 0.0], RECOMMENDED_Q_ARM)


def test_inverse_kinematics_accounts_for_the_vehicle_pose() -> None:
    """With the vehicle moved and yawed, IK still reaches the target in map_ned."""
    q_vehicle = np.array([2.0, -1.0, 3.0, 0.1, -0.2, 1.0])
    target = np.array([2.0, -1.0, 3.0]) + rot_ned_from_body(*q_vehicle[3:]) @ [1.7, 0.0, -0.1]
    q_arm = MODEL.joint_positions_for_ee_position(q_vehicle, target, RECOMMENDED_Q_ARM)
    np.testing.assert_allclose(
        MODEL.ee_position(np.concatenate((q_vehicle, q_arm))), target, atol=1e-9
    )


@pytest.mark.parametrize('rpy', ATTITUDES)
def test_euler_angles_round_trip_through_the_rotation(rpy: tuple[float, float, float]) -> None:
    """euler_from_rotation inverts rot_ned_from_body for |pitch| < 90 deg."""
    np.testing.assert_allclose(euler_from_rotation(rot_ned_from_body(*rpy)), rpy, atol=1e-12)
