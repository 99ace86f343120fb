"""Independent oracles over every robot folder: Pinocchio, finite differences, energy."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from uvms_description.robots import robot_files, robot_names, urdf_text
from uvms_model import UvmsModel, UvmsParameters

ROBOTS = robot_names()
SEEDS = range(5)


def _params(robot: str, **flat: object) -> UvmsParameters:
    files = robot_files(robot)
    return UvmsParameters().updated({'description.urdf_path': str(files.urdf),
                                     'description.hydrodynamics_path': str(files.hydrodynamics),
                                     **flat})


def _state(model: UvmsModel, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    q = np.concatenate((rng.uniform(-1, 1, 3), rng.uniform(-0.4, 0.4, 3),
                        rng.uniform(-1.2, 1.2, model.n_joints)))
    return q, rng.normal(0.0, 0.3, model.n_dof)


@pytest.fixture(scope='module', params=ROBOTS)
def robot(request: pytest.FixtureRequest) -> str:
    """Each robot folder of uvms_description."""
    return str(request.param)


@pytest.mark.parametrize('seed', SEEDS)
def test_rigid_body_terms_equal_pinocchio_from_the_urdf_alone(robot: str, seed: int) -> None:
    """Without hydrodynamics and gravity: M_b = CRBA and bias = RNEA of a plain URDF model."""
    model = UvmsModel(_params(robot, **{'hydrodynamics.added_mass_enabled': False,
                                        'hydrodynamics.drag_enabled': False,
                                        'hydrodynamics.buoyancy_enabled': False,
                                        'hydrodynamics.gravity_m_s2': 0.0}))
    oracle = pin.buildModelFromXML(urdf_text(robot_files(robot).urdf), pin.JointModelFreeFlyer())
    oracle.gravity = pin.Motion.Zero()
    data = oracle.createData()
    q, w = _state(model, seed)
    config = np.concatenate((np.zeros(3), [0.0, 0.0, 0.0, 1.0], q[6:]))  # body at the origin
    mass = pin.crba(oracle, data, config)
    mass = np.triu(mass) + np.triu(mass, 1).T
    np.testing.assert_allclose(model.mass_matrix_body(q), mass, rtol=1e-9, atol=1e-10)
    bias = pin.rnea(oracle, data, config, w, np.zeros(model.n_dof))
    np.testing.assert_allclose(model.bias_body(q, w), bias, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize('seed', SEEDS)
def test_jacobian_equals_finite_differences(robot: str, seed: int) -> None:
    """J q_dot = d X(q + h q_dot)/dh by central differences (eq. 22)."""
    model = UvmsModel(_params(robot))
    q, _ = _state(model, seed)
    q_dot = np.random.default_rng(seed + 100).normal(size=model.n_dof)
    h = 1e-6
    fd = (model.ee_position(q + h * q_dot) - model.ee_position(q - h * q_dot)) / (2 * h)
    np.testing.assert_allclose(model.ee_jacobian(q) @ q_dot, fd, atol=1e-7)


@pytest.mark.parametrize('seed', SEEDS)
def test_mass_matrix_is_symmetric_positive_definite(robot: str, seed: int) -> None:
    """M_b with added mass is SPD at any configuration."""
    model = UvmsModel(_params(robot))
    mass = model.mass_matrix_body(_state(model, seed)[0])
    np.testing.assert_allclose(mass, mass.T, atol=1e-12)
    assert np.linalg.eigvalsh(mass).min() > 0.0


def test_kinetic_energy_is_conserved_without_drag_gravity_and_inputs(robot: str) -> None:
    """½ wᵀ M_b w over 2 s of RK4 at 2 ms, added mass included, is constant to 1e-6."""
    model = UvmsModel(_params(robot, **{'hydrodynamics.drag_enabled': False,
                                        'hydrodynamics.buoyancy_enabled': False,
                                        'hydrodynamics.gravity_m_s2': 0.0}))
    q, w = _state(model, 7)
    energy = 0.5 * w @ model.mass_matrix_body(q) @ w
    for _ in range(1000):
        q, w = model.step(q, w, np.zeros(model.n_dof), None, 2e-3)
    assert 0.5 * w @ model.mass_matrix_body(q) @ w == pytest.approx(energy, rel=1e-6)


def test_drag_only_removes_kinetic_energy(robot: str) -> None:
    """With drag on (gravity and inputs off) the kinetic energy never grows."""
    model = UvmsModel(_params(robot, **{'hydrodynamics.buoyancy_enabled': False,
                                        'hydrodynamics.gravity_m_s2': 0.0}))
    q, w = _state(model, 8)
    energies = []
    for _ in range(200):
        energies.append(0.5 * w @ model.mass_matrix_body(q) @ w)
        q, w = model.step(q, w, np.zeros(model.n_dof), None, 2e-3)
    assert np.all(np.diff(energies) <= 1e-12)
