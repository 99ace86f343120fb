"""Tests of the allocation on T diag(η̂): dropped columns, weights and the rank check."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from uvms_model.thrusters import ThrusterLayout
from uvms_thrusters.allocation import (
    AllocatorParameters,
    ThrusterAllocator,
    weighted_pseudo_inverse,
)
from uvms_thrusters.errors import ThrusterInputError

from uvms_description.robots import robot_parameters
from uvms_model import UvmsParameters

#: Six unit thrusters along the wrench axes plus a seventh doubling surge (hand example).
T_HAND = np.hstack([np.eye(6), np.eye(6)[:, :1]])


def bluerov2_layout() -> ThrusterLayout:
    """The BlueROV2 Heavy's 8 thrusters (robots/bluerov2_alpha5/thrusters.yaml)."""
    values = robot_parameters('bluerov2_alpha5', 'simulator')
    params = UvmsParameters.from_flat_dict({k: v.value for k, v in values.items()
                                            if k.startswith('thrusters.')})
    return ThrusterLayout.from_parameters(params.thrusters)


def test_dropped_column_moves_surge_to_the_twin_thruster() -> None:
    """η̂_0 = 0: surge all on thruster 6, thruster 0 commanded zero (by hand: u = e_6)."""
    pinv, rank = weighted_pseudo_inverse(T_HAND, np.array([0.0, 1, 1, 1, 1, 1, 1]))
    assert rank == 6
    np.testing.assert_allclose(pinv @ [10.0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0, 10.0],
                               atol=1e-12)


def test_healthy_twins_share_surge_equally() -> None:
    """η̂ = 1: the minimum-norm split of a surge force over two equal thrusters is half each."""
    pinv, _ = weighted_pseudo_inverse(T_HAND, np.ones(7))
    np.testing.assert_allclose(pinv @ [10.0, 0, 0, 0, 0, 0], [5.0, 0, 0, 0, 0, 0, 5.0],
                               atol=1e-12)


def test_weak_thruster_is_used_less() -> None:
    """η̂_0 = 0.5: min u_0² + u_6² s.t. 0.5 u_0 + u_6 = F gives u_0 = 0.4 F, u_6 = 0.8 F."""
    pinv, _ = weighted_pseudo_inverse(T_HAND, np.array([0.5, 1, 1, 1, 1, 1, 1]))
    u = pinv @ [10.0, 0, 0, 0, 0, 0]
    np.testing.assert_allclose(u, [4.0, 0, 0, 0, 0, 0, 8.0], atol=1e-12)
    assert 0.5 * u[0] + u[6] == pytest.approx(10.0)


def test_losing_both_surge_thrusters_loses_rank() -> None:
    """Without thrusters 0 and 6 nothing pushes along x: rank 5."""
    _, rank = weighted_pseudo_inverse(T_HAND, np.array([0.0, 1, 1, 1, 1, 1, 0.0]))
    assert rank == 5


@pytest.mark.parametrize('failed', range(8))
def test_bluerov2_heavy_keeps_rank_six_after_any_single_failure(failed: int) -> None:
    """Each of the 8 thrusters can fail alone and the vehicle stays fully actuated."""
    layout = bluerov2_layout()
    allocator = ThrusterAllocator(AllocatorParameters(
        layout.thrust_matrix(), layout.max_thrust_n, np.full(4, 9.0)))
    eta = np.ones(8)
    eta[failed] = 0.0
    assert allocator.set_effectiveness(eta) == 6
    assert allocator.fully_actuated
    tau = np.array([5.0, -3.0, 4.0, 0.5, -0.4, 0.3, 0.0, 0.0, 0.0, 0.0])
    result = allocator.allocate(tau)
    assert result.saturation_scale == 1.0
    assert result.thrust[failed] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(layout.thrust_matrix() @ result.thrust, tau[:6], atol=1e-9)


@pytest.mark.parametrize('pair', [*itertools.combinations(range(4), 2),
                                  *itertools.combinations(range(4, 8), 2)])
def test_bluerov2_heavy_loses_rank_with_two_horizontals_or_two_verticals(
    pair: tuple[int, int],
) -> None:
    """Two failed horizontals (or verticals) leave two in that plane, too few for 3 DOF."""
    layout = bluerov2_layout()
    eta = np.ones(8)
    eta[list(pair)] = 0.0
    _, rank = weighted_pseudo_inverse(layout.thrust_matrix(), eta)
    assert rank < 6


def test_rank_loss_allocates_the_reachable_part_in_least_squares() -> None:
    """Rank 5: the wrench is met as closely as possible and the allocator says so."""
    allocator = ThrusterAllocator(AllocatorParameters(
        np.hstack([np.eye(6), np.eye(6)[:, :2]]), np.full(8, 100.0), np.full(3, 10.0)))
    assert allocator.set_effectiveness([0.0, 1, 1, 1, 1, 1, 0.0, 1]) == 5
    assert not allocator.fully_actuated
    result = allocator.allocate([10.0, 2.0, 3.0, 0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(result.achieved_wrench, [0.0, 2.0, 3.0, 0, 0, 0], atol=1e-12)


def test_saturation_scales_the_weighted_allocation_as_a_whole() -> None:
    """A dropped column still gets direction-preserving saturation against the limits."""
    allocator = ThrusterAllocator(AllocatorParameters(
        T_HAND, np.full(7, 100.0), np.full(3, 10.0)))
    allocator.set_effectiveness([0.0, 1, 1, 1, 1, 1, 1])
    result = allocator.allocate([300.0, 50.0, 0, 0, 0, 0, 0, 0, 0])
    assert result.saturation_scale == pytest.approx(1.0 / 3.0)
    np.testing.assert_allclose(result.achieved_wrench, [100.0, 50.0 / 3.0, 0, 0, 0, 0],
                               atol=1e-9)


def test_full_effectiveness_restores_the_plain_pseudo_inverse() -> None:
    """Back to η̂ = 1 the allocation is T⁺ tau again, to the last bit."""
    layout = ThrusterLayout.from_parameters()
    params = AllocatorParameters(layout.thrust_matrix(), layout.max_thrust_n, np.full(3, 50.0))
    fresh, used = ThrusterAllocator(params), ThrusterAllocator(params)
    used.set_effectiveness([0.3, 1, 1, 1, 1, 1, 1, 1])
    used.set_effectiveness(np.ones(8))
    tau = np.array([40.0, -10.0, 25.0, 3.0, -2.0, 1.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(used.allocate(tau).thrust, fresh.allocate(tau).thrust)


@pytest.mark.parametrize('eta', [[1.0] * 7, [1.2] + [1.0] * 7, [np.nan] + [1.0] * 7])
def test_effectiveness_outside_zero_one_is_rejected(eta: list[float]) -> None:
    """η̂ must be p values in [0, 1]."""
    layout = ThrusterLayout.from_parameters()
    allocator = ThrusterAllocator(AllocatorParameters(
        layout.thrust_matrix(), layout.max_thrust_n, np.full(3, 50.0)))
    with pytest.raises(ThrusterInputError, match='effectiveness'):
        allocator.set_effectiveness(eta)
