"""The null-space torque of the unified controller (paper eq. 20, 24, 26), compiled."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from uvms_model.jit import kernel
from uvms_model.loop_products import matvec

FloatArray = npt.NDArray[np.float64]


@kernel
def null_space_torque(
    J: FloatArray, Jt_pinv: FloatArray, J_dot_q_dot: FloatArray, M: FloatArray,
    zeta: FloatArray, Jt_pinv_zeta: FloatArray, M_hat: FloatArray, mass_scale: float,
    q: FloatArray, q0: FloatArray, q_dot: FloatArray, gains: FloatArray,
    commands: FloatArray, tau: FloatArray,
) -> None:
    """τ = Jᵀ (F_c - M̂ y - J̃⁺ ζ) + ζ + M̂_q (φ̈ + J⁺ (y - J φ̈)) into ``tau`` (eq. 20, 24, 26).

    y = a_c - J̇ q̇, φ̈ = K_n (q_0 - q) - D_n q̇ with the attitude error taken the short way
    round, M̂_q = s M; ``gains`` rows are K_n and D_n, ``commands`` is [F_c, a_c].
    """
    error = q0 - q
    for k in (3, 4, 5):  # Euler angles wrap: hold the attitude the short way round
        if abs(error[k]) > math.pi:
            error[k] = (error[k] + math.pi) % (2.0 * math.pi) - math.pi
    phi_ddot = gains[0] * error - gains[1] * q_dot
    y = commands[3:] - J_dot_q_dot
    w3 = commands[:3] - matvec(M_hat, y) - Jt_pinv_zeta
    s9 = phi_ddot + matvec(Jt_pinv.T, y - matvec(J, phi_ddot))
    tau[:] = matvec(J.T, w3) + mass_scale * matvec(M, s9) + zeta
