"""Per-equation tests of the unified force controller on the real UVMS model (paper sec. 4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uvms_control.core.errors import ControlInputError
from uvms_control.core.law.reference import ForcePhase, HalfCircleReference
from uvms_control.core.law.unified_controller import Phase, UnifiedForceController
from uvms_control.core.parameters import ControllerParameters
from uvms_control.core.task.contact_task import ContactTaskGoal

from uvms_model import UvmsModel

MODEL = UvmsModel()
Q_START = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.477, -1.511])
X_START = MODEL.ee_position(Q_START)

# (q, w, F_e): states around the working posture, with vehicle attitude, motion and contact.
STATES = [
    (
        Q_START + np.array([0.02, -0.01, 0.03, 0.05, -0.04, 0.1, 0.05, -0.1, 0.08]),
        np.array([0.05, -0.02, 0.01, 0.02, -0.03, 0.04, 0.1, -0.2, 0.15]),
        np.array([60.0, 2.0, -1.0]),
    ),
    (
        Q_START + np.array([-0.02, 0.03, -0.01, -0.05, 0.05, -0.1, -0.05, 0.03, -0.03]),
        np.array([-0.1, 0.05, 0.08, -0.05, 0.02, -0.01, -0.3, 0.1, 0.2]),
        np.array([150.0, 0.0, 0.0]),
    ),
    (
        Q_START + np.array([0.0, 0.0, 0.0, 0.1, 0.05, 0.3, 0.05, 0.04, -0.04]),
        np.zeros(9),
        np.zeros(3),
    ),
]


def tolerance(*terms: np.ndarray) -> float:
    """Absolute tolerance of the finite-difference oracle: 1e-4 of the largest term."""
    return 1e-4 * max(float(np.linalg.norm(term)) for term in terms) + 1e-6


def controller(**overrides: object) -> UnifiedForceController:
    """A controller with exact model knowledge (M̂ = M̃, ζ̂ = ζ̃) and the given parameters."""
    return UnifiedForceController(ControllerParameters.from_flat_dict(overrides), UvmsModel())


def ee_acceleration(
    q: np.ndarray, w: np.ndarray, tau_b: np.ndarray, F_e: np.ndarray
) -> np.ndarray:
    """Ẍ of the plant under tau_b, by finite differences of the EE position along RK4 steps.

    Uses only the plant's integrator and forward kinematics (not J, J̇ q̇ or the mass matrix),
    so it checks the controller's task-space model independently. The environment pushes on
    the end effector with -F_e.
    """
    h = 2e-4
    positions = [MODEL.ee_position(q)]
    qk, wk = q, w
    for _ in range(3):
        qk, wk = MODEL.step(qk, wk, tau_b, -F_e, h)
        positions.append(MODEL.ee_position(qk))
    x0, x1, x2, x3 = positions
    result: np.ndarray = (2.0 * x0 - 5.0 * x1 + 4.0 * x2 - x3) / (h * h)
    return result


def generalized_acceleration(
    q: np.ndarray, w: np.ndarray, tau_b: np.ndarray, F_e: np.ndarray
) -> np.ndarray:
    """q̈ of the plant under tau_b, by finite differences of q along RK4 steps."""
    h = 2e-4
    states = [q]
    qk, wk = q, w
    for _ in range(3):
        qk, wk = MODEL.step(qk, wk, tau_b, -F_e, h)
        states.append(qk)
    q0, q1, q2, q3 = states
    result: np.ndarray = (2.0 * q0 - 5.0 * q1 + 4.0 * q2 - q3) / (h * h)
    return result


def half_circle_goal(start_delay_s: float = 2.0) -> ContactTaskGoal:
    """The paper's task from X_START: the half circle (r = 0.1 m, 16 s, down) and 150 N along +x.

    81 waypoints with the exact velocities and accelerations of ``HalfCircleReference``,
    starting ``start_delay_s`` after the task; F_d ramps over 1 s.
    """
    reference = HalfCircleReference(radius=0.1, duration=16.0, start_delay=0.0)
    times = np.linspace(0.0, 16.0, 81)
    samples = np.array([reference.evaluate_floats(float(t), X_START.tolist()) for t in times])
    return ContactTaskGoal(
        path=samples[:, 0:3],
        times=start_delay_s + times,
        velocities=samples[:, 3:6],
        accelerations=samples[:, 6:9],
        normal=np.array([1.0, 0.0, 0.0]),
        force_n=150.0,
        force_ramp_s=1.0,
    )


def start(ctrl: UnifiedForceController, goal: ContactTaskGoal | None):  # type: ignore[no-untyped-def]
    """First step at Q_START at rest (posture and time origin), running ``goal`` from t = 0."""
    if goal is not None:
        ctrl.task.hold(X_START)
        ctrl.start_task(0.0, goal)
    return ctrl.step(0.0, Q_START, np.zeros(9), np.zeros(3))


def step_at(
    ctrl: UnifiedForceController,
    q: np.ndarray,
    w: np.ndarray,
    F_e: np.ndarray,
    t: float = 3.7,
    goal: ContactTaskGoal | None = None,
):  # type: ignore[no-untyped-def]
    """Start the controller at Q_START on a task (default: the paper's), then step at (q, w)."""
    start(ctrl, half_circle_goal() if goal is None else goal)
    q_dot = MODEL.velocity_transform(q) @ w
    return ctrl.step(t, q, q_dot, F_e)


def reference_acceleration(ctrl: UnifiedForceController, t: float) -> np.ndarray:
    """Ẍ_d of the controller's running task path at t (m/s²)."""
    assert ctrl.task.path is not None
    return np.array(ctrl.task.path.evaluate_floats(t)[6:9])


@pytest.mark.parametrize(('q', 'w', 'F_e'), STATES)
def test_impedance_closed_loop_obeys_target_impedance(
    q: np.ndarray, w: np.ndarray, F_e: np.ndarray
) -> None:
    """With M̂ = M̃, ζ̂ = ζ̃ the plant under F_IP satisfies P Ë + B_d Ė + K E = F_e (eq. 21, 34)."""
    ctrl = controller(mode='impedance')
    result = step_at(ctrl, q, w, F_e, goal=half_circle_goal(start_delay_s=1.0))
    x_ddot = ee_acceleration(q, w, result.tau_b, F_e)
    x_ddot_d = reference_acceleration(ctrl, 3.7)
    law = ctrl.impedance
    E = result.X_d - result.X
    E_dot = result.X_dot_d - result.X_dot
    lhs = law.P @ (x_ddot_d - x_ddot) + law.B_d @ E_dot + law.K @ E
    np.testing.assert_allclose(lhs, F_e, atol=tolerance(law.P @ x_ddot, law.K @ E, F_e))


@pytest.mark.parametrize(('q', 'w', 'F_e'), STATES)
def test_hybrid_closed_loop_obeys_eq_36(q: np.ndarray, w: np.ndarray, F_e: np.ndarray) -> None:
    """With ζ̂ = ζ̃ the plant under F_H satisfies M̃ Ẍ = (I - S) F_p + S F_f (eq. 36)."""
    ctrl = controller(**{'mode': 'hybrid'})
    result = step_at(ctrl, q, w, F_e)
    assert result.W == 0.0  # the task's 150 N set-point selects the hybrid law alone
    x_ddot = ee_acceleration(q, w, result.tau_b, F_e)
    selected = result.F_H - result.zeta_hat - F_e  # (I - S) F_p + S F_f of eq. 35
    np.testing.assert_allclose(result.M_hat @ x_ddot, selected, atol=tolerance(selected, F_e))


@pytest.mark.parametrize(('q', 'w', 'F_e'), STATES)
def test_blended_closed_loop_follows_the_blended_command(
    q: np.ndarray, w: np.ndarray, F_e: np.ndarray
) -> None:
    """Under the fuzzy blend the plant obeys eq. 28 for F = F_c: M̃ Ẍ + ζ̃ = F_c - F_e."""
    ctrl = controller()
    result = step_at(ctrl, q, w, F_e)
    x_ddot = ee_acceleration(q, w, result.tau_b, F_e)
    np.testing.assert_allclose(
        result.M_hat @ x_ddot + result.zeta_hat,
        result.F_c - F_e,
        atol=tolerance(result.F_c, result.M_hat @ x_ddot, F_e),
    )


def test_paper_law_without_null_space_misses_the_target_impedance() -> None:
    """τ = Jᵀ F_IP alone does not give eq. 21 on this redundant UVMS (why the term exists)."""
    q, w, F_e = STATES[0]
    ctrl = controller(**{'mode': 'impedance', 'null_space.enabled': False})
    result = step_at(ctrl, q, w, F_e)
    x_ddot = ee_acceleration(q, w, result.tau_b, F_e)
    x_ddot_d = reference_acceleration(ctrl, 3.7)
    law = ctrl.impedance
    E = result.X_d - result.X
    lhs = law.P @ (x_ddot_d - x_ddot) + law.B_d @ (result.X_dot_d - result.X_dot) + law.K @ E
    assert float(np.linalg.norm(lhs - F_e)) > 0.1 * float(np.linalg.norm(F_e))


def test_without_null_space_the_command_is_the_papers() -> None:
    """null_space.enabled = False gives exactly τ = Jᵀ F_c, τ_b = Bᵀ τ (eq. 26)."""
    q, w, F_e = STATES[1]
    result = step_at(controller(**{'null_space.enabled': False}), q, w, F_e)
    tau = MODEL.ee_jacobian(q).T @ result.F_c
    np.testing.assert_allclose(result.tau, tau, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(result.tau_b, MODEL.velocity_transform(q).T @ tau, atol=1e-9)


@pytest.mark.parametrize(('q', 'w', 'F_e'), STATES)
def test_null_space_motion_follows_the_posture_law(
    q: np.ndarray, w: np.ndarray, F_e: np.ndarray
) -> None:
    """The null-space acceleration is N φ̈ with φ̈ = K_n (q_0 - q) - D_n q̇ (eq. 24)."""
    ctrl = controller()
    result = step_at(ctrl, q, w, F_e)
    q_ddot = generalized_acceleration(q, w, result.tau_b, F_e)
    q_dot = MODEL.velocity_transform(q) @ w
    J = MODEL.ee_jacobian(q)
    N = np.eye(9) - np.linalg.pinv(J) @ J
    error = Q_START - q
    phi_ddot = ctrl.params.null_space_stiffness * error - ctrl.params.null_space_damping * q_dot
    np.testing.assert_allclose(N @ q_ddot, N @ phi_ddot, atol=tolerance(q_ddot))


@pytest.mark.parametrize(('q', 'w', 'F_e'), STATES)
def test_command_power_is_the_same_in_both_forms(
    q: np.ndarray, w: np.ndarray, F_e: np.ndarray
) -> None:
    """τ·q̇ = τ_b·w: the body-form command is Bᵀ τ, not the paper's printed B τ_b."""
    result = step_at(controller(), q, w, F_e)
    q_dot = MODEL.velocity_transform(q) @ w
    assert float(result.tau @ q_dot) == pytest.approx(float(result.tau_b @ w), rel=1e-12, abs=1e-9)


def test_sensor_force_is_rotated_into_map_ned() -> None:
    """step_from_sensors(f in ft_sensor_link) equals step(rot_ned_from_ee f)."""
    q, w, F_e = STATES[0]
    rot = MODEL.ee_rotation(q)
    a = controller()
    b = controller()
    for ctrl in (a, b):
        start(ctrl, half_circle_goal())
    from_sensor = a.step_from_sensors(1.0, q, w, rot.T @ F_e)
    from_ned = b.step(1.0, q, MODEL.velocity_transform(q) @ w, F_e)
    np.testing.assert_allclose(from_sensor.F_e, F_e, atol=1e-12)
    np.testing.assert_allclose(from_sensor.tau_b, from_ned.tau_b, rtol=1e-10, atol=1e-9)


def test_mass_scale_scales_the_inertia_estimate() -> None:
    """model.mass_scale = 0.9 gives M̂ = 0.9 M̃ (paper Case IV)."""
    q, w, F_e = STATES[0]
    exact = step_at(controller(), q, w, F_e)
    scaled = step_at(controller(**{'model.mass_scale': 0.9}), q, w, F_e)
    np.testing.assert_allclose(scaled.M_hat, 0.9 * exact.M_hat, rtol=1e-12)


def test_first_step_starts_the_reference_at_rest_in_free_motion() -> None:
    """The first state sets X0: X_d = X, Ẋ_d = 0, W = 1 (impedance) and the phase is free."""
    result = controller().step(12.5, Q_START, np.zeros(9), np.zeros(3))
    np.testing.assert_allclose(result.X_d, MODEL.ee_position(Q_START))
    np.testing.assert_allclose(result.X_dot_d, 0.0)
    assert result.W == 1.0
    assert result.phase == Phase.FREE_MOTION


def test_hold_point_is_used_instead_of_the_captured_one() -> None:
    """task.hold(p) before the first step holds p at rest (W = 1), not the captured X."""
    ctrl = controller()
    ctrl.task.hold([1.6, 0.1, 0.3])
    result = ctrl.step(0.0, Q_START, np.zeros(9), np.zeros(3))
    np.testing.assert_allclose(result.X_d, [1.6, 0.1, 0.3])
    np.testing.assert_allclose(result.X_dot_d, 0.0)
    assert result.W == 1.0


def test_large_contact_force_at_rest_selects_the_hybrid_law() -> None:
    """At the set-point force and at rest the fuzzy switch gives W = 0: constrained motion."""
    result = step_at(controller(), Q_START, np.zeros(9), np.array([150.0, 0.0, 0.0]))
    assert result.W == 0.0
    assert result.phase == Phase.CONSTRAINED
    assert result.force_ratio == pytest.approx(1.0)


@pytest.mark.parametrize(
    ('q', 'q_dot', 'f'),
    [
        (np.full(9, math.nan), np.zeros(9), np.zeros(3)),
        (Q_START, np.zeros(8), np.zeros(3)),
        (Q_START, np.zeros(9), np.array([0.0, math.inf, 0.0])),
    ],
)
def test_malformed_inputs_are_rejected(q: np.ndarray, q_dot: np.ndarray, f: np.ndarray) -> None:
    """Non-finite or wrongly sized state or force raises ControlInputError."""
    with pytest.raises(ControlInputError):
        controller().step(0.0, q, q_dot, f)


def test_singular_attitude_is_an_input_error() -> None:
    """Pitch at 90 deg (Euler singularity of J2) is reported as a ControlInputError."""
    q = Q_START.copy()
    q[4] = math.pi / 2.0
    with pytest.raises(ControlInputError):
        controller().step(0.0, q, np.zeros(9), np.zeros(3))


def test_force_integral_does_not_wind_up_out_of_contact() -> None:
    """In free motion the force integral stays zero even with a pure hybrid set-point active."""
    ctrl = controller(mode='hybrid')
    start(ctrl, half_circle_goal())
    for k in range(1, 200):
        ctrl.step(0.01 * k, Q_START, np.zeros(9), np.zeros(3))
    assert ctrl.task.force is not None
    assert ctrl.task.force.phase == ForcePhase.RAMP_UP
    assert ctrl.hybrid.integral == 0.0


def test_posture_error_in_yaw_is_taken_the_short_way_round() -> None:
    """A yaw held at π - 0.05 seen at -π + 0.05 is 0.1 rad away, not 2π - 0.1 (Euler wrap)."""
    q0 = Q_START.copy()
    q0[5] = math.pi - 0.05
    q = q0.copy()
    q[5] = -math.pi + 0.05
    ctrl = controller()
    ctrl.step(0.0, q0, np.zeros(9), np.zeros(3))
    result = ctrl.step(0.002, q, np.zeros(9), np.zeros(3))
    q_ddot = generalized_acceleration(q, np.zeros(9), result.tau_b, np.zeros(3))
    J = MODEL.ee_jacobian(q)
    N = np.eye(9) - np.linalg.pinv(J) @ J
    error = np.zeros(9)
    error[5] = -0.1
    phi_ddot = ctrl.params.null_space_stiffness * error
    np.testing.assert_allclose(N @ q_ddot, N @ phi_ddot, atol=tolerance(q_ddot) + 1e-6)
