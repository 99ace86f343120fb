"""uvms_model against a hand-built Pinocchio model of the paper's bodies, and quadrature."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest
from model_oracles import PinocchioOracle, random_state
from reference_model import ReferenceRobot
from scipy.integrate import quad
from uvms_model.hydrodynamics import cylinder_added_mass, spheroid_added_mass

from uvms_model import UvmsModel, UvmsParameters, load_description

ROBOT = ReferenceRobot()

RIGID = UvmsParameters().without_hydrodynamics()
ORACLE_STATES = range(200)
RELATIVE = 1e-9


def _assert_relative(actual: np.ndarray, expected: np.ndarray, rtol: float) -> None:
    """Max abs error within rtol of the largest entry of ``expected``."""
    scale = float(np.max(np.abs(expected)))
    np.testing.assert_allclose(actual, expected, rtol=0.0, atol=rtol * scale)


@pytest.fixture(scope='module')
def rigid_model() -> UvmsModel:
    """Model with added mass, drag and buoyancy off."""
    return UvmsModel(RIGID)


@pytest.mark.parametrize('seed', ORACLE_STATES)
def test_rigid_mass_matrix_equals_pinocchio_crba(
    seed: int, rigid_model: UvmsModel, oracle: PinocchioOracle
) -> None:
    """Without hydrodynamics M_b(q_m) is Pinocchio's CRBA matrix to 1e-9 relative."""
    q, _ = random_state(seed)
    _assert_relative(rigid_model.mass_matrix_body(q), oracle.mass_matrix(q), RELATIVE)


@pytest.mark.parametrize('seed', ORACLE_STATES)
def test_rigid_bias_equals_pinocchio_rnea(
    seed: int, rigid_model: UvmsModel, oracle: PinocchioOracle
) -> None:
    """Without hydrodynamics C_b w + G_b is Pinocchio's RNEA at zero acceleration to 1e-9."""
    q, w = random_state(seed)
    _assert_relative(rigid_model.bias_body(q, w), oracle.bias(q, w), RELATIVE)


def _added_masses(params: UvmsParameters) -> list[np.ndarray]:
    rho = params.hydrodynamics.water_density_kg_m3
    hull = ROBOT.vehicle
    vehicle = spheroid_added_mass(0.5 * hull.length_m, 0.5 * hull.diameter_m, rho)
    links = [
        cylinder_added_mass(length, radius, rho)
        for length, radius in zip(ROBOT.arm.link_lengths_m, ROBOT.arm.link_radii_m, strict=True)
    ]
    return [vehicle, *links]


ADDED_MASS_ONLY = RIGID.updated({'hydrodynamics.added_mass_enabled': True})


@pytest.mark.parametrize('seed', range(20))
def test_added_mass_enters_mass_matrix_through_body_jacobians(
    seed: int, rigid_model: UvmsModel, oracle: PinocchioOracle
) -> None:
    """M_b - M_RB = sum_i J_i^T M_A,i J_i with Pinocchio's body Jacobians."""
    q, _ = random_state(seed)
    expected = sum(
        jac.T @ added @ jac
        for jac, added in zip(
            oracle.body_jacobians(q), _added_masses(ADDED_MASS_ONLY), strict=True
        )
    )
    actual = UvmsModel(ADDED_MASS_ONLY).mass_matrix_body(q) - rigid_model.mass_matrix_body(q)
    _assert_relative(actual, np.asarray(expected), RELATIVE)


@pytest.mark.parametrize('seed', range(20))
def test_added_mass_bias_is_kirchhoff_force_through_body_jacobians(
    seed: int, rigid_model: UvmsModel, oracle: PinocchioOracle
) -> None:
    """Bias - rigid bias = sum_i J_i^T (M_A,i J_dot_i w + nu_i x* M_A,i nu_i) (Pinocchio)."""
    q, w = random_state(seed)
    expected = np.zeros(9)
    motions = oracle.body_motion(q, w)
    jacobians = oracle.body_jacobians(q)
    for (nu, acc), jac, added in zip(
        motions, jacobians, _added_masses(ADDED_MASS_ONLY), strict=True
    ):
        coriolis = pin.Motion(nu).cross(pin.Force(added @ nu)).vector
        expected += jac.T @ (added @ acc + coriolis)
    actual = UvmsModel(ADDED_MASS_ONLY).bias_body(q, w) - rigid_model.bias_body(q, w)
    _assert_relative(actual, expected, RELATIVE)


BUOYANT = RIGID.updated({'hydrodynamics.buoyancy_enabled': True})


@pytest.mark.parametrize('seed', range(20))
def test_gravity_and_buoyancy_equal_pinocchio_rnea_with_buoyancy_as_external_force(
    seed: int, oracle: PinocchioOracle
) -> None:
    """G_b equals RNEA at rest with each body's buoyancy rho V g applied upward at its centre."""
    q, _ = random_state(seed)
    model = UvmsModel(BUOYANT)
    g = BUOYANT.hydrodynamics.gravity_m_s2
    rho = BUOYANT.hydrodynamics.water_density_kg_m3
    arm = ROBOT.arm
    displaced = [model.hull_displaced_mass_kg] + [
        rho * np.pi * r**2 * length
        for length, r in zip(arm.link_lengths_m, arm.link_radii_m, strict=True)
    ]
    centres = [np.array(ROBOT.vehicle.center_of_buoyancy_m)] + [
        np.array([0.5 * length, 0.0, 0.0]) for length in arm.link_lengths_m
    ]
    config = oracle.configuration(q)
    pin.forwardKinematics(oracle.model, oracle.data, config)
    forces = [pin.Force.Zero()]
    for joint in range(1, 5):
        rot_ned_from_local = oracle.data.oMi[joint].rotation
        up_local = rot_ned_from_local.T @ np.array([0.0, 0.0, -displaced[joint - 1] * g])
        forces.append(pin.Force(up_local, np.cross(centres[joint - 1], up_local)))
    expected = pin.rnea(oracle.model, oracle.data, config, np.zeros(9), np.zeros(9), forces)
    _assert_relative(model.gravity_body(q), expected, RELATIVE)
    _assert_relative(model.bias_body(q, np.zeros(9)), expected, RELATIVE)


