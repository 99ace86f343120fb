"""Closed-loop simulations of the controller on the real UVMS model against a stiff wall."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from uvms_control.core.law.unified_controller import UnifiedForceController
from uvms_control.core.parameters import ControllerParameters

from uvms_model import UvmsModel

DT = 1e-3
Q0 = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.927, -1.571])  # EE near (1.70, 0, -0.10)
STEP = 0.03  # reference 3 cm beyond the start, into the wall (m)
WALL_GAP = 0.01  # wall 1 cm beyond the start (m)


def wall_force(x: float, wall: float, k_e: float) -> np.ndarray:
    """Force the end effector exerts on a spring wall normal to +x (N)."""
    return np.array([k_e * max(x - wall, 0.0), 0.0, 0.0])


def simulate(k_e: float, duration: float, **overrides: object) -> tuple[np.ndarray, np.ndarray]:
    """Run controller + plant (exact model, RK4) at 1 kHz; return t and EE positions.

    Stops early if the end effector leaves a 1 m box around its start (a diverging loop).
    """
    plant = UvmsModel()
    x_start = plant.ee_position(Q0)
    params = ControllerParameters.from_flat_dict({'mode': 'impedance', **overrides})
    controller = UnifiedForceController(params, UvmsModel())
    controller.task.hold(x_start + np.array([STEP, 0.0, 0.0]))
    wall = x_start[0] + WALL_GAP
    q, w = Q0.copy(), np.zeros(9)
    times, positions = [], []
    for k in range(round(duration / DT)):
        x = plant.ee_position(q)
        if not np.all(np.abs(x - x_start) < 1.0):
            break
        f_e = wall_force(float(x[0]), wall, k_e)
        times.append(k * DT)
        positions.append(x)
        result = controller.step(k * DT, q, plant.velocity_transform(q) @ w, f_e)
        q, w = plant.step(q, w, result.tau_b, -f_e, DT)
    return np.array(times), np.array(positions)


def target_impedance(
    k_e: float, t: np.ndarray, x_start: np.ndarray, params: ControllerParameters
) -> np.ndarray:
    """X(t) of the target P Ë + B_d Ė + K E = F_e (eq. 21) with the same wall, E = X_d - X."""
    P_inv = np.linalg.inv(params.impedance_inertia)
    x_d = x_start + np.array([STEP, 0.0, 0.0])
    wall = x_start[0] + WALL_GAP

    def rhs(_: float, state: np.ndarray) -> np.ndarray:
        x, v = state[:3], state[3:]
        f_e = wall_force(float(x[0]), wall, k_e)
        e, e_dot = x_d - x, -v
        e_ddot = P_inv @ (f_e - params.impedance_damping @ e_dot - params.impedance_stiffness @ e)
        return np.concatenate([v, -e_ddot])

    solution = solve_ivp(
        rhs,
        (0.0, t[-1]),
        np.concatenate([x_start, np.zeros(3)]),
        t_eval=t,
        rtol=1e-10,
        atol=1e-12,
        max_step=1e-3,
    )
    result: np.ndarray = solution.y[:3].T
    return result


@pytest.mark.parametrize('k_e', [1e4, 1e5])
def test_impedance_step_response_against_a_wall_is_the_target_impedance(k_e: float) -> None:
    """With M̂ = M̃, ζ̂ = ζ̃ the UVMS end effector moves as P Ë + B_d Ė + K E = F_e (eq. 21)."""
    t, x_sim = simulate(k_e, 1.0)
    params = ControllerParameters.from_flat_dict()
    x_target = target_impedance(k_e, t, x_sim[0], params)
    # The end effector reaches the wall and compresses it; both trajectories agree to 2 % of
    # the 3 cm step (1 ms zero-order hold on the command is the only difference).
    assert x_sim[:, 0].max() > x_sim[0, 0] + WALL_GAP
    np.testing.assert_allclose(x_sim, x_target, atol=0.02 * STEP)
    force_sim = k_e * np.maximum(x_sim[:, 0] - x_sim[0, 0] - WALL_GAP, 0.0)
    force_target = k_e * np.maximum(x_target[:, 0] - x_sim[0, 0] - WALL_GAP, 0.0)
    assert force_sim.max() == pytest.approx(force_target.max(), rel=0.03)


def test_without_null_space_the_paper_law_misses_the_target_impedance() -> None:
    """τ = Jᵀ F_IP alone (the paper's law) departs from eq. 21 here: it runs away."""
    t, x_sim = simulate(1e4, 0.5, **{'null_space.enabled': False})
    x_target = target_impedance(1e4, t, x_sim[0], ControllerParameters.from_flat_dict())
    assert np.max(np.abs(x_sim - x_target)) > 0.1 * STEP
