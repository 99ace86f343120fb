"""Dynamics of uvms_model: eq. 8 in quasi-velocities, eq. 18-20 in coordinates, integration."""

from __future__ import annotations

import numpy as np
import pytest
from model_oracles import random_state

from uvms_model import UvmsModel, UvmsParameters

MODEL = UvmsModel()
STATES = range(12)
CONSERVATIVE = UvmsParameters().updated(
    {'hydrodynamics.drag_enabled': False, 'hydrodynamics.gravity_m_s2': 0.0}
)


def _b_dot(q: np.ndarray, q_dot: np.ndarray) -> np.ndarray:
    """B_dot along q_dot by central differences."""
    h = 1e-6
    return (MODEL.velocity_transform(q + h * q_dot) - MODEL.velocity_transform(q - h * q_dot)) / (
        2 * h
    )


@pytest.mark.parametrize('seed', STATES)
def test_body_mass_matrix_is_symmetric_positive_definite(seed: int) -> None:
    """M_b (rigid + added mass) is symmetric with eigenvalues > 0."""
    q, _ = random_state(seed)
    mass = MODEL.mass_matrix_body(q)
    np.testing.assert_allclose(mass, mass.T, atol=1e-12)
    assert np.linalg.eigvalsh(mass).min() > 0.1


@pytest.mark.parametrize('seed', STATES)
def test_added_mass_part_of_mass_matrix_is_symmetric_positive_semidefinite(seed: int) -> None:
    """M_b - M_RB is symmetric PSD, and positive definite in vehicle translation."""
    q, _ = random_state(seed)
    rigid = UvmsModel(UvmsParameters().without_hydrodynamics())
    added = MODEL.mass_matrix_body(q) - rigid.mass_matrix_body(q)
    np.testing.assert_allclose(added, added.T, atol=1e-12)
    assert np.linalg.eigvalsh(added).min() > -1e-9
    assert np.linalg.eigvalsh(added[:3, :3]).min() > 28.0  # Lamb's surge added mass, 28.2 kg


@pytest.mark.parametrize('seed', STATES)
def test_generalized_mass_matrix_is_b_inverse_transpose_m_b_b_inverse(seed: int) -> None:
    """M(q) B = B^-T M_b (eq. 18) and M is symmetric positive definite."""
    q, _ = random_state(seed)
    b = MODEL.velocity_transform(q)
    mass = MODEL.mass_matrix(q)
    np.testing.assert_allclose(b.T @ mass @ b, MODEL.mass_matrix_body(q), rtol=1e-10, atol=1e-9)
    assert np.linalg.eigvalsh(mass).min() > 0.0


@pytest.mark.parametrize('seed', STATES)
def test_generalized_form_predicts_the_same_motion_as_body_form(seed: int) -> None:
    """M q_ddot + zeta = tau (eq. 20) for q_ddot = B w_dot + B_dot w of eq. 8 with B^T tau."""
    q, w = random_state(seed)
    rng = np.random.default_rng(seed + 100)
    tau = rng.normal(0.0, 50.0, 9)
    b = MODEL.velocity_transform(q)
    q_dot = b @ w
    w_dot = MODEL.forward_dynamics(q, w, b.T @ tau)
    q_ddot = b @ w_dot + _b_dot(q, q_dot) @ w
    residual = MODEL.mass_matrix(q) @ q_ddot + MODEL.bias(q, q_dot) - tau
    np.testing.assert_allclose(residual, 0.0, atol=1e-5 * np.abs(tau).max())


@pytest.mark.parametrize('seed', STATES)
def test_power_of_generalized_forces_is_frame_invariant(seed: int) -> None:
    """Tau . q_dot = tau_b . w with tau_b = B^T tau and q_dot = B w."""
    q, w = random_state(seed)
    tau = np.random.default_rng(seed).normal(size=9)
    b = MODEL.velocity_transform(q)
    assert float(tau @ (b @ w)) == pytest.approx(float((b.T @ tau) @ w), rel=1e-12, abs=1e-12)


