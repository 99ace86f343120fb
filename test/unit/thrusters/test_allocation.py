"""Tests of the thruster/motor allocation (paper eq. 9-10) and its saturation handling."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uvms_model.thrusters import ThrusterLayout
from uvms_thrusters.allocation import AllocatorParameters, ThrusterAllocator
from uvms_thrusters.errors import ThrusterInputError, ThrusterParameterError
from uvms_thrusters.thruster_dynamics import ThrusterModelParameters

LAYOUT = ThrusterLayout.from_parameters()
JOINT_LIMITS = np.array([100.0, 80.0, 50.0])


@pytest.fixture
def allocator() -> ThrusterAllocator:
    """Allocator for the default 8-thruster layout of uvms_model."""
    return ThrusterAllocator(
        AllocatorParameters(LAYOUT.thrust_matrix(), LAYOUT.max_thrust_n, JOINT_LIMITS)
    )


def random_wrenches(count: int, scale: float, seed: int) -> np.ndarray:
    """Random generalized forces (count, 9) of roughly the given magnitude."""
    return np.random.default_rng(seed).normal(0.0, scale, (count, 9))


#: 1/√2: the horizontal thrusters of config/robot.yaml are vectored at 45 degrees.
C45 = 0.5**0.5
#: Columns of E (eq. 9) written out from config/robot.yaml's layout: force = direction d,
#: moment = position r x d, in base_link_frd (not from the code under test).
HAND_COLUMNS = {
    # Thruster 0: r = (0.35, 0.25, 0), d = (c, -c, 0): r x d = (0, 0, -0.35 c - 0.25 c).
    0: [C45, -C45, 0.0, 0.0, 0.0, -0.6 * C45, 0.0, 0.0, 0.0],
    # Thruster 4: r = (0.25, 0.3, 0), d = (0, 0, 1): r x d = (0.3, -0.25, 0).
    4: [0.0, 0.0, 1.0, 0.3, -0.25, 0.0, 0.0, 0.0, 0.0],
}


@pytest.mark.parametrize('thruster', sorted(HAND_COLUMNS))
def test_configuration_matrix_column_is_direction_and_moment_of_the_thruster(
    allocator: ThrusterAllocator, thruster: int
) -> None:
    """Column i of E is [d_i; r_i x d_i] (eq. 9), written out by hand from the layout."""
    e = allocator.params.configuration_matrix()
    np.testing.assert_allclose(e[:, thruster], HAND_COLUMNS[thruster], atol=1e-12)


def test_configuration_matrix_passes_joint_torques_straight_through(
    allocator: ThrusterAllocator,
) -> None:
    """The arm block of E is I_3 and the thrusters give no joint torque (eq. 9)."""
    e = allocator.params.configuration_matrix()
    assert e.shape == (9, LAYOUT.count + 3)
    np.testing.assert_array_equal(e[6:, LAYOUT.count:], np.eye(3))
    np.testing.assert_array_equal(e[6:, :LAYOUT.count], 0.0)
    np.testing.assert_array_equal(e[:6, LAYOUT.count:], 0.0)


def test_pseudo_inverse_is_a_right_inverse(allocator: ThrusterAllocator) -> None:
    """E E⁺ = I (eq. 10): every generalized force is reproducible."""
    e = allocator.params.configuration_matrix()
    np.testing.assert_allclose(e @ allocator.pseudo_inverse, np.eye(9), atol=1e-12)


def test_pseudo_inverse_is_the_moore_penrose_inverse(allocator: ThrusterAllocator) -> None:
    """E⁺ = Eᵀ (E Eᵀ)⁻¹ equals numpy's pinv (an independent oracle)."""
    e = allocator.params.configuration_matrix()
    np.testing.assert_allclose(allocator.pseudo_inverse, np.linalg.pinv(e), atol=1e-12)


@pytest.mark.parametrize('seed', range(5))
def test_allocation_reproduces_wrench_when_unsaturated(
    allocator: ThrusterAllocator, seed: int
) -> None:
    """E F_td = tau_b for every feasible tau_b, with scale factors 1."""
    for tau in random_wrenches(20, 20.0, seed):
        result = allocator.allocate(tau)
        assert result.saturation_scale == 1.0
        assert result.joint_scale == 1.0
        f_td = np.concatenate([result.thrust, result.joint_torques])
        np.testing.assert_allclose(allocator.params.configuration_matrix() @ f_td, tau, atol=1e-9)
        np.testing.assert_allclose(result.achieved_wrench, tau[:6], atol=1e-9)


