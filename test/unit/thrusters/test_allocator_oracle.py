"""The compiled allocator step agrees with the previous numpy implementation (the oracle).

``reference_allocator.ReferenceAllocator`` computes eq. 10-15 vectorised in numpy, with
T⁺ from ``numpy.linalg.pinv``; the allocator computes them per thruster in Numba kernels.
"""

from __future__ import annotations

import numpy as np
import pytest
from reference_allocator import ReferenceAllocator
from uvms_model.thrusters import ThrusterLayout
from uvms_thrusters.allocation import AllocatorParameters, ThrusterAllocator

LAYOUT = ThrusterLayout.from_parameters()
PARAMS = AllocatorParameters(LAYOUT.thrust_matrix(), LAYOUT.max_thrust_n,
                             np.array([100.0, 80.0, 50.0]))


@pytest.mark.parametrize('scale', [20.0, 400.0])
def test_allocation_matches_the_reference(scale: float) -> None:
    """Thrusts, torques and both saturation scales equal the oracle's, saturated or not."""
    allocator, reference = ThrusterAllocator(PARAMS), ReferenceAllocator(PARAMS)
    saturated = 0
    for tau_b in np.random.default_rng(7).normal(0.0, scale, (200, 9)):
        result = allocator.allocate(tau_b)
        thrust, joints, thrust_scale, joint_scale = reference.allocate(tau_b)
        np.testing.assert_allclose(result.thrust, thrust, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(result.joint_torques, joints, rtol=1e-12, atol=1e-12)
        assert result.saturation_scale == pytest.approx(thrust_scale, rel=1e-12)
        assert result.joint_scale == pytest.approx(joint_scale, rel=1e-12)
        saturated += result.saturation_scale < 1.0
    assert (saturated > 100) == (scale > 100.0)  # both regimes are what they claim


def test_thruster_dynamics_match_the_reference_over_a_manoeuvre() -> None:
    """Ω, u_p, Ω_r, i_m and thrust follow the oracle through steps, reversals and long dt.

    Commands change sign and saturate; dt of 0, 2 ms (one Euler sub-step) and 11 ms (several)
    are mixed, so every branch of the kernels runs.
    """
    allocator, reference = ThrusterAllocator(PARAMS), ReferenceAllocator(PARAMS)
    rng = np.random.default_rng(11)
    commands = rng.normal(0.0, 300.0, (40, 9))
    for k in range(600):
        tau_b, dt = commands[k // 15], (0.002, 0.0, 0.011, 0.002)[k % 4]
        output = allocator.step(tau_b, dt)
        expected = reference.step(tau_b, dt)
        np.testing.assert_allclose(output.thrust, expected, rtol=1e-9, atol=1e-9)
        for name, value in (('propeller_speed', reference.omega),
                            ('reference_speed', reference.omega_r),
                            ('motor_current', reference.motor_current)):
            np.testing.assert_allclose(getattr(output, name), value, rtol=1e-9, atol=1e-9,
                                       err_msg=name)
    assert np.abs(reference.thrust).max() > 50.0  # the propellers did turn
