"""Analytic hydrodynamic coefficients: added mass of spheroid and cylinders, drag constants.

Sources: Lamb, Hydrodynamics (1932) sec. 373 for the prolate spheroid (formulas as quoted in
DESIGN.md); strip theory for slender cylinders (Newman, Marine Hydrodynamics, 1977, ch. 4):
per metre of length the added mass across the axis is rho pi r^2 and the cross-flow drag is
dF = -1/2 rho C_D (2 r) |v_n| v_n. Spatial quantities are ordered [linear; angular] as the
quasi-velocities of the paper's eq. 8 (surge, sway, heave, roll, pitch, yaw).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def lamb_coefficients(a: float, b: float) -> tuple[float, float, float]:
    """Lamb's k-factors (k1, k2, k') of a prolate spheroid with semi-axes a > b.

    ``k1 = alpha0 / (2 - alpha0)`` (axial), ``k2 = beta0 / (2 - beta0)`` (lateral) and
    ``k'`` the rotational factor such that the added moment of inertia about a lateral axis
    is ``k' I_y`` of the displaced fluid, ``I_y = m_f (a^2 + b^2) / 5``.

    Example:
        >>> [round(k, 4) for k in lamb_coefficients(0.5, 0.25)]
        [0.21, 0.7042, 0.2394]
    """
    e = math.sqrt(1.0 - (b * b) / (a * a))
    log_term = math.log((1.0 + e) / (1.0 - e))
    alpha0 = 2.0 * (1.0 - e * e) / e**3 * (0.5 * log_term - e)
    beta0 = 1.0 / (e * e) - (1.0 - e * e) / (2.0 * e**3) * log_term
    k1 = alpha0 / (2.0 - alpha0)
    k2 = beta0 / (2.0 - beta0)
    a2, b2 = a * a, b * b
    k_rot = (
        (b2 - a2) ** 2
        * (alpha0 - beta0)
        / ((2.0 * (b2 - a2) + (b2 + a2) * (beta0 - alpha0)) * (a2 + b2))
    )
    return k1, k2, k_rot


def spheroid_added_mass(a: float, b: float, rho: float) -> FloatArray:
    """Added-mass matrix M_A (6, 6) of a prolate spheroid at its centre, axis along x.

    Lamb: with m_f = 4/3 pi rho a b^2, X_u_dot = -alpha0 / (2 - alpha0) m_f,
    Y_v_dot = Z_w_dot = -beta0 / (2 - beta0) m_f, K_p_dot = 0 (body of revolution),
    M_q_dot = N_r_dot = -1/5 m_f (b^2 - a^2)^2 (alpha0 - beta0) /
    (2 (b^2 - a^2) + (b^2 + a^2)(beta0 - alpha0)). Returned as the positive matrix
    M_A = -diag(X_u_dot, ..., N_r_dot) of the paper's M_b (eq. 8).

    Args:
        a: Semi-axis along the body x axis (m), a > b.
        b: Semi-axis across (m).
        rho: Water density (kg/m^3).

    Returns:
        M_A (6, 6), symmetric positive semidefinite (zero in roll).
    """
    m_f = 4.0 / 3.0 * math.pi * rho * a * b * b
    k1, k2, k_rot = lamb_coefficients(a, b)
    inertia_f = m_f * (a * a + b * b) / 5.0
    return np.diag([k1 * m_f, k2 * m_f, k2 * m_f, 0.0, k_rot * inertia_f, k_rot * inertia_f])


def cylinder_added_mass(length: float, radius: float, rho: float) -> FloatArray:
    """Added-mass matrix (6, 6) of a slender cylinder along x from 0 to ``length``, at x = 0.

    Strip theory: each metre carries rho pi r^2 across the axis; the strip at x moves with
    v + r x sideways and w - q x vertically, which gives the translation-rotation coupling
    +-rho pi r^2 L^2 / 2 and rotary terms rho pi r^2 L^3 / 3. Axial: Lamb's k1 of the prolate
    spheroid with the cylinder's length and radius times the cylinder's displaced mass (a few
    per cent); roll: zero (a circular section carries no fluid in rotation).

    Args:
        length: Cylinder length (m), more than twice the radius.
        radius: Cylinder radius (m).
        rho: Water density (kg/m^3).

    Returns:
        M_A (6, 6) at the cylinder's end x = 0, in its own axes, [linear; angular] order.
    """
    m_per_length = rho * math.pi * radius * radius
    k1 = lamb_coefficients(0.5 * length, radius)[0]
    m_lat = m_per_length * length
    coupling = m_per_length * length * length / 2.0
    rotary = m_per_length * length**3 / 3.0
    added = np.zeros((6, 6))
    added[0, 0] = k1 * m_lat
    added[1, 1] = added[2, 2] = m_lat
    added[1, 5] = added[5, 1] = coupling
    added[2, 4] = added[4, 2] = -coupling
    added[4, 4] = added[5, 5] = rotary
    return added


def rigid_body_inertia(mass: float, com: FloatArray, inertia_com: FloatArray) -> FloatArray:
    """Spatial inertia (6, 6) at the frame origin, [linear; angular] order.

    Args:
        mass: Body mass (kg).
        com: Centre of mass in the frame (m).
        inertia_com: Rotational inertia (3, 3) about the centre of mass, frame axes (kg m^2).

    Returns:
        [[m I, -m [c]x], [m [c]x, I_c - m [c]x [c]x]] (Featherstone, reordered).
    """
    c = np.asarray(com, dtype=float)
    cx = np.array([[0.0, -c[2], c[1]], [c[2], 0.0, -c[0]], [-c[1], c[0], 0.0]])
    spatial = np.zeros((6, 6))
    spatial[:3, :3] = mass * np.eye(3)
    spatial[:3, 3:] = -mass * cx
    spatial[3:, :3] = mass * cx
    spatial[3:, 3:] = inertia_com - mass * cx @ cx
    return spatial


def cylinder_inertia(mass: float, length: float, radius: float) -> FloatArray:
    """Rotational inertia (3, 3) of a uniform solid cylinder about its centre, axis along x."""
    axial = 0.5 * mass * radius * radius
    transverse = mass * (3.0 * radius * radius + length * length) / 12.0
    return np.diag([axial, transverse, transverse])


def hull_quadratic_drag(
    a: float, b: float, rho: float, cd_trans: float, cd_rot: float
) -> FloatArray:
    """Quadratic drag coefficients (6,) of the hull: D_i |nu_i| nu_i for each quasi-velocity.

    Translation: 1/2 rho C_D A with the projected areas pi b^2 (surge) and pi a b (sway,
    heave). Rotation: cross-flow strips over the silhouette, 1/2 rho C_D int |s|^3 h(s) ds:
    for pitch and yaw, strips along x of height 2 b sqrt(1 - x^2/a^2), giving 8/15 a^4 b;
    for roll the same with a and b exchanged, 8/15 a b^4 (a body of revolution has no form
    drag in roll; this stands in for appendage drag the paper's one coefficient implies).

    Returns:
        Coefficients in N/(m/s)^2 (translation) and N m/(rad/s)^2 (rotation).
    """
    half_rho = 0.5 * rho
    surge = half_rho * cd_trans * math.pi * b * b
    lateral = half_rho * cd_trans * math.pi * a * b
    roll = half_rho * cd_rot * 8.0 / 15.0 * a * b**4
    pitch = half_rho * cd_rot * 8.0 / 15.0 * a**4 * b
    return np.array([surge, lateral, lateral, roll, pitch, pitch])


def strip_nodes(length: float, count: int) -> tuple[FloatArray, FloatArray]:
    """Gauss-Legendre strip centres x (m) and widths dx (m) along [0, length]."""
    xi, weights = np.polynomial.legendre.leggauss(count)
    return 0.5 * length * (xi + 1.0), 0.5 * length * weights