@pytest.mark.parametrize('seed', range(5))
def test_saturated_wrench_keeps_its_direction(allocator: ThrusterAllocator, seed: int) -> None:
    """Beyond the limits the achieved wrench is s tau_v, s < 1, parallel to the command."""
    for tau in random_wrenches(20, 2000.0, seed):
        result = allocator.allocate(tau)
        s = result.saturation_scale
        assert 0.0 < s < 1.0
        np.testing.assert_allclose(result.achieved_wrench, s * tau[:6], atol=1e-9)
        cosine = result.achieved_wrench @ tau[:6]
        cosine /= np.linalg.norm(result.achieved_wrench) * np.linalg.norm(tau[:6])
        assert cosine == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize('seed', range(3))
def test_saturation_scale_is_the_largest_feasible(allocator: ThrusterAllocator, seed: int) -> None:
    """Every thruster is within its limit and at least one sits exactly on it."""
    for tau in random_wrenches(20, 2000.0, seed):
        thrust = allocator.allocate(tau).thrust
        usage = np.abs(thrust) / LAYOUT.max_thrust_n
        assert usage.max() == pytest.approx(1.0, rel=1e-12)


def test_reverse_thrust_limit_is_the_thrust_magnitude_limit(allocator: ThrusterAllocator) -> None:
    """thrusters.max_thrust_n bounds reverse thrust too (reached at a higher propeller speed)."""
    result = allocator.allocate(np.array([-5000.0, 0, 0, 0, 0, 0, 0, 0, 0]))
    assert result.thrust.min() == pytest.approx(-LAYOUT.max_thrust_n[0])


def test_joint_torques_are_scaled_together(allocator: ThrusterAllocator) -> None:
    """Joint torques beyond a motor limit are scaled as one vector, each within its limit."""
    tau = np.array([0, 0, 0, 0, 0, 0, 300.0, -40.0, 10.0])
    result = allocator.allocate(tau)
    assert result.joint_scale == pytest.approx(100.0 / 300.0)
    np.testing.assert_allclose(result.joint_torques, tau[6:] * result.joint_scale)
    assert result.saturation_scale == 1.0


@pytest.mark.parametrize('tau', [np.zeros(8), np.zeros(10), np.array([math.nan] + [0.0] * 8)])
def test_malformed_generalized_force_is_rejected(
    allocator: ThrusterAllocator, tau: np.ndarray
) -> None:
    """A wrongly sized or non-finite tau_b raises ThrusterInputError and leaves the thrusters."""
    with pytest.raises(ThrusterInputError):
        allocator.step(tau, 1e-3)
    assert np.all(allocator.thrusters.omega == 0.0)


def test_actual_thrust_follows_the_allocation(allocator: ThrusterAllocator) -> None:
    """After the thruster transients the produced wrench T F_act equals the command."""
    tau = np.array([60.0, -20.0, 30.0, 4.0, -6.0, 8.0, 1.0, 2.0, 3.0])
    for _ in range(1000):
        out = allocator.step(tau, 1e-3)
    np.testing.assert_allclose(LAYOUT.thrust_matrix() @ out.thrust, tau[:6], rtol=1e-3, atol=1e-2)
    np.testing.assert_allclose(out.joint_torques, tau[6:])
    np.testing.assert_allclose(out.propeller_speed, out.reference_speed, rtol=1e-3, atol=1e-2)


def test_too_small_motor_current_is_rejected_at_start_up() -> None:
    """A current limit that cannot hold the thrust limit stops the allocator, naming it."""
    with pytest.raises(ThrusterParameterError, match=r'thruster\.max_motor_current_a'):
        ThrusterAllocator(
            AllocatorParameters(
                LAYOUT.thrust_matrix(),
                LAYOUT.max_thrust_n,
                JOINT_LIMITS,
                ThrusterModelParameters(max_motor_current=5.0),
            )
        )


def test_rank_deficient_layout_is_rejected() -> None:
    """Thrusters that cannot produce every vehicle wrench are a parameter error."""
    t = LAYOUT.thrust_matrix().copy()
    t[5, :] = 0.0
    with pytest.raises(ThrusterParameterError, match='rank'):
        AllocatorParameters(t, LAYOUT.max_thrust_n, JOINT_LIMITS)
