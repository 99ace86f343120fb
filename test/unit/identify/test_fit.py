"""The hull fit: exact recovery, physical bounds, unidentifiable terms named."""

from __future__ import annotations

import numpy as np
import pytest
from uvms_identify.errors import IdentifyError
from uvms_identify.fit import fit_hull
from uvms_identify.regressor import (
    ADDED_MASS,
    LINEAR_DAMPING,
    PARAMETER_NAMES,
    QUADRATIC_DAMPING,
    hull_regressor,
    theta_from_hull,
)

TRUE = theta_from_hull(np.array([8.0, 9.5, 25.0, 0.25, 0.18, 0.3]),
                       np.array([18.0, 5.0, 40.0, 0.4, 1.1, 0.6]),
                       np.array([180.0, 250.0, 240.0, 1.5, 0.6, 2.0]),
                       140.0, np.array([0.02, 0.0, -0.012]))
PRIOR = theta_from_hull(np.array([6.36, 7.12, 18.68, 0.189, 0.135, 0.222]),
                        np.array([13.7, 0.0, 33.0, 0.0, 0.8, 0.0]),
                        np.array([141.0, 217.0, 190.0, 1.19, 0.47, 1.5]),
                        142.3, np.array([0.0184, 0.0, -0.01]))


def _motion(n: int = 3000, seed: int = 0, still: tuple[int, ...] = ()) -> tuple[
        np.ndarray, np.ndarray, np.ndarray]:
    """Smooth velocities (sums of sines), their exact derivatives, and gravity directions."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 60.0, n)
    nu = np.zeros((n, 6))
    nu_dot = np.zeros((n, 6))
    for axis in range(6):
        if axis in still:
            continue
        scale = 0.5 if axis < 3 else 0.4
        for _ in range(3):
            a, w, p = scale * rng.uniform(0.2, 0.6), rng.uniform(0.2, 2.0), rng.uniform(0, 6)
            nu[:, axis] += a * np.sin(w * t + p) + 0.3 * a
            nu_dot[:, axis] += a * w * np.cos(w * t + p)
    roll = 0.2 * np.sin(0.7 * t)
    pitch = 0.15 * np.sin(0.5 * t + 1.0)
    gravity = np.column_stack([-np.sin(pitch), np.cos(pitch) * np.sin(roll),
                               np.cos(pitch) * np.cos(roll)])
    return nu, nu_dot, gravity


def test_noise_free_synthetic_data_give_the_parameters_back_exactly() -> None:
    """Data made by known parameters, without noise, give every parameter back."""
    nu, nu_dot, gravity = _motion()
    phi = hull_regressor(nu, nu_dot, gravity)
    fit = fit_hull(phi @ TRUE, phi, PRIOR)
    np.testing.assert_allclose(fit.theta, TRUE, rtol=1e-6, atol=1e-9)
    assert all(fit.identified(j) for j in range(len(PARAMETER_NAMES))), fit.status
    np.testing.assert_allclose(fit.r2, 1.0, atol=1e-9)


def test_an_axis_never_excited_is_named_unidentifiable_and_keeps_the_prior() -> None:
    """Sway never moves: its terms are named unidentifiable, keep the prior, bounds hold."""
    nu, nu_dot, gravity = _motion(still=(1,))  # sway never moves
    phi = hull_regressor(nu, nu_dot, gravity)
    rng = np.random.default_rng(3)
    y = phi @ TRUE + rng.normal(0.0, [2.0, 2.0, 2.0, 0.05, 0.05, 0.05], (nu.shape[0], 6))
    fit = fit_hull(y, phi, PRIOR)
    for index in (ADDED_MASS.start + 1, LINEAR_DAMPING.start + 1, QUADRATIC_DAMPING.start + 1):
        assert fit.status[index] == 'unidentifiable: not excited', PARAMETER_NAMES[index]
        assert fit.theta[index] == PRIOR[index]
    assert (fit.theta[:19] >= 0.0).all()  # added mass, damping and buoyancy non-negative
    mass_matrix = np.diag(fit.theta[ADDED_MASS]) + np.diag([13.5, 13.5, 13.5, 0.26, 0.23, 0.37])
    assert np.linalg.eigvalsh(mass_matrix).min() > 0.0
    assert fit.identified(ADDED_MASS.start)
    assert abs(fit.theta[0] - TRUE[0]) < 0.1 * TRUE[0]


def test_bounds_hold_where_the_unconstrained_fit_would_go_negative() -> None:
    """A true zero damping under noise stays >= 0 (damping dissipates, M_A >= 0)."""
    nu, nu_dot, gravity = _motion(seed=5)
    phi = hull_regressor(nu, nu_dot, gravity)
    truth = TRUE.copy()
    truth[LINEAR_DAMPING.start + 1] = 0.0  # a true zero: noise pushes least squares below it
    rng = np.random.default_rng(11)
    y = phi @ truth + rng.normal(0.0, 5.0, (nu.shape[0], 6))
    fit = fit_hull(y, phi, PRIOR)
    assert (fit.theta[:19] >= 0.0).all()


def test_a_vehicle_at_rest_is_refused() -> None:
    """No term excited at all: refused with one line saying what to do."""
    n = 500
    nu = np.zeros((n, 6))
    gravity = np.tile([0.0, 0.0, 1.0], (n, 1))
    phi = hull_regressor(nu, nu, gravity)
    phi[:, :, 18:] = 0.0  # level and still: not even the buoyancy's direction varies
    with pytest.raises(IdentifyError, match='no hull term is excited'):
        fit_hull(np.zeros((n, 6)), phi, PRIOR)
