"""Unified force controller: impedance and hybrid laws blended by a fuzzy switch (paper sec. 2, 4).

One step, at the state (q, q_dot) and the measured contact force F_e (the force the end
effector exerts on the environment, in map_ned):

1. task-space model M̃, ζ̃ (eq. 22-28) from the controller's own UvmsModel; M̂ = s M̃
   (s = 1 nominally, 0.9 in the paper's Case IV), ζ̂ = ζ̃;
2. references: the half circle X_d (sec. 5.1) and the force set-point F_d n (sec. 5.2);
3. impedance law F_IP (eq. 29-31) and hybrid law F_H (eq. 35, 37, 39);
4. fuzzy weight W(F_e/F_d, v_e) (sec. 4.3) and the blend F_c = W F_IP + (1 - W) F_H (eq. 2);
5. generalized forces τ = Jᵀ F_c (eq. 26) plus, optionally, the null-space term below, mapped
   to body form τ_b = Bᵀ τ. Power is invariant, τ·q̇ = τ_b·w with q̇ = B w (eq. 4), which
   forces Bᵀ; the paper prints τ = B τ_b under eq. 18, which violates it.

Null space. The paper drops the null-space part of eq. 24 (sec. 4.1 and 5.2.3). For this
redundant UVMS (9 DOF, 3-D task) τ = Jᵀ F_c alone leaves six directions uncontrolled, so
the vehicle pose and the arm posture drift, and the closed loop is not the task-space model
eq. 28 claims: premultiplying eq. 25 by J̃⁺ (eq. 27) discards the part of the joint-space
equation that Jᵀ F cannot produce. With ``null_space_enabled`` we apply the joint-space law
the paper derives from, eq. 20 with eq. 24 and a posture acceleration φ̈:

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

import enum
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from uvms_control.core.errors import ControlInputError
from uvms_control.core.fuzzy_switch import FuzzySwitch
from uvms_control.core.hybrid import HybridLaw
from uvms_control.core.impedance import ImpedanceLaw
from uvms_control.core.parameters import ControllerParameters
from uvms_control.core.reference import ForcePhase, ForceSetpoint, HalfCircleReference
from uvms_control.core.task_space import (
    TaskSpaceModel,
    inverse_3x3,
    task_space_model_from_terms,
)
from uvms_model import ModelError, TaskSpaceTerms, UvmsModel

FloatArray = npt.NDArray[np.float64]

#: W at or below which the hybrid law dominates and the task counts as constrained motion.
CONSTRAINED_WEIGHT = 0.1


class Phase(enum.IntEnum):
    """Task phase (values of uvms_msgs/ControllerState.PHASE_*)."""

    FREE_MOTION = 0
    CONTACT_TRANSITION = 1
    CONSTRAINED = 2


@dataclass(slots=True)
class ControllerResult:
    """Output and internals of one controller step (task-space vectors in map_ned).

    Attributes:
        tau_b: generalized force in body form (9,): vehicle force (N) and moment (N m) in
            base_link_frd, then joint torques (N m).
        tau: generalized force in generalized coordinates (9,), eq. 26 (+ null space).
        W: fuzzy weight in [0, 1], 1 = impedance.
        X: end-effector position (m).
        X_d: reference position (m).
        X_dot: end-effector velocity (m/s).
        X_dot_d: reference velocity (m/s).
        F_e: contact force exerted on the environment (N).
        F_d: desired contact force (N).
        F_c: blended task-space command (N), eq. 2.
        F_IP: impedance law output (N), eq. 31.
        F_H: hybrid law output (N), eq. 35.
        v_e: velocity along the environment normal, positive toward it (m/s).
        force_ratio: n·F_e over the force set-point (-).
        phase: task phase.
        M_hat: inertia estimate M̂ = s M̃ (kg), eq. 29.
        zeta_hat: bias estimate ζ̂ = ζ̃ (N), eq. 29.
    """

    tau_b: FloatArray
    tau: FloatArray
    W: float
    X: FloatArray
    X_d: FloatArray
    X_dot: FloatArray
    X_dot_d: FloatArray
    F_e: FloatArray
    F_d: FloatArray
    F_c: FloatArray
    F_IP: FloatArray
    F_H: FloatArray
    v_e: float
    force_ratio: float
    phase: Phase
    M_hat: FloatArray
    zeta_hat: FloatArray


def _finite_vector(name: str, value: npt.ArrayLike, size: int) -> FloatArray:
    array = np.asarray(value, dtype=np.float64)
    # A finite sum of plain floats is the cheap test; a huge finite sum may overflow: look again.
    if array.shape != (size,) or (
        not math.isfinite(sum(array.tolist())) and not np.isfinite(array).all()
    ):
        raise ControlInputError(
            f'{name} must be {size} finite values, got {np.ravel(array).tolist()}'
        )
    return array


class UnifiedForceController:
    """Unified force controller of the paper (eq. 2, 26, 29-39, sec. 4.3).

    Args:
        params: validated controller parameters.
        model: the controller's own UVMS model (its estimate of the plant).

    Example:
        >>> controller = UnifiedForceController(ControllerParameters.from_flat_dict(), UvmsModel())
        >>> q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.6, -1.2])
        >>> result = controller.step(0.0, q, np.zeros(9), np.zeros(3))
        >>> result.W, result.phase.name
        (1.0, 'FREE_MOTION')
    """

    def __init__(self, params: ControllerParameters, model: UvmsModel) -> None:
        self.params = params
        self.model = model
        self.impedance = ImpedanceLaw(
            params.impedance_inertia, params.impedance_damping, params.impedance_stiffness
        )
        self.hybrid = HybridLaw(
            params.force_direction,
            params.position_kp,
            params.position_kd,
            params.force_kp,
            params.force_ki,
            params.force_kd,
            params.force_feedforward_compliance,
            params.force_derivative_cutoff_hz,
            params.force_integral_limit,
        )
        self.fuzzy = FuzzySwitch(params.fuzzy)
        self.reference = HalfCircleReference(
            params.reference_radius,
            params.reference_duration,
            params.reference_start_delay,
            params.force_direction,
            params.reference_sweep_direction,
        )
        self.force_setpoint = ForceSetpoint(
            params.force_setpoint,
            params.force_ramp_time,
            params.contact_threshold,
            start_immediately=params.switch_mode == 'hybrid',
        )
        self.n = self.hybrid.n
        self._n_list: list[float] = self.n.tolist()
        self._n_dof = model.n_dof
        self._eye = np.eye(self._n_dof)
        self.reset()

    def reset(self) -> None:
        """Forget the start time, start position, posture and the integral and filter states."""
        self._t0: float | None = None
        self._t_prev = 0.0
        self._X0: FloatArray | None = (
            None
            if self.params.reference_start_position is None
            else self.params.reference_start_position.copy()
        )
        self._q0 = np.zeros(self._n_dof)
        self.hybrid.reset()
        self.force_setpoint.reset()

    @property
    def start_time(self) -> float | None:
        """Time of the first step (s), the origin of the references; None before it."""
        return self._t0

    def step_from_sensors(
        self, t: float, q: npt.ArrayLike, w: npt.ArrayLike, f_sensor: npt.ArrayLike
    ) -> ControllerResult:
        """Step from what the robot measures: body velocities and the wrist-sensor force.

        Args:
            t: time (s).
            q: generalized coordinates (9,).
            w: quasi-velocities (9,) (vehicle twist in base_link_frd, joint rates), eq. 4.
            f_sensor: force the end effector exerts on the environment, in ft_sensor_link
                (axes of ee_link) (N).

        Raises:
            ControlInputError: for non-finite or wrongly sized inputs or a singular attitude.
        """
        q = _finite_vector('q', q, self._n_dof)
        w = _finite_vector('w', w, self._n_dof)
        f_sensor = _finite_vector('f_sensor', f_sensor, 3)
        try:
            terms = self.model.task_space_terms(q, w=w)
        except ModelError as error:
            raise ControlInputError(str(error)) from error
        return self._step(t, q, terms, terms.rot_ned_from_ee.dot(f_sensor))

    def step(
        self, t: float, q: npt.ArrayLike, q_dot: npt.ArrayLike, f_e_ned: npt.ArrayLike
    ) -> ControllerResult:
        """One control step at time t (s).

        Args:
            t: time (s); references count from the first step's t.
            q: generalized coordinates (9,).
            q_dot: generalized velocities (9,).
            f_e_ned: contact force the end effector exerts on the environment, map_ned (N).

        Raises:
            ControlInputError: for non-finite or wrongly sized inputs or a singular attitude.
        """
        q = _finite_vector('q', q, self._n_dof)
        q_dot = _finite_vector('q_dot', q_dot, self._n_dof)
        f_e = _finite_vector('f_e_ned', f_e_ned, 3)
        try:
            terms = self.model.task_space_terms(q, q_dot)
        except ModelError as error:
            raise ControlInputError(str(error)) from error
        return self._step(t, q, terms, f_e)

    def _step(
        self, t: float, q: FloatArray, terms: TaskSpaceTerms, F_e: FloatArray
    ) -> ControllerResult:
        if not math.isfinite(t):
            raise ControlInputError(f'time t = {t} s must be finite')
        ts = task_space_model_from_terms(terms)
        q_dot, B = terms.q_dot, terms.B
        if self._t0 is None:
            self._t0 = t
            self._t_prev = t
            self._q0 = q.copy()
            if self._X0 is None:
                self._X0 = ts.X.copy()
        assert self._X0 is not None
        dt = max(t - self._t_prev, 0.0)
        self._t_prev = max(t, self._t_prev)
        t_rel = t - self._t0
        n = self.n
        p = self.params

        X_d, X_dot_d, X_ddot_d = self.reference.evaluate(t_rel, self._X0)
        X, X_dot = ts.X, ts.X_dot
        n0, n1, n2 = self._n_list
        f0, f1, f2 = F_e.tolist()
        v0, v1, v2 = X_dot.tolist()
        x0, x1, x2 = X.tolist()
        d0, d1, d2 = X_d.tolist()
        w0, w1, w2 = X_dot_d.tolist()
        f_normal = n0 * f0 + n1 * f1 + n2 * f2
        v_e = n0 * v0 + n1 * v1 + n2 * v2
        setpoint = self.force_setpoint.update(
            t_rel,
            f_normal,
            n0 * x0 + n1 * x1 + n2 * x2,
            n0 * d0 + n1 * d1 + n2 * d2,
            n0 * w0 + n1 * w1 + n2 * w2,
        )
        if setpoint.phase == ForcePhase.IDLE and self.hybrid.integral != 0.0:
            self.hybrid.integral = 0.0
        force_ratio = f_normal / p.force_setpoint
        if p.switch_mode == 'fuzzy':
            W = self.fuzzy.weight(force_ratio, v_e)
        else:
            W = 1.0 if p.switch_mode == 'impedance' else 0.0

        M_hat = ts.M_tilde if p.mass_scale == 1.0 else p.mass_scale * ts.M_tilde
        zeta_hat = ts.zeta_tilde
        E = X_d - X
        E_dot = X_dot_d - X_dot
        U = self.impedance.acceleration(E, E_dot, X_ddot_d, F_e)
        F_IP = ImpedanceLaw.force(M_hat, zeta_hat, U, F_e)
        a_p = self.hybrid.position_acceleration(E, E_dot, X_ddot_d)
        a_f = self.hybrid.force_acceleration(
            setpoint.f_d,
            setpoint.f_d_dot,
            setpoint.f_d_ddot,
            f_normal,
            dt,
            integrate=setpoint.phase != ForcePhase.IDLE
            and W <= CONSTRAINED_WEIGHT
            and f_normal >= self.force_setpoint.contact_threshold,
        )
        F_H, F_H_selected = self.hybrid.force(M_hat, zeta_hat, F_e, a_p, a_f)
        F_c = W * F_IP + (1.0 - W) * F_H

        tau = ts.J.T @ F_c
        if p.null_space_enabled:
            # M̂ a_c = F_c - ζ̂ - F_e = W M̂ U + (1 - W) [(I - S) F_p + S F_f].
            if W == 1.0:
                a_c = U
            else:
                a_c = W * U + (1.0 - W) * (inverse_3x3(M_hat) @ F_H_selected)
            tau += self._null_space_torque(ts, q, q_dot, a_c)
        tau_b = B.T @ tau
        if not math.isfinite(sum(tau_b.tolist())) and not np.isfinite(tau_b).all():
            raise ControlInputError(
                f'the control law gave a non-finite command at q = {q.tolist()} '
                '(kinematic singularity?)'
            )
        if f_normal < self.force_setpoint.contact_threshold:
            phase = Phase.FREE_MOTION
        elif W <= CONSTRAINED_WEIGHT:
            phase = Phase.CONSTRAINED
        else:
            phase = Phase.CONTACT_TRANSITION
        return ControllerResult(
            tau_b=tau_b,
            tau=tau,
            W=W,
            X=X,
            X_d=X_d,
            X_dot=X_dot,
            X_dot_d=X_dot_d,
            F_e=F_e,
            F_d=setpoint.f_d * n,
            F_c=F_c,
            F_IP=F_IP,
            F_H=F_H,
            v_e=v_e,
            force_ratio=force_ratio,
            phase=phase,
            M_hat=M_hat,
            zeta_hat=zeta_hat,
        )

    def _null_space_torque(
        self, ts: TaskSpaceModel, q: FloatArray, q_dot: FloatArray, a_c: FloatArray
    ) -> FloatArray:
        """τ_null = (I - J⁺J)(M̂_q J⁺ (a_c - J̇q̇) + ζ̂_q) + M̂_q (I - J⁺J) φ̈ (eq. 20, 24)."""
        p = self.params
        error = self._q0 - q
        # Euler angles wrap: hold the attitude the short way round.
        e3, e4, e5 = error[3:6].tolist()
        if max(abs(e3), abs(e4), abs(e5)) > math.pi:
            error[3:6] = (error[3:6] + math.pi) % (2.0 * math.pi) - math.pi
        phi_ddot = p.null_space_stiffness * error - p.null_space_damping * q_dot
        N = self._eye - ts.J_pinv @ ts.J
        M_hat_q = ts.M if p.mass_scale == 1.0 else p.mass_scale * ts.M
        row_space = M_hat_q @ (ts.J_pinv @ (a_c - ts.J_dot_q_dot)) + ts.zeta
        result: FloatArray = N @ row_space + M_hat_q @ (N @ phi_ddot)
        return result
