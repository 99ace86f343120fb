"""Hybrid position/force law (paper eq. 35-39): PD position control, PID force control."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from uvms_control.core.errors import ControlParameterError
from uvms_control.core.law.filters import DirtyDerivative

FloatArray = npt.NDArray[np.float64]


class HybridLaw:
    """F_H = (I - S) F_p + S F_f + ζ̂ + F_e (eq. 35) with S = n nᵀ.

    Position (eq. 37): F_p = M̂ (I - S)(Ẍ_d + K_pv ΔẊ + K_pp ΔX), ΔX = X_d - X. The position
    law acts on the position subspace, as eq. 1 writes it (Ψ[(1 - S) Δx]). Selecting only
    after M̂, as eq. 35 alone would, lets the normal part of the position error (the reference
    runs inside the wall) leak into the tangential motion through the off-diagonal terms of
    M̂: the end effector then lags or leads the reference along the wall in steady contact.
    Force (eq. 39), along n: F_f = M̂ n (c F̈_d + K_fp ΔF + K_fi ∫ΔF dt + K_fv ΔḞ),
    ΔF = F_d - n·F_e. The force gains act on the normal component only (gain matrices
    K_f = k_f S), so tangential force noise cannot reach the normal direction through the
    off-diagonal terms of M̂. The paper adds F̈_d (N/s²) to an acceleration; c (m/N) makes that
    dimensionally sound (c = 1/K_e would be exact for a spring wall; see the parameters).

    The force derivative ΔḞ = Ḟ_d - d(n·F_e)/dt uses the analytic Ḟ_d of the set-point and a
    filtered ("dirty") derivative of the measured force: the paper (sec. 6) warns that
    differentiating the sensor signal amplifies its noise.

    Anti-windup (conditional integration plus a clamp): the integral runs only in contact
    (n·F_e above the contact threshold), while a force set-point is active and the hybrid law
    is in charge (the constrained phase, W <= 0.1): out of contact the force error cannot be
    reduced by pushing, and during the fuzzy hand-over (0.1 < W < 1) the impedance law still
    holds the force back, so an integral running then only winds up and overshoots F_d once
    the hybrid law takes over (15 % on the K_e = 1e4 wall when it ran for any W < 1). It is
    also clamped to ±``integral_limit`` (N s), which bounds what it can command if the force
    cannot be reached (thruster or motor saturation, a receding wall).

    Example:
        >>> law = HybridLaw(np.array([1.0, 0.0, 0.0]), 100.0 * np.eye(3), 20.0 * np.eye(3),
        ...                 0.01, 0.0, 0.0, 0.0, 20.0, 10.0)
        >>> law.force_acceleration(100.0, 0.0, 0.0, 90.0, 0.001, False)
        0.1
    """

    def __init__(
        self,
        force_direction: FloatArray,
        position_kp: FloatArray,
        position_kd: FloatArray,
        force_kp: float,
        force_ki: float,
        force_kd: float,
        feedforward_compliance: float,
        derivative_cutoff_hz: float,
        integral_limit: float,
    ) -> None:
        for name, value in (
            ('hybrid.force_kp', force_kp),
            ('hybrid.force_ki', force_ki),
            ('hybrid.force_kd', force_kd),
            ('hybrid.force_feedforward_compliance_m_n', feedforward_compliance),
            ('hybrid.force_integral_limit_n_s', integral_limit),
        ):
            if not (math.isfinite(value) and value >= 0.0):
                raise ControlParameterError(name, value, '[0, inf)')
        n = np.asarray(force_direction, dtype=np.float64)
        self.n = n / float(np.linalg.norm(n))
        self.S = np.outer(self.n, self.n)
        self.I_minus_S = np.eye(3) - self.S
        self.K_pp = position_kp
        self.K_pv = position_kd
        self.k_fp = force_kp
        self.k_fi = force_ki
        self.k_fv = force_kd
        self.c_ff = feedforward_compliance
        self.integral_limit = integral_limit
        self._derivative = DirtyDerivative(derivative_cutoff_hz)
        self.integral = 0.0

    def carry_state_from(self, other: HybridLaw) -> None:
        """Continue another law's integral and force-derivative filter (new gains, no bump).

        The integral is clamped to this law's limit; the filter keeps its input and output
        (at a new cut-off, its time constant changes from the next sample on).
        """
        self.integral = min(max(other.integral, -self.integral_limit), self.integral_limit)
        self._derivative.continue_from(other._derivative)

    @property
    def force_gains(self) -> tuple[float, float, float, float]:
        """(K_fp, K_fi, K_fv, c) of eq. 39, the gains a run-time change ramps."""
        return self.k_fp, self.k_fi, self.k_fv, self.c_ff

    @force_gains.setter
    def force_gains(self, gains: tuple[float, float, float, float]) -> None:
        self.k_fp, self.k_fi, self.k_fv, self.c_ff = gains

    def restart_derivative(self) -> None:
        """Restart the force-derivative filter (after a gap its derivative is unknown)."""
        self._derivative.reset()

    def reset(self) -> None:
        """Clear the integral and the derivative filter."""
        self.integral = 0.0
        self._derivative.reset()

    def position_acceleration(
        self, E: FloatArray, E_dot: FloatArray, X_d_ddot: FloatArray
    ) -> FloatArray:
        """Acceleration of the PD position law in the position subspace, F_p = M̂ (this) (eq. 37).

        Returns (I - S)(Ẍ_d + K_pv ΔẊ + K_pp ΔX) (m/s²).
        """
        result: FloatArray = self.I_minus_S @ (X_d_ddot + self.K_pv @ E_dot + self.K_pp @ E)
        return result

    def position_linear_map(self) -> FloatArray:
        """A (3, 9) with the position law's acceleration = A [ΔX; ΔẊ; Ẍ_d] (eq. 37)."""
        result: FloatArray = self.I_minus_S @ np.hstack((self.K_pp, self.K_pv, np.eye(3)))
        return result

    def force_acceleration(
        self,
        f_d: float,
        f_d_dot: float,
        f_d_ddot: float,
        f_normal: float,
        dt: float,
        integrate: bool,
    ) -> float:
        """Normal acceleration of the PID force law, F_f = M̂ n (this) (eq. 39) (m/s²).

        Args:
            f_d: desired normal force F_d (N).
            f_d_dot: its rate (N/s).
            f_d_ddot: its second derivative (N/s²).
            f_normal: measured normal force n·F_e (N).
            dt: time since the previous call (s); the derivative filter and the integral use it.
            integrate: whether the integral may run (see the anti-windup note).
        """
        f_normal_dot = self._derivative.update(f_normal, dt)
        error = f_d - f_normal
        if integrate and dt > 0.0:
            limit = self.integral_limit
            self.integral = min(max(self.integral + error * dt, -limit), limit)
        return (
            self.c_ff * f_d_ddot
            + self.k_fp * error
            + self.k_fi * self.integral
            + self.k_fv * (f_d_dot - f_normal_dot)
        )

    def force(
        self,
        M_hat: FloatArray,
        zeta_hat: FloatArray,
        F_e: FloatArray,
        a_p: FloatArray,
        a_f: float,
    ) -> tuple[FloatArray, FloatArray]:
        """F_H of eq. 35 and its (I - S) F_p + S F_f part, from the law accelerations (N)."""
        F_p = M_hat @ a_p
        F_f = M_hat @ (a_f * self.n)
        selected: FloatArray = self.I_minus_S @ F_p + self.S @ F_f
        return selected + zeta_hat + F_e, selected
