"""Hydrodynamic coefficients of uvms_model.hydrodynamics against Lamb's table and quadrature."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from uvms_model.hydrodynamics import (
    cylinder_added_mass,
    hull_quadratic_drag,
    lamb_coefficients,
    spheroid_added_mass,
    strip_nodes,
)

# Lamb, Hydrodynamics (6th ed., 1932) sec. 373 table: a/b, k1, k2, k' (3 decimals; Lamb's
# ratios are themselves rounded, hence the 2e-3 tolerance).
LAMB_TABLE = [
    (1.50, 0.305, 0.621, 0.094),
    (2.00, 0.210, 0.704, 0.240),
    (2.99, 0.122, 0.803, 0.465),
    (4.99, 0.059, 0.895, 0.701),
    (9.97, 0.021, 0.960, 0.883),
]


@pytest.mark.parametrize(('ratio', 'k1', 'k2', 'k_rot'), LAMB_TABLE)
def test_spheroid_k_factors_match_lambs_table(
    ratio: float, k1: float, k2: float, k_rot: float
) -> None:
    """k1, k2, k' of a prolate spheroid agree with Lamb's table (to 2e-3)."""
    np.testing.assert_allclose(lamb_coefficients(ratio * 0.1, 0.1), (k1, k2, k_rot), atol=2e-3)


def test_nearly_spherical_spheroid_has_half_its_displaced_mass_added() -> None:
    """As a/b -> 1, k1 and k2 -> 1/2 (sphere) and k' -> 0."""
    k1, k2, k_rot = lamb_coefficients(1.001, 1.0)
    assert (k1, k2, k_rot) == pytest.approx((0.5, 0.5, 0.0), abs=2e-3)


def test_paper_hull_added_mass_scales_displaced_mass() -> None:
    """The 1.0 x 0.5 m hull: m_f = 134.2 kg, X_u_dot = -28.2 kg, Y_v_dot = Z_w_dot = -94.5 kg."""
    added = spheroid_added_mass(0.5, 0.25, 1025.0)
    m_f = 4.0 / 3.0 * np.pi * 1025.0 * 0.5 * 0.25**2
    np.testing.assert_allclose(
        np.diag(added)[:3], [0.21 * m_f, 0.7042 * m_f, 0.7042 * m_f], rtol=1e-3
    )
    assert added[3, 3] == 0.0
    np.testing.assert_allclose(added, added.T)


@pytest.mark.parametrize(('length', 'radius'), [(0.5, 0.05), (0.5, 0.035), (1.2, 0.1)])
def test_cylinder_added_mass_is_the_strip_integral_of_kinetic_energy(
    length: float, radius: float
) -> None:
    """nu^T M_A nu / 2 = integral of 1/2 rho pi r^2 |v_n(x)|^2 dx (+ Lamb's axial term)."""
    rho = 1025.0
    nu = np.array([0.3, -0.8, 0.5, 0.9, -1.3, 0.7])
    added = cylinder_added_mass(length, radius, rho)

    def strip(x: float) -> float:
        v = nu[:3] + np.cross(nu[3:], [x, 0.0, 0.0])
        return 0.5 * rho * np.pi * radius**2 * (v[1] ** 2 + v[2] ** 2)

    axial = (
        0.5
        * lamb_coefficients(length / 2, radius)[0]
        * rho
        * np.pi
        * radius**2
        * length
        * nu[0] ** 2
    )
    expected = quad(strip, 0.0, length)[0] + axial
    assert 0.5 * nu @ added @ nu == pytest.approx(expected, rel=1e-12)
    assert np.linalg.eigvalsh(added).min() > -1e-12


HULL_A, HULL_B, HULL_CD_TRANSLATION, HULL_CD_ROTATION = 0.5, 0.25, 1.05, 0.9


def _silhouette(half_length: float, half_width: float, power: int) -> float:
    """An ellipse's strips by quadrature: int |s|^power 2 w sqrt(1 - s^2/l^2) ds on [-l, l]."""
    return float(quad(lambda s: abs(s) ** power * 2.0 * half_width
                      * np.sqrt(1.0 - s**2 / half_length**2), -half_length, half_length)[0])


#: Per quasi-velocity: (drag coefficient, the integral over the projected silhouette).
#: Translation: the projected area (a disc of radius b across surge; an ellipse of semi-axes
#: a, b across sway and heave). Rotation: int |s|^3 h(s) ds over strips along the long axis
#: (pitch, yaw) and, a and b exchanged, along the short one (roll).
HULL_DRAG_INTEGRALS = {
    'surge': (0, HULL_CD_TRANSLATION, lambda: _silhouette(HULL_B, HULL_B, 0)),
    'sway': (1, HULL_CD_TRANSLATION, lambda: _silhouette(HULL_A, HULL_B, 0)),
    'heave': (2, HULL_CD_TRANSLATION, lambda: _silhouette(HULL_A, HULL_B, 0)),
    'roll': (3, HULL_CD_ROTATION, lambda: _silhouette(HULL_B, HULL_A, 3)),
    'pitch': (4, HULL_CD_ROTATION, lambda: _silhouette(HULL_A, HULL_B, 3)),
    'yaw': (5, HULL_CD_ROTATION, lambda: _silhouette(HULL_A, HULL_B, 3)),
}


@pytest.mark.parametrize('axis', list(HULL_DRAG_INTEGRALS))
def test_hull_drag_coefficient_is_the_integral_over_the_silhouette(axis: str) -> None:
    """D_i = 1/2 rho C_D times the silhouette integral of its axis, by quadrature (all six)."""
    rho = 1025.0
    index, cd, integral = HULL_DRAG_INTEGRALS[axis]
    coefficients = hull_quadratic_drag(HULL_A, HULL_B, rho, HULL_CD_TRANSLATION,
                                       HULL_CD_ROTATION)
    assert coefficients[index] == pytest.approx(0.5 * rho * cd * integral(), rel=1e-9)


@pytest.mark.parametrize('count', [1, 4, 8])
def test_strip_widths_sum_to_the_link_length(count: int) -> None:
    """Gauss-Legendre strips cover [0, L]: widths sum to L, centres inside."""
    x, dx = strip_nodes(0.5, count)
    assert dx.sum() == pytest.approx(0.5, rel=1e-14)
    assert np.all((x > 0.0) & (x < 0.5))
