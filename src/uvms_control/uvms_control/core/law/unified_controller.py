"""Unified force controller: impedance and hybrid laws blended by a fuzzy switch (paper sec. 2, 4).

One step, at the state (q, q_dot) and the measured contact force F_e (the force the end
effector exerts on the environment, in map_ned):

1. task-space model M̃, ζ̃ (eq. 22-28) from the controller's own UvmsModel; M̂ = s M̃
   (s = 1 nominally, 0.9 in the paper's Case IV), ζ̂ = ζ̃;
2. references: X_d of the running task's path or the hold point (``TaskReference``), and
   the task's force set-point F_d n (sec. 5.2), n the task's normal;
3. impedance law F_IP (eq. 29-31) and hybrid law F_H (eq. 35, 37, 39);
4. fuzzy weight W(F_e/F_d, v_e) (sec. 4.3) and the blend F_c = W F_IP + (1 - W) F_H (eq. 2);
5. generalized forces τ = Jᵀ F_c (eq. 26) plus, optionally, the null-space term below, mapped
   to body form τ_b = Bᵀ τ. Power is invariant, τ·q̇ = τ_b·w with q̇ = B w (eq. 4), which
   forces Bᵀ; the paper prints τ = B τ_b under eq. 18, which violates it.

Null space: the paper drops the null-space part of eq. 24; ``null_space_enabled`` applies the
joint-space law it derives from instead (why and how: ``uvms_control.core.law.null_space``).
"""

from __future__ import annotations

import contextlib
import math

import numpy as np
import numpy.typing as npt

from uvms_control.core.errors import ControlInputError
from uvms_control.core.law.controller_result import ControllerResult, Phase
from uvms_control.core.law.fuzzy_switch import FuzzySwitch
from uvms_control.core.law.gain_ramp import GainRamp
from uvms_control.core.law.gain_stability import check_gain_stability
from uvms_control.core.law.held_command import HeldCommandForce
from uvms_control.core.law.hybrid import HybridLaw
from uvms_control.core.law.impedance import ImpedanceLaw
from uvms_control.core.law.null_space import null_space_torque
from uvms_control.core.law.reference import ForcePhase
from uvms_control.core.law.task_goal import ContactTaskGoal
from uvms_control.core.law.task_reference import TaskReference
from uvms_control.core.law.task_space import (
    TaskSpaceModel,
    inverse_3x3,
    task_space_model_from_terms,
)
from uvms_control.core.parameters import ControllerParameters, null_space_gains
from uvms_model import ModelError, TaskSpaceTerms, UvmsModel

FloatArray = npt.NDArray[np.float64]

__all__ = ['CONSTRAINED_WEIGHT', 'ControllerResult', 'Phase', 'UnifiedForceController']

#: W at or below which the hybrid law dominates and the task counts as constrained motion.
CONSTRAINED_WEIGHT = 0.1
#: Control period (s) the integrations and the gain check assume unless told: 500 Hz.
DEFAULT_CONTROL_PERIOD_S = 0.002
#: A gap longer than this many periods restarts the force-derivative filter.
GAP_RESTART_PERIODS = 5


def _finite_vector(name: str, value: npt.ArrayLike, size: int) -> FloatArray:
    array = np.asarray(value, dtype=np.float64)
    # A finite sum of plain floats is the cheap test; a huge finite sum may overflow: look again.
    if array.shape != (size,) or (
        not math.isfinite(sum(array.tolist())) and not np.isfinite(array).all()
    ):
        raise ControlInputError(f'{name} must be {size} finite values, got '
                                f'{np.ravel(array).tolist()}')
    return array


