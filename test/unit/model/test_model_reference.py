"""uvms_model (Pinocchio, from the URDF) against the previous pure-Python implementation.

The reference (``reference_model.ReferenceModel``) computes the same model by hand-written
spatial algorithms from the paper's numbers written out in the test, not from the URDF: the
two agree to rounding when the URDF holds the paper's robot and Pinocchio with the added-mass
sliders computes what the spatial algorithms do.
"""

from __future__ import annotations

import numpy as np
import pytest
from model_oracles import random_state
from reference_model import ReferenceModel

from uvms_model import UvmsModel, UvmsParameters

STATES = range(40)
RELATIVE = 1e-9
VARIANTS = {
    'full': UvmsParameters(),
    'rigid': UvmsParameters().without_hydrodynamics(),
    'added mass only': UvmsParameters()
    .without_hydrodynamics()
    .updated({'hydrodynamics.added_mass_enabled': True}),
    'no buoyancy': UvmsParameters().updated({'hydrodynamics.buoyancy_enabled': False}),
}


def _assert_relative(actual: np.ndarray, expected: np.ndarray) -> None:
    """Max abs error within RELATIVE of the largest entry of ``expected``."""
    scale = max(float(np.max(np.abs(expected))), 1e-12)
    np.testing.assert_allclose(actual, expected, rtol=0.0, atol=RELATIVE * scale)


@pytest.fixture(scope='module', params=list(VARIANTS), ids=list(VARIANTS))
def pair(request: pytest.FixtureRequest) -> tuple[UvmsModel, ReferenceModel]:
    """The model and its reference for one set of hydrodynamic switches."""
    params = VARIANTS[request.param]
    return UvmsModel(params), ReferenceModel(params)


@pytest.mark.parametrize('seed', STATES)
def test_body_mass_matrix_equals_the_reference(
    seed: int, pair: tuple[UvmsModel, ReferenceModel]
) -> None:
    """M_b(q_m) of eq. 8, added mass included, equals the composite-rigid-body reference."""
    model, reference = pair
    q, _ = random_state(seed)
    _assert_relative(model.mass_matrix_body(q), reference.mass_matrix_body(q))


@pytest.mark.parametrize('seed', STATES)
def test_body_bias_equals_the_reference(
    seed: int, pair: tuple[UvmsModel, ReferenceModel]
) -> None:
    """C_b w + D_b w + G_b of eq. 8 equals the recursive Newton-Euler reference."""
    model, reference = pair
    q, w = random_state(seed)
    _assert_relative(model.bias_body(q, w), reference.bias_body(q, w))


@pytest.mark.parametrize('seed', STATES)
def test_forward_dynamics_with_an_end_effector_force_equals_the_reference(
    seed: int, pair: tuple[UvmsModel, ReferenceModel]
) -> None:
    """ABA with the sliders, drag, weights and an EE force gives the reference's w_dot."""
    model, reference = pair
    q, w = random_state(seed)
    tau_b = np.random.default_rng(seed).normal(0.0, 30.0, 9)
    f_ee = np.array([-150.0, 12.0, -7.0])
    _assert_relative(
        model.forward_dynamics(q, w, tau_b, f_ee), reference.forward_dynamics(q, w, tau_b, f_ee)
    )


@pytest.mark.parametrize('method', ['rk4', 'semi_implicit_euler'])
@pytest.mark.parametrize('seed', range(8))
def test_one_step_equals_the_reference(seed: int, method: str) -> None:
    """One step of either integrator lands where the reference's does."""
    model, reference = UvmsModel(), ReferenceModel()
    q, w = random_state(seed)
    tau_b = np.random.default_rng(seed).normal(0.0, 30.0, 9)
    mine = model.step(q, w, tau_b, [-100.0, 0.0, 3.0], 1e-3, method=method)
    theirs = reference.step(q, w, tau_b, [-100.0, 0.0, 3.0], 1e-3, method=method)
    _assert_relative(np.concatenate(mine), np.concatenate(theirs))


@pytest.mark.parametrize('seed', STATES)
def test_generalized_terms_and_ee_kinematics_equal_the_reference(seed: int) -> None:
    """M(q), zeta (eq. 18-19), X, J (eq. 22) and J_dot q_dot (eq. 23) equal the reference's."""
    model, reference = UvmsModel(), ReferenceModel()
    q, q_dot = random_state(seed)
    terms = model.task_space_terms(q, q_dot)
    _assert_relative(terms.M, reference.mass_matrix(q))
    _assert_relative(terms.zeta, reference.bias(q, q_dot))
    _assert_relative(terms.X, reference.ee_position(q))
    _assert_relative(terms.J, reference.ee_jacobian(q))
    _assert_relative(terms.J_dot_q_dot, reference.ee_jacobian_dot_qdot(q, q_dot))
    _assert_relative(terms.B, reference.velocity_transform(q))
    _assert_relative(terms.rot_ned_from_ee, reference.ee_rotation(q))


@pytest.mark.parametrize('seed', range(12))
def test_frame_poses_equal_the_reference(seed: int) -> None:
    """Every frame of the URDF sits where the reference's kinematics put it."""
    q, _ = random_state(seed)
    mine, theirs = UvmsModel().frame_poses(q), ReferenceModel().frame_poses(q)
    assert tuple(mine) == tuple(theirs)
    for name, (position, rotation) in mine.items():
        np.testing.assert_allclose(position, theirs[name][0], atol=1e-12)
        np.testing.assert_allclose(rotation, theirs[name][1], atol=1e-12)


def test_added_mass_and_displacement_equal_the_reference() -> None:
    """Hull and link added-mass matrices and the hull's displaced mass (544.43 kg) agree."""
    model, reference = UvmsModel(), ReferenceModel()
    np.testing.assert_allclose(model.added_mass_vehicle, reference.added_mass_vehicle, atol=1e-12)
    np.testing.assert_allclose(model.added_mass_links, reference.added_mass_links, atol=1e-12)
    assert model.hull_displaced_mass_kg == pytest.approx(reference.hull_displaced_mass_kg, 1e-14)
