"""Stability of the sampled control loops for a set of gains (paper eq. 24, 29-31, 35-39).

The controller runs at a period T and holds its command over it (zero-order hold). With the
controller's inertia estimate M̂ = s M̃ (eq. 34) and ζ̂ = ζ̃ the task-space plant
M̃ Ẍ + ζ̃ + F_e = F_c (eq. 28) under the blended command F_c = W F_IP + (1 - W) F_H (eq. 2)
obeys, with X_d, Ẋ_d and F_d at rest (the homogeneous loop),

    Ẍ = s M̃⁻¹ [W M̃ U + (1 - W) ((I - S) M̃ a_p + S M̃ n a_f)],
    U = P⁻¹ (-B_d Ẋ - K X - F_e)                          (eq. 30),
    a_p = (I - S)(-K_pv Ẋ - K_pp X)                         (eq. 37),
    a_f = -K_fp f + K_fi ∫(-f) dt - K_fv ḟ_filtered           (eq. 39),

on a spring wall F_e = K_e n nᵀ X, f = n·F_e. The impedance law cancels M̃ (Ẍ = s U); the
hybrid law selects after M̂, so the task-space inertia couples its normal and tangential
parts unless M̃ is isotropic. Each loop is sampled exactly as the control step runs it: the
force integral by forward sums, the force derivative by the backward-Euler dirty derivative
(``filters.DirtyDerivative``), the acceleration held over T (X += T Ẋ + T²/2 Ẍ). A loop is
stable when the spectral radius ρ of its transition matrix is below 1. The null-space
coordinates follow φ̈ = -K_n φ - D_n φ̇ (eq. 24) and must not diverge (ρ <= 1: a zero gain
leaves a coordinate uncontrolled, as the paper's τ = Jᵀ F_c does).

The check is necessary, not sufficient: it assumes the model is exact up to s, no delay
beyond the hold, and a linear wall; thruster lag, a real-time pipeline delay and the fuzzy
switch's nonlinearity are not in it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from uvms_control.core.errors import ControlParameterError
from uvms_control.core.parameters import ControllerParameters

FloatArray = npt.NDArray[np.float64]

#: Weights of the blend checked in contact: the hybrid law alone (force integral running,
#: W <= 0.1) and half way (the integral held, as the anti-windup does for W > 0.1).
CONTACT_WEIGHTS = (0.0, 0.5)
#: Margin on ρ <= 1 for the null-space coordinates (round-off of a marginal loop).
MARGINAL = 1e-9


@dataclass(frozen=True)
class LoopRadius:
    """Spectral radius of one sampled loop.

    Attributes:
        loop: which loop (e.g. 'impedance in contact').
        radius: ρ of its transition matrix (-).
        limit: the largest ρ accepted (-).
        parameters: the gains it depends on, as they would be named in a refusal.
    """

    loop: str
    radius: float
    limit: float
    parameters: tuple[str, ...]

    @property
    def stable(self) -> bool:
        """ρ within its limit."""
        return self.radius < self.limit


def _task_loop_matrix(params: ControllerParameters, period_s: float, stiffness_n_m: float,
                      W: float, M_tilde: FloatArray, integrate: bool) -> FloatArray:
    """Transition matrix of z = [X, Ẋ, ∫ΔF, ḟ_filtered, f_prev] over one period."""
    T = period_s
    n = params.force_direction / float(np.linalg.norm(params.force_direction))
    S = np.outer(n, n)
    I_S = np.eye(3) - S
    P_inv = np.linalg.inv(params.impedance_inertia)
    M_inv = np.linalg.inv(M_tilde)
    tau = 1.0 / (2.0 * np.pi * params.force_derivative_cutoff_hz)
    s = params.mass_scale
    feeds_integral = integrate and params.force_ki > 0.0 and W < 1.0

    def advance(z: FloatArray) -> FloatArray:
        X, V, integral, y, f_prev = z[0:3], z[3:6], z[6], z[7], z[8]
        f = stiffness_n_m * float(n @ X)
        integral_next = integral - f * T if feeds_integral else integral
        y_next = (tau * y + f - f_prev) / (tau + T)
        a_f = -params.force_kp * f + params.force_ki * integral_next - params.force_kd * y_next
        U = P_inv @ (-params.impedance_damping @ V - params.impedance_stiffness @ X - n * f)
        a_p = I_S @ (-params.position_kd @ V - params.position_kp @ X)
        F = W * (M_tilde @ U) + (1.0 - W) * (I_S @ (M_tilde @ a_p) + S @ (M_tilde @ n) * a_f)
        A = s * (M_inv @ F)
        return np.concatenate((X + T * V + 0.5 * T * T * A, V + T * A,
                               (integral_next, y_next, f)))

    A = np.column_stack([advance(column) for column in np.eye(9)])
    if not feeds_integral:  # the integral then feeds nothing: drop its (unobservable) 1
        keep = [k for k in range(9) if k != 6]
        A = A[np.ix_(keep, keep)]
    return A


def spectral_radius(A: FloatArray) -> float:
    """Largest eigenvalue modulus of a square matrix (-)."""
    return float(np.max(np.abs(np.linalg.eigvals(A))))


def null_space_radius(stiffness_1_s2: float, damping_1_s: float, period_s: float) -> float:
    """ρ of one null-space coordinate, φ̈ = -K_n φ - D_n φ̇ held over T (eq. 24)."""
    T, k, d = period_s, stiffness_1_s2, damping_1_s
    A = np.array(((1.0 - 0.5 * T * T * k, T - 0.5 * T * T * d), (-T * k, 1.0 - T * d)))
    return spectral_radius(A)


IMPEDANCE = ('impedance.inertia_kg', 'impedance.damping_n_s_m', 'impedance.stiffness_n_m')
HYBRID = ('hybrid.position_kp', 'hybrid.position_kd', 'hybrid.force_kp', 'hybrid.force_ki',
          'hybrid.force_kd', 'hybrid.force_derivative_cutoff_hz')


def loop_radii(params: ControllerParameters, period_s: float, max_stiffness_n_m: float,
               M_tilde: FloatArray | None = None) -> list[LoopRadius]:
    """ρ of every sampled loop of a gain set at the control period.

    Args:
        params: the gains.
        period_s: control period T (s).
        max_stiffness_n_m: the stiffest wall the loops must hold, K_e (N/m).
        M_tilde: task-space inertia M̃ (3, 3) (kg) at the working configuration; None:
            isotropic (then the hybrid law's normal and tangential loops decouple).
    """
    M = np.eye(3) if M_tilde is None else np.asarray(M_tilde, dtype=np.float64)
    radii = [
        LoopRadius('impedance in free motion', spectral_radius(
            _task_loop_matrix(params, period_s, 0.0, 1.0, M, False)), 1.0, IMPEDANCE),
        LoopRadius(f'impedance on a K_e = {max_stiffness_n_m:g} N/m wall', spectral_radius(
            _task_loop_matrix(params, period_s, max_stiffness_n_m, 1.0, M, False)), 1.0,
            IMPEDANCE),
    ]
    for W in CONTACT_WEIGHTS:
        A = _task_loop_matrix(params, period_s, max_stiffness_n_m, W, M, W <= 0.1)
        radii.append(LoopRadius(f'blend W = {W:g} on a K_e = {max_stiffness_n_m:g} N/m wall',
                                spectral_radius(A), 1.0,
                                HYBRID + (IMPEDANCE if W > 0.0 else ())))
    if params.null_space_enabled:
        worst = max(null_space_radius(k, d, period_s) for k, d in
                    zip(params.null_space_stiffness.tolist(),
                        params.null_space_damping.tolist(), strict=False))
        radii.append(LoopRadius('null space', worst, 1.0 + MARGINAL,
                                ('null_space.stiffness_1_s2', 'null_space.damping_1_s')))
    return radii


def check_gain_stability(params: ControllerParameters, period_s: float,
                         max_stiffness_n_m: float, M_tilde: FloatArray | None = None) -> None:
    """Refuse gains whose sampled loops are unstable at the control period (``loop_radii``).

    Raises:
        ControlParameterError: naming the gains of the first unstable loop, its ρ and T.
    """
    for radius in loop_radii(params, period_s, max_stiffness_n_m, M_tilde):
        if not radius.stable:
            raise ControlParameterError(
                ', '.join(radius.parameters),
                f'spectral radius {radius.radius:.4g} of the sampled {radius.loop} loop at '
                f'T = {period_s:g} s',
                f'gains whose sampled loops are stable (spectral radius < {radius.limit:g}; '
                'docs/controller.md, "Gains at run time")')