DRAG_ONLY = RIGID.updated(
    {
        'hydrodynamics.drag_enabled': True,
        'hydrodynamics.gravity_m_s2': 0.0,
        'hydrodynamics.drag_strips_per_link': 64,
    }
)


def _link_drag_local(
    nu: np.ndarray, length: float, radius: float, params: UvmsParameters
) -> np.ndarray:
    """Cross-flow strip drag wrench of one link in its own frame, by adaptive quadrature."""
    gain = (
        0.5 * params.hydrodynamics.water_density_kg_m3 * ROBOT.arm.drag_coefficient * 2 * radius
    )

    def strip(x: float, component: int) -> float:
        v = nu[:3] + np.cross(nu[3:], [x, 0.0, 0.0])
        v_n = np.array([0.0, v[1], v[2]])
        force = -gain * np.linalg.norm(v_n) * v_n
        wrench = np.concatenate((force, np.cross([x, 0.0, 0.0], force)))
        return float(wrench[component])

    return np.array([quad(strip, 0.0, length, args=(k,), limit=200)[0] for k in range(6)])


@pytest.mark.parametrize('seed', range(10))
def test_link_drag_equals_quadrature_of_cross_flow_strips(
    seed: int, oracle: PinocchioOracle
) -> None:
    """Drag of the links is J_i^T of the integral of -1/2 rho C_D 2r |v_n| v_n dx (quad)."""
    q, w = random_state(seed)
    params = DRAG_ONLY
    description = load_description()
    no_hull_drag = dataclasses.replace(
        description,
        hull_hydrodynamics=dataclasses.replace(
            description.hull_hydrodynamics,
            linear_drag_rotation_n_m_s=0.0,
            drag_coefficient_translation=0.0,
            drag_coefficient_rotation=0.0,
        ),
    )
    drag_model = UvmsModel(params, no_hull_drag)
    rigid = UvmsModel(params.updated({'hydrodynamics.drag_enabled': False}))
    actual = drag_model.bias_body(q, w) - rigid.bias_body(q, w)
    expected = np.zeros(9)
    motions = oracle.body_motion(q, w)
    jacobians = oracle.body_jacobians(q)
    for i in range(3):
        wrench = _link_drag_local(
            motions[i + 1][0], ROBOT.arm.link_lengths_m[i], ROBOT.arm.link_radii_m[i], params
        )
        expected -= jacobians[i + 1].T @ wrench
    _assert_relative(actual, expected, 1e-4)


def test_hull_drag_in_pure_surge_is_half_rho_cd_frontal_area_u_squared() -> None:
    """Surging at u the hull feels 1/2 rho C_D pi b^2 u|u| (+ linear drag, zero in surge)."""
    model = UvmsModel(DRAG_ONLY)
    q = np.zeros(9)
    w = np.zeros(9)
    w[0] = -1.3
    b = 0.5 * ROBOT.vehicle.diameter_m
    expected = 0.5 * 1025.0 * 1.05 * np.pi * b**2 * 1.3**2
    rigid = UvmsModel(RIGID.updated({'hydrodynamics.gravity_m_s2': 0.0}))
    drag = model.bias_body(q, w) - rigid.bias_body(q, w)
    np.testing.assert_allclose(drag[0], -expected, rtol=1e-12)


def test_body_frames_match_pinocchio_forward_kinematics(oracle: PinocchioOracle) -> None:
    """frame_poses gives Pinocchio's joint placements for base_link_frd and link_1..3."""
    model = UvmsModel()
    for seed in range(20):
        q, _ = random_state(seed)
        poses = model.frame_poses(q)
        pin.forwardKinematics(oracle.model, oracle.data, oracle.configuration(q))
        for joint, name in enumerate(('base_link_frd', 'link_1', 'link_2', 'link_3'), start=1):
            placement = oracle.data.oMi[joint]
            np.testing.assert_allclose(poses[name][0], placement.translation, atol=1e-12)
            np.testing.assert_allclose(poses[name][1], placement.rotation, atol=1e-12)


@pytest.mark.parametrize('seed', range(10))
def test_velocity_transform_integrates_like_pinocchio_free_flyer(
    seed: int, oracle: PinocchioOracle
) -> None:
    """q_dot = B(q) w (eq. 4): Pinocchio's exact integration of w for dt agrees to O(dt^2)."""
    q, w = random_state(seed, max_pitch=1.2)
    dt = 1e-6
    config = pin.integrate(oracle.model, oracle.configuration(q), w * dt)
    rot = pin.Quaternion(config[3:7]).matrix()
    phi, theta, psi = (
        np.arctan2(rot[2, 1], rot[2, 2]),
        -np.arcsin(rot[2, 0]),
        np.arctan2(rot[1, 0], rot[0, 0]),
    )
    q_next = np.concatenate((config[:3], [phi, theta, psi], config[7:]))
    q_dot_fd = (q_next - q) / dt
    q_dot_fd[3:6] = (np.angle(np.exp(1j * (q_next[3:6] - q[3:6])))) / dt
    np.testing.assert_allclose(UvmsModel().velocity_transform(q) @ w, q_dot_fd, atol=1e-4)
