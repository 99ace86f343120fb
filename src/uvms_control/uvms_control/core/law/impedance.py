"""Torque-based impedance law in the task space (paper eq. 21, 29-31)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from uvms_control.core.law.task_space import inverse_3x3

FloatArray = npt.NDArray[np.float64]


class ImpedanceLaw:
    """F_IP = M̂ U + ζ̂ + F_e with U = Ẍ_d + P⁻¹ [B_d (Ẋ_d - Ẋ) + K (X_d - X) - F_e] (eq. 29-31).

    With M̂ = M̃ and ζ̂ = ζ̃ the closed loop obeys the target impedance
    P Ë + B_d Ė + K E = F_e, E = X_d - X (eq. 21, 34).

    Args:
        inertia: P (3, 3), symmetric positive definite (kg).
        damping: B_d (3, 3), symmetric positive definite (N s/m).
        stiffness: K (3, 3), symmetric positive definite (N/m).

    Example:
        >>> law = ImpedanceLaw(np.eye(3), 2.0 * np.eye(3), np.eye(3))
        >>> law.acceleration(np.ones(3), np.zeros(3), np.zeros(3), np.zeros(3)).tolist()
        [1.0, 1.0, 1.0]
    """

    def __init__(self, inertia: FloatArray, damping: FloatArray, stiffness: FloatArray) -> None:
        self.P = inertia
        self.B_d = damping
        self.K = stiffness
        self._P_inv = inverse_3x3(inertia)
        self._P_inv_B = self._P_inv @ damping
        self._P_inv_K = self._P_inv @ stiffness

    def acceleration(
        self, E: FloatArray, E_dot: FloatArray, X_d_ddot: FloatArray, F_e: FloatArray
    ) -> FloatArray:
        """U of eq. 30 (m/s²), from E = X_d - X, Ė = Ẋ_d - Ẋ, Ẍ_d and F_e."""
        result: FloatArray = (
            X_d_ddot + self._P_inv_B @ E_dot + self._P_inv_K @ E - self._P_inv @ F_e
        )
        return result

    def linear_map(self) -> FloatArray:
        """A (3, 12) with U = A [E; Ė; Ẍ_d; F_e] (eq. 30): [P⁻¹K, P⁻¹B_d, I, -P⁻¹]."""
        return np.hstack((self._P_inv_K, self._P_inv_B, np.eye(3), -self._P_inv))

    @staticmethod
    def force(
        M_hat: FloatArray, zeta_hat: FloatArray, U: FloatArray, F_e: FloatArray
    ) -> FloatArray:
        """F_IP = M̂ U + ζ̂ + F_e (eq. 29) (N)."""
        result: FloatArray = M_hat @ U + zeta_hat + F_e
        return result