class UnifiedForceController:
    """Unified force controller of the paper (eq. 2, 26, 29-39, sec. 4.3).

    Args:
        params: validated controller parameters.
        model: the controller's own UVMS model (its estimate of the plant).
        control_period_s: the control period T (s): no step integrates the force integral or
            the derivative filter over more than T, and gains are checked for stability at T.
        force_horizon_s: h (s) of ``held_command``: eq. 29 and 35 cancel the contact force
            predicted h after its sample (the middle of an arm command slot held by the
            device); 0, the default, cancels the measured F_e as the paper.

    Raises:
        ControlParameterError: gains that ``check_gains`` refuses.

    Example:
        >>> controller = UnifiedForceController(ControllerParameters.from_flat_dict(), UvmsModel())
        >>> q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.6, -1.2])
        >>> result = controller.step(0.0, q, np.zeros(9), np.zeros(3))  # the paper robot: n = 3
        >>> result.W, result.phase.name
        (1.0, 'FREE_MOTION')
    """

    def __init__(self, params: ControllerParameters, model: UvmsModel,
                 control_period_s: float = DEFAULT_CONTROL_PERIOD_S,
                 force_horizon_s: float = 0.0) -> None:
        self.params = params
        self._held_force = HeldCommandForce(force_horizon_s) if force_horizon_s > 0.0 else None
        self.model = model
        self.control_period_s = control_period_s
        self._n_dof = model.n_dof
        self._M_tilde: FloatArray | None = None
        self._ramp: GainRamp | None = None
        self.check_gains(params)
        self.impedance = ImpedanceLaw(
            params.impedance_inertia, params.impedance_damping, params.impedance_stiffness
        )
        self.fuzzy = FuzzySwitch(params.fuzzy)
        self.task = TaskReference(params.contact_threshold,
                                  ramp_from_start=params.switch_mode == 'hybrid')
        self._set_normal(params.force_direction)
        self._null_gains = null_space_gains(params, self._n_dof)
        # Load the compiled kernels now (``UvmsModel._load_kernels``), not in the first period.
        self.reset()
        rest = np.zeros(self._n_dof)
        with contextlib.suppress(ControlInputError):  # then the first real step says why
            self.step(0.0, rest, rest, np.zeros(3))
        self.reset()
        self._M_tilde = None  # the rest pose is no working configuration

    def _set_normal(self, normal: npt.ArrayLike) -> None:
        """Make n the force direction of the hybrid law (S = n nᵀ) and rebuild its maps."""
        p = self.params
        self.hybrid = HybridLaw(
            np.asarray(normal, dtype=np.float64), p.position_kp, p.position_kd, p.force_kp,
            p.force_ki, p.force_kd, p.force_feedforward_compliance,
            p.force_derivative_cutoff_hz, p.force_integral_limit)
        self.n = self.hybrid.n
        self._n_list: list[float] = self.n.tolist()
        self._law_map = self._build_law_map()
        self._S: list[list[float]] = self.hybrid.S.tolist()
        self._I_minus_S: list[list[float]] = self.hybrid.I_minus_S.tolist()

    def check_gains(self, params: ControllerParameters) -> None:
        """Refuse gains that do not fit this robot or whose sampled loops are unstable.

        6 + n null-space gains; ``gain_stability`` at T with M̃ of the last step. No change.

        Raises:
            ControlParameterError: naming the parameter(s), the value and what is expected.
        """
        null_space_gains(params, self._n_dof)
        check_gain_stability(params, self.control_period_s, params.max_environment_stiffness,
                             self._M_tilde)

    def set_gains(self, params: ControllerParameters) -> None:
        """Take new gains while running, checked first (``check_gains``), without a bump.

        The force integral and filter, task, posture and time origin carry over; the gains ramp
        in (``gain_ramp``; a task that starts meanwhile takes them at once).

        Raises:
            ControlParameterError: from ``check_gains``; the controller is then unchanged.
        """
        self.check_gains(params)
        self._end_ramp()
        old_map, old_null, old_force = self._law_map, self._null_gains, self.hybrid.force_gains
        old_fuzzy, old_hybrid = self.fuzzy, self.hybrid
        self.params = params
        self.impedance = ImpedanceLaw(params.impedance_inertia, params.impedance_damping,
                                      params.impedance_stiffness)
        self.fuzzy = FuzzySwitch(params.fuzzy)
        self._set_normal(old_hybrid.n)
        self.hybrid.carry_state_from(old_hybrid)
        self.task.set_contact_threshold(params.contact_threshold)
        self._null_gains = null_space_gains(params, self._n_dof)
        self._ramp = GainRamp((old_map, self._law_map), (old_null, self._null_gains),
                              (old_force, self.hybrid.force_gains), old_fuzzy)
        self._law_map, self._null_gains = old_map, old_null
        self.hybrid.force_gains = old_force

    def _advance_ramp(self, ramp: GainRamp) -> None:
        """One step further from the old gains to the new (``set_gains``)."""
        self._law_map, self._null_gains, self.hybrid.force_gains = ramp.advance()
        if ramp.done:
            self._end_ramp()

    def _end_ramp(self) -> None:
        """Take the new gains of a running ramp at once."""
        ramp, self._ramp = self._ramp, None
        if ramp is not None:
            self._law_map, self._null_gains = ramp.law_map[1], ramp.null_gains[1]
            self.hybrid.force_gains = ramp.force_gains[1]

    def start_task(self, t: float, goal: ContactTaskGoal) -> None:
        """Follow a contact task from t (s): its path from the running X_d, F_d along its normal.

        The goal must have passed ``contact_task.validate_goal``. The force law starts afresh
        (integral and derivative filter) along the new normal.
        """
        self._end_ramp()
        self._set_normal(goal.normal)
        self.task.start(t, goal)

    def _build_law_map(self) -> FloatArray:
        """G (9, 19): the law accelerations from z = [X_d, Ẋ_d, Ẍ_d, F_e, X, Ẋ, a_f] at once.

        (G z).reshape(3, 3) has the columns U (eq. 30), the position-law acceleration
        (I - S)(Ẍ_d + K_pv ΔẊ + K_pp ΔX) (eq. 37) and the force-law acceleration a_f n
        (eq. 39), so that one product M̂ V gives M̂ U, F_p and F_f.
        """
        impedance = self.impedance.linear_map()  # on [E, Ė, Ẍ_d, F_e]
        position = self.hybrid.position_linear_map()  # on [E, Ė, Ẍ_d]
        u = np.hstack((impedance, -impedance[:, :6], np.zeros((3, 1))))
        a_p = np.hstack((position, np.zeros((3, 3)), -position[:, :6], np.zeros((3, 1))))
        a_f = np.zeros((3, 19))
        a_f[:, 18] = self.n
        result: FloatArray = np.stack((u, a_p, a_f), axis=1).reshape(9, 19)
        return result

    def reset(self) -> None:
        """Forget start time, posture, task and states: the next step holds where it is."""
        self._t0: float | None = None
        self._t_prev = 0.0
        self._q0 = np.zeros(self._n_dof)
        self._q0_dot: FloatArray | None = None  # the posture's rate, while a pilot moves it
        if self._held_force is not None:
            self._held_force.reset()
        self.hybrid.reset()
        self.task.hold()

    @property
    def vehicle_reference(self) -> FloatArray | None:
        """The vehicle pose η_0 (6,) the null-space posture holds; None before the first step."""
        return None if self._t0 is None else self._q0[:6].copy()

    def set_vehicle_reference(self, eta: npt.ArrayLike, eta_dot: npt.ArrayLike) -> bool:
        """Move the posture's vehicle part to η_0 = eta (m, rad; map_ned) at η̇_0 = eta_dot.

        The null space then damps q̇ - q̇_0, so it follows a moving η_0 without lag (a pilot;
        ``null_space``). False before the first step, where q_0 is captured.
        """
        if self._t0 is None:
            return False
        self._q0[:6] = np.asarray(eta, dtype=np.float64)
        rate = np.asarray(eta_dot, dtype=np.float64)
        self._q0_dot = np.concatenate((rate, np.zeros(self._n_dof - 6))) if rate.any() else None
        return True

    @property
    def start_time(self) -> float | None:
        """Time of the first step (s), the origin of the references; None before it."""
        return self._t0

    def step_from_sensors(
        self, t: float, q: npt.ArrayLike, w: npt.ArrayLike, f_sensor: npt.ArrayLike,
        f_t: float | None = None
    ) -> ControllerResult:
        """Step from what the robot measures: body velocities and the wrist-sensor force.

        Args:
            t: time (s).
            q: generalized coordinates (6 + n,).
            w: quasi-velocities (6 + n,) (vehicle twist in base_link_frd, joint rates), eq. 4.
            f_sensor: force the end effector exerts on the environment, in ft_sensor_link
                (axes of ee_link) (N).
            f_t: when f_sensor was sampled (s; None: t), for ``held_command``.

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
        return self._step(t, q, terms, terms.rot_ned_from_ee.dot(f_sensor), f_t)

    def step(
        self, t: float, q: npt.ArrayLike, q_dot: npt.ArrayLike, f_e_ned: npt.ArrayLike
    ) -> ControllerResult:
        """One control step at time t (s).

        Args:
            t: time (s); references count from the first step's t.
            q: generalized coordinates (6 + n,).
            q_dot: generalized velocities (6 + n,).
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
        return self._step(t, q, terms, f_e, None)

    def _step(self, t: float, q: FloatArray, terms: TaskSpaceTerms, F_e: FloatArray,
              f_t: float | None) -> ControllerResult:
        """One step from the model's terms; 3-vectors in plain floats, 9-vectors in numpy."""
        if not math.isfinite(t):
            raise ControlInputError(f'time t = {t} s must be finite')
        ts = task_space_model_from_terms(terms)
        if self._t0 is None:
            self._t0 = t
            self._t_prev = t
            self._q0 = q.copy()
        self.task.capture(ts.X.tolist())
        self._M_tilde = ts.M_tilde
        # No step integrates more than one control period: after a gap (stale inputs, a
        # paused simulation) the integral must not take in the whole gap at once.
        gap = t - self._t_prev
        dt = min(max(gap, 0.0), self.control_period_s)
        if gap > GAP_RESTART_PERIODS * self.control_period_s:
            self.hybrid.restart_derivative()
        self._t_prev = max(t, self._t_prev)
        p = self.params
        ramp = self._ramp
        if ramp is not None:
            self._advance_ramp(ramp)

        reference = self.task.state(t)
        d0, d1, d2, w0, w1, w2 = reference[:6]
        X, X_dot = ts.X.tolist(), ts.X_dot.tolist()
        F_e_list = F_e.tolist()
        n0, n1, n2 = self._n_list
        f0, f1, f2 = F_e_list
        v0, v1, v2 = X_dot
        x0, x1, x2 = X
        f_normal = n0 * f0 + n1 * f1 + n2 * f2
        v_e = n0 * v0 + n1 * v1 + n2 * v2
        setpoint = self.task.force_sample(t, f_normal, n0 * x0 + n1 * x1 + n2 * x2,
                                          n0 * d0 + n1 * d1 + n2 * d2, n0 * w0 + n1 * w1 + n2 * w2)
        if setpoint.phase == ForcePhase.IDLE and self.hybrid.integral != 0.0:
            self.hybrid.integral = 0.0
        force = self.task.force
        force_ratio = f_normal / force.magnitude if force is not None else 0.0
        if force is None:
            W = 1.0  # no force set-point: the impedance law holds or follows the path
        elif p.switch_mode == 'fuzzy':
            W = self.fuzzy.weight(force_ratio, v_e)
            if ramp is not None:
                W = ramp.blend_weight(W, force_ratio, v_e)
        else:
            W = 1.0 if p.switch_mode == 'impedance' else 0.0
        a_f = self.hybrid.force_acceleration(
            setpoint.f_d,
            setpoint.f_d_dot,
            setpoint.f_d_ddot,
            f_normal,
            dt,
            integrate=setpoint.phase != ForcePhase.IDLE
            and W <= CONSTRAINED_WEIGHT
            and f_normal >= self.task.contact_threshold_n,
        )

        M_hat = ts.M_tilde if p.mass_scale == 1.0 else p.mass_scale * ts.M_tilde
        zeta_hat = ts.zeta_tilde
        # V = [U, (I - S)(Ẍ_d + K_pv ΔẊ + K_pp ΔX), a_f n] (eq. 30, 37, 39), then M̂ V.
        V = self._law_map.dot([*reference, *F_e_list, *X, *X_dot, a_f]).reshape(3, 3)
        (mu0, p0, g0), (mu1, p1, g1), (mu2, p2, g2) = M_hat.dot(V).tolist()
        z0, z1, z2 = zeta_hat.tolist()
        e0, e1, e2 = (f0, f1, f2) if self._held_force is None else self._held_force.update(
            t if f_t is None else f_t, (f0, f1, f2), t)  # held_command: over the held slot
        c0, c1, c2 = z0 + e0, z1 + e1, z2 + e2
        # F_IP = M̂ U + ζ̂ + F_e (eq. 29); F_H = (I - S) F_p + S F_f + ζ̂ + F_e (eq. 35).
        (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = self._I_minus_S
        (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = self._S
        s0 = a00 * p0 + a01 * p1 + a02 * p2 + b00 * g0 + b01 * g1 + b02 * g2
        s1 = a10 * p0 + a11 * p1 + a12 * p2 + b10 * g0 + b11 * g1 + b12 * g2
        s2 = a20 * p0 + a21 * p1 + a22 * p2 + b20 * g0 + b21 * g1 + b22 * g2
        F_IP = (mu0 + c0, mu1 + c1, mu2 + c2)
        F_H = (s0 + c0, s1 + c1, s2 + c2)
        H = 1.0 - W
        F_c = (W * F_IP[0] + H * F_H[0], W * F_IP[1] + H * F_H[1], W * F_IP[2] + H * F_H[2])

        if p.null_space_enabled:
            # M̂ a_c = F_c - ζ̂ - F_e = W M̂ U + (1 - W) [(I - S) F_p + S F_f].
            u0, u1, u2 = V[:, 0].tolist()
            if W == 1.0:
                a_c = (u0, u1, u2)
            else:
                (k00, k01, k02), (k10, k11, k12), (k20, k21, k22) = inverse_3x3(
                    M_hat
                ).tolist()
                a_c = (
                    W * u0 + H * (k00 * s0 + k01 * s1 + k02 * s2),
                    W * u1 + H * (k10 * s0 + k11 * s1 + k12 * s2),
                    W * u2 + H * (k20 * s0 + k21 * s1 + k22 * s2),
                )
            tau = self._torque_with_null_space(ts, M_hat, q, terms.q_dot, F_c, a_c)
        else:
            tau = ts.J.T.dot(F_c)  # eq. 26
        tau_b = terms.B.T.dot(tau)
        if not math.isfinite(sum(tau_b.tolist())) and not np.isfinite(tau_b).all():
            raise ControlInputError(
                f'the control law gave a non-finite command at q = {q.tolist()} '
                '(kinematic singularity?)'
            )
        if f_normal < self.task.contact_threshold_n:
            phase = Phase.FREE_MOTION
        elif W <= CONSTRAINED_WEIGHT:
            phase = Phase.CONSTRAINED
        else:
            phase = Phase.CONTACT_TRANSITION
        f_d = setpoint.f_d
        vectors = np.array(
            (reference[0:3], reference[3:6], F_c, F_IP, F_H, (f_d * n0, f_d * n1, f_d * n2))
        )
        return ControllerResult(
            tau_b=tau_b,
            tau=tau,
            W=W,
            X=ts.X,
            X_d=vectors[0],
            X_dot=ts.X_dot,
            X_dot_d=vectors[1],
            F_e=F_e,
            F_d=vectors[5],
            F_c=vectors[2],
            F_IP=vectors[3],
            F_H=vectors[4],
            v_e=v_e,
            force_ratio=force_ratio,
            phase=phase,
            M_hat=M_hat,
            zeta_hat=zeta_hat,
        )

    def _torque_with_null_space(
        self,
        ts: TaskSpaceModel,
        M_hat: FloatArray,
        q: FloatArray,
        q_dot: FloatArray,
        F_c: tuple[float, float, float],
        a_c: tuple[float, float, float],
    ) -> FloatArray:
        """τ = Jᵀ F_c + τ_null with τ_null = N r + M̂_q N φ̈, r = M̂_q J⁺ y + ζ (eq. 20, 24, 26).

        N = I - J⁺ J and J⁺ J = Jᵀ J̃⁺, y = a_c - J̇ q̇. Collected:
        τ = Jᵀ (F_c - J̃⁺ r) + ζ + M̂_q (φ̈ + J⁺ (y - J φ̈)), where J̃⁺ r = M̂ y + J̃⁺ ζ
        (M̂ = s M̃ = J̃⁺ M̂_q J⁺): two 9 x 9 and three 3 x 9 products in all.
        """
        tau = np.empty(self._n_dof)
        q_dot = q_dot if self._q0_dot is None else q_dot - self._q0_dot  # D_n (q̇ - q̇_0)
        null_space_torque(
            ts.J, ts.Jt_pinv, ts.J_dot_q_dot, ts.M, ts.zeta, ts.Jt_pinv_zeta, M_hat,
            self.params.mass_scale, q, self._q0, q_dot, self._null_gains,
            np.array((*F_c, *a_c)), tau,
        )  # fmt: skip
        return tau
