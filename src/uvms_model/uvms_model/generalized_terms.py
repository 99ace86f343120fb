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
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from uvms_model.coordinates import velocity_transforms
from uvms_model.jit import kernel
from uvms_model.loop_products import matmul, matvec

FloatArray = NDArray[np.float64]


class TaskSpaceTerms(NamedTuple):
    """What the controller needs at one state (q, q_dot), from one pass of the model.

    Attributes:
        X: End-effector position in map_ned (3,) (m).
        J: End-effector Jacobian (3, 6 + n) in map_ned with respect to q_dot (eq. 22).
        J_dot_q_dot: J_dot q_dot (3,) (m/s^2), eq. 23.
        M: Mass matrix M(q) (6 + n, 6 + n) in generalized coordinates (eq. 18).
        zeta: Bias zeta(q, q_dot) (6 + n,) of eq. 19.
        B: Velocity transform B(q) (6 + n, 6 + n) of eq. 4.
        rot_ned_from_ee: ee_link axes in map_ned (3, 3).
        q_dot: Generalized velocities (6 + n,) of the state.
    """

    X: FloatArray
    J: FloatArray
    J_dot_q_dot: FloatArray
    M: FloatArray
    zeta: FloatArray
    B: FloatArray
    rot_ned_from_ee: FloatArray
    q_dot: FloatArray


@kernel
def b_inverse_b_dot_w(q: FloatArray, w: FloatArray) -> FloatArray:
    """C = B⁻¹ Ḃ w (6 + n,) = [ω x v; J2⁻¹ J̇2 ω; 0] with η̇ = J2 ω (the pitch is regular)."""
    c4, s4 = math.cos(q[3]), math.sin(q[3])
    c5, s5 = math.cos(q[4]), math.sin(q[4])
    t5 = s5 / c5
    c = np.zeros(q.shape[0])
    v0, v1, v2, w0, w1, w2 = w[0], w[1], w[2], w[3], w[4], w[5]
    c[0], c[1], c[2] = w1 * v2 - w2 * v1, w2 * v0 - w0 * v2, w0 * v1 - w1 * v0
    a = s4 * w1 + c4 * w2
    b = c4 * w1 - s4 * w2
    phi_dot = w0 + a * t5
    u0 = phi_dot * b * t5 + b * a / (c5 * c5)
    u1 = -phi_dot * a
    u2 = phi_dot * b / c5 + b * s5 * a / (c5 * c5)
    c[3], c[4], c[5] = u0 - s5 * u2, c4 * u1 + s4 * c5 * u2, -s4 * u1 + c4 * c5 * u2
    return c


@kernel
def generalized_terms(
    q: FloatArray, w: FloatArray, mass_b: FloatArray, bias_b: FloatArray,
    jac_w: FloatArray, acc_w: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """J, J̇ q̇, M, ζ, B and q̇ (new arrays) from the body-form terms (eq. 4, 18, 22-23).

    Args:
        q: Generalized coordinates (6 + n,); the pitch is regular (the caller checks it).
        w: Quasi-velocities (6 + n,).
        mass_b: M_b (6 + n, 6 + n) of eq. 8.
        bias_b: C_b w + D_b w + G_b (6 + n,) of eq. 8.
        jac_w: End-effector Jacobian (3, 6 + n) with respect to w, map_ned.
        acc_w: J̇_w w (3,), map_ned.
    """
    b, b_inv = velocity_transforms(q)
    c = b_inverse_b_dot_w(q, w)
    jac = matmul(jac_w, b_inv)
    mass = matmul(b_inv.T, matmul(mass_b, b_inv))
    zeta = matvec(b_inv.T, bias_b - matvec(mass_b, c))
    j_dot_q_dot = acc_w - matvec(jac_w, c)
    return jac, j_dot_q_dot, mass, zeta, b, matvec(b, w)
