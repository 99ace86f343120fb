"""Tests of the Healey et al. (1995) thruster model (paper eq. 11-15) and its calibration."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uvms_thrusters.errors import ThrusterInputError, ThrusterParameterError
from uvms_thrusters.thruster_dynamics import ThrusterBank, ThrusterModelParameters, calibrate

PARAMS = ThrusterModelParameters()


def simulate(
    command: np.ndarray, duration: float, dt: float = 1e-3
) -> tuple[np.ndarray, ThrusterBank]:
    """Step a bank from rest under constant desired thrusts; return the thrust history."""
    bank = ThrusterBank(PARAMS, command.size)
    history = np.array([bank.step(command, dt).copy() for _ in range(round(duration / dt))])
    return history, bank


@pytest.mark.parametrize('thrust', [200.0, 100.0, 30.0, -20.0, -60.0, -120.0])
def test_step_response_settles_to_the_commanded_thrust(thrust: float) -> None:
    """At zero advance speed the actual thrust reaches F_td within 1 % in well under a second."""
    history, bank = simulate(np.array([thrust]), 1.0)
    settled = np.abs(history[:, 0] - thrust) <= 0.01 * abs(thrust)
    first_inside_for_good = int(np.nonzero(~settled)[0][-1]) + 1
    assert first_inside_for_good * 1e-3 < 0.4
    assert bank.omega[0] == pytest.approx(bank.omega_r[0], rel=1e-3)


def test_propeller_speed_reaches_the_reference_speed() -> None:
    """Ω settles on Ω_r = sign(F) sqrt(|F| / α_2) (eq. 11)."""
    _, bank = simulate(np.array([150.0, -90.0]), 1.0)
    c = bank.calibration
    expected = [math.sqrt(150.0 / c.alpha_2[0]), -math.sqrt(90.0 / c.alpha_2[1])]
    np.testing.assert_allclose(bank.omega, expected, rtol=1e-4)
    np.testing.assert_allclose(bank.omega_r, expected, rtol=1e-12)


def test_forward_bollard_thrust_matches_the_wageningen_law() -> None:
    """Steady forward thrust over ρ D⁴ n² is K_T (B-series calibration)."""
    _, bank = simulate(np.array([120.0]), 1.0)
    n = bank.omega[0] / (2.0 * math.pi)
    k_t = bank.thrust[0] / (PARAMS.water_density * PARAMS.propeller_diameter**4 * n * n)
    assert k_t == pytest.approx(PARAMS.thrust_coefficient, rel=1e-4)


def test_reverse_thrust_is_weaker_at_the_same_speed() -> None:
    """At equal |Ω| reverse thrust is reverse_thrust_ratio (0.6) times forward."""
    bank = ThrusterBank(PARAMS, 2)
    omega = 150.0
    u_fwd = bank.calibration.flow_ratio[0] * 0.7 * PARAMS.propeller_diameter / 2.0 * omega
    u_rev = -bank.calibration.flow_ratio[1] * 0.7 * PARAMS.propeller_diameter / 2.0 * omega
    thrust, _ = bank.blade_forces(np.array([omega, -omega]), np.array([u_fwd, u_rev]))
    assert thrust[0] > 0.0 > thrust[1]
    assert -thrust[1] / thrust[0] == pytest.approx(PARAMS.reverse_thrust_ratio, rel=1e-9)


def test_reverse_command_spins_the_propeller_faster() -> None:
    """The same thrust magnitude needs 1/sqrt(0.6) times the speed in reverse."""
    _, bank = simulate(np.array([80.0, -80.0]), 1.0)
    assert -bank.omega[1] / bank.omega[0] == pytest.approx(
        1.0 / math.sqrt(PARAMS.reverse_thrust_ratio), rel=1e-3
    )


def test_bollard_state_is_an_equilibrium() -> None:
    """At the calibrated (Ω, u_p) for a thrust, the state derivatives vanish."""
    bank = ThrusterBank(PARAMS, 1)
    for thrust in (150.0, -90.0):
        omega, u_p = bank.bollard_state(thrust)
        derivative = bank.derivatives(np.array([omega, u_p]), np.array([thrust]))
        np.testing.assert_allclose(derivative, 0.0, atol=1e-6)


def test_blade_forces_vanish_without_flow() -> None:
    """A stopped propeller in still water makes no thrust and no torque."""
    bank = ThrusterBank(PARAMS, 1)
    thrust, torque = bank.blade_forces(np.zeros(1), np.zeros(1))
    assert (thrust[0], torque[0]) == (0.0, 0.0)


def test_blade_forces_match_the_trigonometric_form() -> None:
    """The polynomial form equals the textbook β, α, C_L, C_D, L, D evaluation (eq. 14-15)."""
    bank = ThrusterBank(PARAMS, 1)
    c = bank.calibration
    r07 = 0.7 * PARAMS.propeller_diameter / 2.0
    for omega, u_p in [(120.0, 2.0), (80.0, -0.5), (-100.0, -1.5), (-60.0, 1.0)]:
        v_t = r07 * omega
        beta = math.atan2(u_p, v_t)
        alpha = PARAMS.pitch_angle - beta
        eta = 1.0 if omega >= 0.0 else c.reverse_lift_factor
        q_dyn = 0.5 * PARAMS.water_density * c.blade_area * (u_p**2 + v_t**2)
        lift = q_dyn * eta * PARAMS.lift_coefficient_max * math.sin(2 * alpha)
        drag = q_dyn * PARAMS.drag_coefficient_max * (1 - math.cos(2 * alpha))
        thrust, torque = bank.blade_forces(np.array([omega]), np.array([u_p]))
        assert thrust[0] == pytest.approx(lift * math.cos(beta) - drag * math.sin(beta), rel=1e-12)
        assert torque[0] == pytest.approx(
            r07 * (lift * math.sin(beta) + drag * math.cos(beta)), rel=1e-12
        )


def test_large_steps_are_substepped_stably() -> None:
    """A 20 ms step (10x the stability bound) still converges to the commanded thrust."""
    assert calibrate(PARAMS).max_step < 0.02
    history, _ = simulate(np.array([150.0, -100.0]), 2.0, dt=0.02)
    np.testing.assert_allclose(history[-1], [150.0, -100.0], rtol=1e-3)


def test_current_limit_caps_the_motor_current() -> None:
    """i_m never exceeds i_max, even for a large speed error at start-up."""
    bank = ThrusterBank(PARAMS, 1)
    currents = []
    for _ in range(300):
        bank.step(np.array([300.0]), 1e-3)
        currents.append(abs(bank.motor_current[0]))
    assert max(currents) == pytest.approx(PARAMS.max_motor_current)


def test_non_finite_desired_thrust_is_rejected() -> None:
    """A NaN command raises instead of corrupting the propeller state."""
    bank = ThrusterBank(PARAMS, 2)
    with pytest.raises(ThrusterInputError):
        bank.step(np.array([1.0, math.nan]), 1e-3)
    assert np.all(bank.omega == 0.0)


def test_pitch_below_the_bollard_flow_angle_is_rejected() -> None:
    """A pitch too flat for the requested K_T cannot be calibrated: the error names the pitch."""
    with pytest.raises(ThrusterParameterError, match=r'thruster\.pitch_angle'):
        calibrate(ThrusterModelParameters(pitch_angle=0.2))


def test_control_rate_step_matches_a_fine_integration() -> None:
    """At the 500 Hz step (one sub-step) thrust tracks a 0.1 ms integration: 3 %, then 1 %.

    3 % of the 200 N range during the first 50 ms of the rise, 1 % after it.
    """
    command = np.array([200.0, 20.0, 1.0, -150.0])
    coarse, _ = simulate(command, 0.6, dt=2e-3)
    fine = simulate(command, 0.6, dt=1e-4)[0][19::20]
    np.testing.assert_allclose(coarse[:25], fine[:25], atol=0.03 * 200.0)
    np.testing.assert_allclose(coarse[25:], fine[25:], atol=0.01 * 200.0)
