"""Task-space model of the UVMS: end-effector dynamics M̃ Ẍ + ζ̃ = F - F_e (paper eq. 22-28)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from uvms_model.jit import kernel
from uvms_model.loop_products import matmul, matvec

from uvms_model import TaskSpaceTerms, UvmsModel

FloatArray = npt.NDArray[np.float64]


def inverse_3x3(a: FloatArray) -> FloatArray:
    """Inverse of a 3x3 matrix by its adjugate (cheaper than a general LU for one 3x3).

    The callers pass symmetric positive-definite matrices (J Jᵀ, M̃, M̂); a singular one (the
    arm at a kinematic singularity) gives inf/nan, which the controller rejects.
    """
    return adjugate_inverse_3x3(np.asarray(a, dtype=np.float64))


@dataclass(slots=True)
class TaskSpaceModel:
    """Task-space quantities at one state (q, q_dot).

    Attributes:
        X: end-effector position in map_ned (3,) (m).
        X_dot: end-effector velocity J q_dot (3,) (m/s), eq. 22.
        J: end-effector Jacobian (3, 6 + n), eq. 22.
        J_dot_q_dot: J_dot q_dot (3,) (m/s²), eq. 23.
        J_pinv: J⁺ = Jᵀ (J Jᵀ)⁻¹ (6 + n, 3), eq. 24.
        Jt_pinv: J̃⁺ = (Jᵀ)⁺ = (J Jᵀ)⁻¹ J (3, 6 + n), eq. 27.
        M: joint-space inertia M(q) (6 + n, 6 + n), eq. 18.
        zeta: joint-space bias ζ(q, q_dot) (6 + n,), eq. 19.
        M_tilde: task-space inertia M̃ = J̃⁺ M J⁺ (3, 3) (kg), eq. 28.
        zeta_tilde: task-space bias ζ̃ = J̃⁺ ζ - M̃ J̇ q̇ (3,) (N), eq. 28.
        Jt_pinv_zeta: J̃⁺ ζ (3,) (N), the first term of ζ̃.
    """

    X: FloatArray
    X_dot: FloatArray
    J: FloatArray
    J_dot_q_dot: FloatArray
    J_pinv: FloatArray
    Jt_pinv: FloatArray
    M: FloatArray
    zeta: FloatArray
    M_tilde: FloatArray
    zeta_tilde: FloatArray
    Jt_pinv_zeta: FloatArray


def task_space_model(
    model: UvmsModel, q: FloatArray, q_dot: FloatArray, X: FloatArray | None = None
) -> TaskSpaceModel:
    """M̃ = J̃⁺ M J⁺ and ζ̃ = J̃⁺ ζ - M̃ J̇ q̇ at (q, q_dot) (paper eq. 27-28).

    The paper writes the last term M̃ J̇ J⁺ Ẋ, which equals M̃ J̇ q̇ only when q̇ has no
    null-space component (J⁺ Ẋ = J⁺ J q̇ is the row-space part of q̇). The exact product J̇ q̇
    is what eq. 23 and 25 contain, so that is what we use.

    Args:
        model: the controller's UVMS model.
        q: generalized coordinates (6 + n,).
        q_dot: generalized velocities (6 + n,).
        X: unused (the model's one pass gives the end-effector position); kept for callers.

    Example:
        >>> model = UvmsModel()
        >>> q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.5, -0.8])
        >>> ts = task_space_model(model, q, np.zeros(model.n_dof))
        >>> bool(np.allclose(ts.J @ ts.J_pinv, np.eye(3)))
        True
    """
    return task_space_model_from_terms(model.task_space_terms(q, q_dot))


def task_space_model_from_terms(terms: TaskSpaceTerms) -> TaskSpaceModel:
    """Eq. 24-28 from the model's terms at one state: J⁺, J̃⁺, M̃, ζ̃ and Ẋ = J q̇ (eq. 22)."""
    Jt_pinv, M_tilde, zeta_tilde, Jt_pinv_zeta, X_dot = task_space_products(
        terms.J, terms.M, terms.zeta, terms.J_dot_q_dot, terms.q_dot
    )
    return TaskSpaceModel(
        X=terms.X,
        X_dot=X_dot,
        J=terms.J,
        J_dot_q_dot=terms.J_dot_q_dot,
        J_pinv=Jt_pinv.T,
        Jt_pinv=Jt_pinv,
        M=terms.M,
        zeta=terms.zeta,
        M_tilde=M_tilde,
        zeta_tilde=zeta_tilde,
        Jt_pinv_zeta=Jt_pinv_zeta,
    )


@kernel
def task_space_products(
    J: FloatArray, M: FloatArray, zeta: FloatArray, J_dot_q_dot: FloatArray, q_dot: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """J̃⁺ = (J Jᵀ)⁻¹ J, M̃ = J̃⁺ M J̃⁺ᵀ, ζ̃ = J̃⁺ ζ - M̃ J̇ q̇ (eq. 27-28), J̃⁺ ζ and Ẋ = J q̇.

    New arrays. A singular J Jᵀ (the arm at a kinematic singularity) gives inf/nan, which the
    controller rejects.
    """
    pinv = matmul(adjugate_inverse_3x3(matmul(J, J.T)), J)  # J̃⁺ (3, n)
    m_tilde = matmul(pinv, matmul(M, pinv.T))
    pinv_zeta = matvec(pinv, zeta)
    zeta_tilde = pinv_zeta - matvec(m_tilde, J_dot_q_dot)
    x_dot = matvec(J, q_dot)
    return pinv, m_tilde, zeta_tilde, pinv_zeta, x_dot


@kernel
def adjugate_inverse_3x3(a: FloatArray) -> FloatArray:
    """Inverse of a 3x3 array by its adjugate; inf/nan for a singular one (compiled)."""
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    k = 1.0 / det if det != 0.0 else np.inf
    result = np.empty((3, 3))
    result[0, 0] = c00 * k
    result[0, 1] = (a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]) * k
    result[0, 2] = (a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]) * k
    result[1, 0] = c01 * k
    result[1, 1] = (a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]) * k
    result[1, 2] = (a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]) * k
    result[2, 0] = c02 * k
    result[2, 1] = (a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]) * k
    result[2, 2] = (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]) * k
    return result
