"""M, ζ, J and J̇ q̇ in generalized coordinates from the body-form terms (paper eq. 4, 18, 22-23).

With B = blockdiag(J1, J2, I) (eq. 4, sec. 3.2), q̇ = B w and the correction
c = B⁻¹ Ḃ w = [ω x v; J2⁻¹ J̇2 ω; 0]:

    M = B⁻ᵀ M_b B⁻¹,   ζ = B⁻ᵀ (bias_b - M_b c)   (eq. 18-19),
    J = J_w B⁻¹,       J̇ q̇ = J̇_w w - J_w c       (eq. 22-23),

with J_w the end-effector Jacobian with respect to w and J̇_w w its classical acceleration at
ẇ = 0. One compiled kernel (Numba) does all of it, since at 9 x 9 the products cost less than
the numpy calls that would make them.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from uvms_model.jit import kernel

FloatArray = NDArray[np.float64]

@kernel
def matmul(a: FloatArray, b: FloatArray) -> FloatArray:
    """A b as a new array, by loops (any memory layout; no BLAS call at these sizes)."""
    result = np.zeros((a.shape[0], b.shape[1]))
    for i in range(a.shape[0]):
        for k in range(a.shape[1]):
            a_ik = a[i, k]
            if a_ik != 0.0:
                for j in range(b.shape[1]):
                    result[i, j] += a_ik * b[k, j]
    return result


@kernel
def matvec(a: FloatArray, x: FloatArray) -> FloatArray:
    """A x as a new array, by loops."""
    result = np.zeros(a.shape[0])
    for i in range(a.shape[0]):
        total = 0.0
        for k in range(a.shape[1]):
            total += a[i, k] * x[k]
        result[i] = total
    return result


@kernel
def generalized_terms(
    q: FloatArray, w: FloatArray, mass_full: FloatArray, bias_full: FloatArray,
    slider_mass_inverse: FloatArray, jac_w: FloatArray, acc_w: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """J, J̇ q̇, M, ζ, B and q̇ (new arrays) from the body-form terms (eq. 4, 18, 22-23).

    M_b and bias_b of eq. 8 come from the dynamic model's M and bias with the added mass's
    sliders (rows s past the ninth; they transmit no force) eliminated:
    M_b = M_rr - M_rs M_ss⁻¹ M_sr, bias_b = b_r - M_rs M_ss⁻¹ b_s, M_ss diagonal.

    Args:
        q: Generalized coordinates (9,); the pitch is regular (the caller checks it).
        w: Quasi-velocities (9,).
        mass_full: The dynamic model's mass matrix (9 + n_s, 9 + n_s) by CRBA.
        bias_full: Its bias (9 + n_s,) by RNEA at zero acceleration (C w + D w + G).
        slider_mass_inverse: M_ss⁻¹ (n_s,).
        jac_w: End-effector Jacobian (3, 9) with respect to w, map_ned.
        acc_w: J̇_w w (3,), map_ned.
    """
    n = 9
    mass_b = np.empty((n, n))
    bias_b = np.empty(n)
    for i in range(n):
        total = bias_full[i]
        for s in range(slider_mass_inverse.shape[0]):
            total -= mass_full[i, n + s] * slider_mass_inverse[s] * bias_full[n + s]
        bias_b[i] = total
        for j in range(n):
            total = mass_full[i, j]
            for s in range(slider_mass_inverse.shape[0]):
                total -= mass_full[i, n + s] * slider_mass_inverse[s] * mass_full[j, n + s]
            mass_b[i, j] = total
    c4, s4 = math.cos(q[3]), math.sin(q[3])
    c5, s5 = math.cos(q[4]), math.sin(q[4])
    c6, s6 = math.cos(q[5]), math.sin(q[5])
    # B and B⁻¹ (9, 9): rot_ned_from_body (J1), J2 and its inverse, identity for the arm.
    b = np.zeros((n, n))
    b_inv = np.zeros((n, n))
    rot = np.array((
        (c5 * c6, -s6 * c4 + s4 * s5 * c6, s4 * s6 + s5 * c4 * c6),
        (s6 * c5, c4 * c6 + s4 * s5 * s6, -s4 * c6 + s5 * s6 * c4),
        (-s5, s4 * c5, c4 * c5),
    ))  # fmt: skip
    t5 = s5 / c5
    for i in range(3):
        for j in range(3):
            b[i, j] = rot[i, j]
            b_inv[i, j] = rot[j, i]
    b[3, 3], b[3, 4], b[3, 5] = 1.0, s4 * t5, c4 * t5
    b[4, 4], b[4, 5] = c4, -s4
    b[5, 4], b[5, 5] = s4 / c5, c4 / c5
    b_inv[3, 3], b_inv[3, 5] = 1.0, -s5
    b_inv[4, 4], b_inv[4, 5] = c4, s4 * c5
    b_inv[5, 4], b_inv[5, 5] = -s4, c4 * c5
    for i in range(6, n):
        b[i, i] = 1.0
        b_inv[i, i] = 1.0
    # c = B⁻¹ Ḃ w = [ω x v; J2⁻¹ J̇2 ω; 0].
    c = np.zeros(n)
    v0, v1, v2, w0, w1, w2 = w[0], w[1], w[2], w[3], w[4], w[5]
    c[0], c[1], c[2] = w1 * v2 - w2 * v1, w2 * v0 - w0 * v2, w0 * v1 - w1 * v0
    a = s4 * w1 + c4 * w2
    bb = c4 * w1 - s4 * w2
    phi_dot = w0 + a * t5
    u0 = phi_dot * bb * t5 + bb * a / (c5 * c5)
    u1 = -phi_dot * a
    u2 = phi_dot * bb / c5 + bb * s5 * a / (c5 * c5)
    c[3], c[4], c[5] = u0 - s5 * u2, c4 * u1 + s4 * c5 * u2, -s4 * u1 + c4 * c5 * u2
    mass_b_inv = matmul(mass_b, b_inv)
    jac = matmul(jac_w, b_inv)
    mass = matmul(b_inv.T, mass_b_inv)
    zeta = matvec(b_inv.T, bias_b - matvec(mass_b, c))
    j_dot_q_dot = acc_w - matvec(jac_w, c)
    q_dot = matvec(b, w)
    return jac, j_dot_q_dot, mass, zeta, b, q_dot
