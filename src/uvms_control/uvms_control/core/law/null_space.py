"""The null-space torque of the unified controller (paper eq. 20, 24, 26), compiled.

The paper drops the null-space part of eq. 24 (sec. 4.1 and 5.2.3). For a redundant UVMS
(6 + n DOF, a 3-D task; 9 and six for the paper's) τ = Jᵀ F_c alone leaves 3 + n directions
uncontrolled, so the vehicle pose and the arm posture drift, and the closed loop is not the
task-space model eq. 28 claims: premultiplying eq. 25 by J̃⁺ (eq. 27) discards the part of the
joint-space equation that Jᵀ F cannot produce. With ``null_space_enabled`` we apply the
joint-space law the paper derives from, eq. 20 with eq. 24 and a posture acceleration φ̈:

    τ = M̂_q [J⁺ (a_c - J̇ q̇) + N φ̈] + ζ̂_q + Jᵀ F_e,   N = I - J⁺ J,
    φ̈ = K_n (q_0 - q) - D_n q̇,   a_c = M̂⁻¹ (F_c - ζ̂ - F_e),

written as τ = Jᵀ F_c + τ_null with
τ_null = (I - Jᵀ J̃⁺) (M̂_q J⁺ (a_c - J̇ q̇) + ζ̂_q) + M̂_q N φ̈ (Jᵀ J̃⁺ = J⁺ J). Its first part lies
in the null space of J̃⁺ (it leaves the task-space command F_c of the paper unchanged and
restores the equation eq. 27 drops); the posture part M̂_q N φ̈ also has a row-space share,
which is exactly what cancels the inertial coupling of N φ̈ into the task. With an exact
model the end effector then follows Ẍ = a_c exactly, so eq. 21 (impedance) and eq. 36
(hybrid) hold, while the null-space coordinates settle to the posture q_0 captured at the
first step (vehicle pose and arm posture). With ``null_space_enabled = False`` the command is
τ = Jᵀ F_c, the paper's own.
"""

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