@pytest.mark.parametrize('seed', STATES)
def test_force_on_end_effector_acts_as_jacobian_transpose(seed: int) -> None:
    """A force f on the EE (map_ned) equals the body force (J B)^T f in the dynamics."""
    q, w = random_state(seed)
    f = np.array([-150.0, 20.0, 35.0])
    b = MODEL.velocity_transform(q)
    tau_b = np.random.default_rng(seed).normal(0.0, 10.0, 9)
    with_force = MODEL.forward_dynamics(q, w, tau_b, f)
    as_torque = MODEL.forward_dynamics(q, w, tau_b + (MODEL.ee_jacobian(q) @ b).T @ f)
    np.testing.assert_allclose(with_force, as_torque, atol=1e-9)


@pytest.mark.parametrize('seed', STATES)
def test_bias_compensation_gives_zero_acceleration(seed: int) -> None:
    """tau_b = C_b w + D_b w + G_b makes w_dot = 0 (eq. 8)."""
    q, w = random_state(seed)
    w_dot = MODEL.forward_dynamics(q, w, MODEL.bias_body(q, w))
    np.testing.assert_allclose(w_dot, 0.0, atol=1e-10)


@pytest.mark.parametrize('seed', STATES)
def test_neutral_uvms_feels_no_net_vertical_force(seed: int) -> None:
    """With buoyancy ratio 1, weight and buoyancy cancel in any attitude and arm posture."""
    q, _ = random_state(seed)
    g_b = MODEL.gravity_body(q)
    assert np.linalg.norm(g_b[:3]) < 1e-9


def test_centre_of_gravity_below_buoyancy_gives_restoring_roll_moment() -> None:
    """With the arm along the roll axis, a positive roll gives a positive G_b roll moment."""
    q = np.zeros(9)
    q[3] = 0.2
    moment = MODEL.gravity_body(q)[3]
    m = 530.0
    expected = m * 9.81 * 0.05 * np.sin(0.2)
    assert moment == pytest.approx(expected, rel=1e-9)


def _simulate(
    model: UvmsModel, q: np.ndarray, w: np.ndarray, dt: float, steps: int
) -> list[float]:
    energies = [model.kinetic_energy(q, w)]
    zero = np.zeros(9)
    for _ in range(steps):
        q, w = model.step(q, w, zero, None, dt)
        energies.append(model.kinetic_energy(q, w))
    return energies


@pytest.mark.parametrize('seed', [1, 2])
def test_kinetic_energy_is_conserved_without_drag_gravity_and_inputs(seed: int) -> None:
    """T = 1/2 w^T M_b w (added mass included) stays constant over 10 s of RK4 (1e-6)."""
    model = UvmsModel(CONSERVATIVE)
    q, w = random_state(seed)
    w *= 0.5
    energies = _simulate(model, q, w, dt=0.005, steps=2000)
    assert max(abs(e - energies[0]) for e in energies) < 1e-6 * energies[0]


@pytest.mark.parametrize('seed', [1, 2])
def test_drag_only_removes_kinetic_energy(seed: int) -> None:
    """With drag on (no gravity, no inputs) T never increases, and falls noticeably in 2 s."""
    model = UvmsModel(CONSERVATIVE.updated({'hydrodynamics.drag_enabled': True}))
    q, w = random_state(seed)
    energies = np.array(_simulate(model, q, w, dt=0.005, steps=400))
    assert np.all(np.diff(energies) <= 1e-9 * energies[0])
    assert energies[-1] < 0.9 * energies[0]


@pytest.mark.parametrize('seed', STATES)
def test_drag_power_is_never_positive(seed: int) -> None:
    """W . D_b(w) w >= 0: drag dissipates for any velocity."""
    q, w = random_state(seed)
    no_drag = UvmsModel(UvmsParameters().updated({'hydrodynamics.drag_enabled': False}))
    drag = MODEL.bias_body(q, w) - no_drag.bias_body(q, w)
    assert float(w @ drag) >= 0.0


def test_semi_implicit_euler_converges_to_rk4_at_first_order() -> None:
    """Halving dt halves the semi-implicit Euler error against a fine RK4 reference."""
    q0, w0 = random_state(3)
    tau_b = np.random.default_rng(3).normal(0.0, 20.0, 9)

    def run(dt: float, method: str) -> np.ndarray:
        q, w = q0, w0
        for _ in range(round(0.2 / dt)):
            q, w = MODEL.step(q, w, tau_b, None, dt, method=method)
        return np.concatenate((q, w))

    reference = run(1e-4, 'rk4')
    errors = [np.linalg.norm(run(dt, 'semi_implicit_euler') - reference) for dt in (4e-3, 2e-3)]
    assert errors[1] / errors[0] == pytest.approx(0.5, abs=0.1)


def test_rk4_converges_at_fourth_order() -> None:
    """Halving dt divides the RK4 error by about 16."""
    q0, w0 = random_state(4)
    tau_b = np.random.default_rng(4).normal(0.0, 20.0, 9)

    def run(dt: float) -> np.ndarray:
        q, w = q0, w0
        for _ in range(round(0.4 / dt)):
            q, w = MODEL.step(q, w, tau_b, None, dt)
        return np.concatenate((q, w))

    reference = run(1e-3)
    errors = [np.linalg.norm(run(dt) - reference) for dt in (0.04, 0.02)]
    assert 10.0 < errors[0] / errors[1] < 22.0


def test_step_is_deterministic() -> None:
    """The same state and inputs give bit-identical results."""
    q, w = random_state(5)
    tau_b = np.arange(9.0)
    first = MODEL.step(q, w, tau_b, [1.0, 2.0, 3.0], 1e-3)
    second = MODEL.step(q, w, tau_b, [1.0, 2.0, 3.0], 1e-3)
    assert first[0].tobytes() == second[0].tobytes()
    assert first[1].tobytes() == second[1].tobytes()


def test_neutral_vehicle_with_folded_arm_at_rest_stays_at_rest() -> None:
    """Zero inputs and gravity compensated by G_b: a UVMS at rest does not move in 1 s."""
    q = np.zeros(9)
    q[6:] = [0.0, 0.9272952180016122, -np.pi / 2]
    tau_b = MODEL.gravity_body(q)
    w = np.zeros(9)
    q_next = q
    for _ in range(100):
        q_next, w = MODEL.step(q_next, w, tau_b, None, 0.01)
    np.testing.assert_allclose(q_next, q, atol=1e-9)


def test_uvms_is_trimmed_level_at_the_recommended_start_pose() -> None:
    """With the arm at (0, atan(4/3), -pi/2) weight and buoyancy give < 1 N m roll/pitch moment."""
    q = np.zeros(9)
    q[6:] = [0.0, np.arctan2(4.0, 3.0), -np.pi / 2]
    np.testing.assert_allclose(MODEL.gravity_body(q)[3:6], 0.0, atol=1.0)


def test_results_do_not_depend_on_the_previous_call() -> None:
    """The per-configuration cache never leaks: a fresh model gives the same numbers."""
    q1, w1 = random_state(7)
    q2, w2 = random_state(8)
    warm = UvmsModel()
    warm.forward_dynamics(q1, w1, np.zeros(9))
    warm.mass_matrix_body(q2)
    fresh = UvmsModel()
    np.testing.assert_array_equal(warm.bias_body(q2, w2), fresh.bias_body(q2, w2))
    np.testing.assert_array_equal(warm.mass_matrix_body(q1), fresh.mass_matrix_body(q1))
    returned = warm.mass_matrix_body(q1)
    returned[:] = 0.0
    np.testing.assert_array_equal(warm.mass_matrix_body(q1), fresh.mass_matrix_body(q1))
