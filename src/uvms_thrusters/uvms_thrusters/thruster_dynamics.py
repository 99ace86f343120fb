"""Thruster dynamics of Healey et al. (1995), paper eq. 11-15.

Each thruster has two states: the propeller speed Ω (rad/s) and the axial flow speed u_p
through the duct (m/s). The motor driver turns a desired thrust F_td into a reference speed
Ω_r (eq. 11) and a current i_m (eq. 12); the motor (eq. 13) turns against the propeller
torque Q, and the blade element at 0.7 R gives thrust and torque from lift and drag against
the angle of attack (eq. 14-15, four quadrants):

    V_t = 0.7 R Ω,  V² = u_p² + V_t²,  β = atan2(u_p, V_t),  α = p - β
    C_L = C_Lmax sin 2α,  C_D = C_Dmax (1 - cos 2α),  L, D = ½ ρ A V² C_L, C_D
    T = L cos β - D sin β,  Q = 0.7 R (L sin β + D cos β)
    J_m Ω_dot = K_t i_m - K_f Ω - Q
    ρ A_p L_d γ u_p_dot + ρ A_p Δβ u_p |u_p| = T

Notes on the paper's printed equations:
- eq. 12 prints the speed feedback as K_fb (Ω - Ω_r), which is positive feedback for a
  positive gain; we use K_fb (Ω_r - Ω), and add the viscous term K_f Ω_r to the feed-forward
  so that the steady speed equals Ω_r exactly: i_m = (α_1 F_td + K_f Ω_r) / K_t
  + K_fb (Ω_r - Ω), clamped to ±i_max.
- eq. 14-15 use θ = γ - α for the flow angle; we write it β with α = p - β (Healey).

Calibration. Healey's constants are not at hand, so the free constants are chosen so that the
bollard thrust (zero advance speed, steady state) is the Wageningen B-series value
T = K_T ρ D⁴ n² (n = Ω / 2π, K_T ≈ 0.4566 for a 3-blade propeller at J = 0): at a steady
state T = ρ A_p Δβ k² V_t² with k = u_p / V_t, which fixes k; the blade-element equation then
fixes the effective blade area A. The sinusoidal lift/drag model is symmetric under reversal,
whereas real propellers (cambered blades, ducts shaped for forward flow) are about 40 %
weaker in reverse: the lift coefficient in reverse rotation is scaled by a factor η_r,
calibrated so that reverse bollard thrust is ``reverse_thrust_ratio`` times forward at the
same speed. α_1 (torque/thrust) and α_2 (thrust/Ω²) of eq. 11-12 are the steady bollard
values of the calibrated model, one pair per direction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from uvms_thrusters.errors import ThrusterInputError, ThrusterParameterError
from uvms_thrusters.thruster_kernels import (
    blade_element,
    euler_step_bank,
    state_derivative,
    thruster_constants,
)

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class ThrusterModelParameters:
    """Constants of one thruster (all thrusters of the vehicle are alike).

    Attributes:
        water_density: ρ (kg/m³).
        propeller_diameter: D (m); duct area A_p = π D² / 4.
        thrust_coefficient: bollard K_T of T = K_T ρ D⁴ n² (-), Wageningen B-series 3-blade.
        reverse_thrust_ratio: reverse / forward bollard thrust at equal |n| (-).
        pitch_angle: blade pitch p at 0.7 R (rad); default atan(P/D / (0.7 π)) for P/D = 1.
        lift_coefficient_max: C_Lmax (-).
        drag_coefficient_max: C_Dmax (-); C_D reaches 2 C_Dmax at α = 90°, a flat plate's ~2.
        duct_length: L_d (m).
        duct_added_mass_ratio: γ, effective fluid mass in the duct over ρ A_p L_d (-).
        momentum_flux_coefficient: Δβ of the duct momentum balance (-).
        motor_inertia: J_m, motor + propeller + entrained water (kg m²).
        motor_torque_constant: K_t (N m/A).
        motor_viscous_friction: K_f (N m s/rad).
        speed_feedback_gain: K_fb (A s/rad).
        max_motor_current: i_max (A).
    """

    water_density: float = 1025.0
    propeller_diameter: float = 0.15
    thrust_coefficient: float = 0.4566
    reverse_thrust_ratio: float = 0.6
    pitch_angle: float = math.atan(1.0 / (0.7 * math.pi))
    lift_coefficient_max: float = 1.2
    drag_coefficient_max: float = 1.0
    duct_length: float = 0.1
    duct_added_mass_ratio: float = 1.0
    momentum_flux_coefficient: float = 1.0
    motor_inertia: float = 2.0e-3
    motor_torque_constant: float = 0.2
    motor_viscous_friction: float = 1.0e-3
    speed_feedback_gain: float = 0.2
    max_motor_current: float = 40.0

    def __post_init__(self) -> None:
        # Keys are the ROS parameter names (config/controller.yaml), so errors name them.
        positive = {
            'hydrodynamics.water_density_kg_m3': ('kg/m^3', self.water_density),
            'thruster.propeller_diameter_m': ('m', self.propeller_diameter),
            'thruster.thrust_coefficient': ('-', self.thrust_coefficient),
            'thruster.lift_coefficient_max': ('-', self.lift_coefficient_max),
            'thruster.drag_coefficient_max': ('-', self.drag_coefficient_max),
            'thruster.duct_length_m': ('m', self.duct_length),
            'thruster.duct_added_mass_ratio': ('-', self.duct_added_mass_ratio),
            'thruster.momentum_flux_coefficient': ('-', self.momentum_flux_coefficient),
            'thruster.motor_inertia_kg_m2': ('kg m^2', self.motor_inertia),
            'thruster.motor_torque_constant_n_m_a': ('N m/A', self.motor_torque_constant),
            'thruster.max_motor_current_a': ('A', self.max_motor_current),
        }
        for name, (unit, value) in positive.items():
            if not (math.isfinite(value) and value > 0.0):
                raise ThrusterParameterError(name, value, f'(0, inf) {unit}')
        for name, value in (
            ('thruster.motor_viscous_friction_n_m_s', self.motor_viscous_friction),
            ('thruster.speed_feedback_gain_a_s', self.speed_feedback_gain),
        ):
            if not (math.isfinite(value) and value >= 0.0):
                raise ThrusterParameterError(name, value, '[0, inf)')
        if not (0.0 < self.reverse_thrust_ratio <= 1.0):
            raise ThrusterParameterError(
                'thruster.reverse_thrust_ratio', self.reverse_thrust_ratio, '(0, 1]'
            )
        if not (0.0 < self.pitch_angle < math.pi / 2.0):
            raise ThrusterParameterError(
                'thruster.pitch_angle_rad', self.pitch_angle, '(0, pi/2) rad'
            )


@dataclass(frozen=True)
class ThrusterCalibration:
    """Constants derived from `ThrusterModelParameters` so that bollard thrust is K_T ρ D⁴ n².

    Index 0 is forward (Ω > 0), index 1 reverse (Ω < 0).

    Attributes:
        blade_area: effective blade-element area A (m²).
        reverse_lift_factor: η_r scaling C_Lmax in reverse rotation (-).
        flow_ratio: steady k = |u_p / V_t| at bollard (-), per direction.
        alpha_1: steady torque/thrust ratio Q/T (m), per direction (eq. 12).
        alpha_2: steady thrust/speed² ratio T/Ω² (N s²), per direction (eq. 11).
        max_step: largest stable explicit-Euler step at full thrust (s).
    """

    blade_area: float
    reverse_lift_factor: float
    flow_ratio: tuple[float, float]
    alpha_1: tuple[float, float]
    alpha_2: tuple[float, float]
    max_step: float


def _lift_drag_terms(pitch: float, k: float) -> tuple[float, float, float, float]:
    """Sin 2α, 1 - cos 2α, cos β, sin β for a forward steady flow ratio k = tan β."""
    beta = math.atan(k)
    alpha = pitch - beta
    return math.sin(2.0 * alpha), 1.0 - math.cos(2.0 * alpha), math.cos(beta), math.sin(beta)


def calibrate(params: ThrusterModelParameters) -> ThrusterCalibration:
    """Derive blade area, reverse lift factor, α_1, α_2 from the bollard law T = K_T ρ D⁴ n².

    Raises:
        ThrusterParameterError: if the pitch is too small for the requested K_T (the blade
            would need a non-positive area).
    """
    p = params
    radius = p.propeller_diameter / 2.0
    r07 = 0.7 * radius
    duct_area = math.pi * radius * radius
    d4 = p.propeller_diameter**4
    # T = ρ A_p Δβ k² (0.7 R Ω)² = K_T ρ D⁴ Ω² / (4π²)  ->  k.
    k_fwd = math.sqrt(
        p.thrust_coefficient
        * d4
        / (4.0 * math.pi**2 * duct_area * p.momentum_flux_coefficient * r07**2)
    )
    s2a, c2a, cb, sb = _lift_drag_terms(p.pitch_angle, k_fwd)
    force_term = p.lift_coefficient_max * s2a * cb - p.drag_coefficient_max * c2a * sb
    if force_term <= 0.0:
        raise ThrusterParameterError(
            'thruster.pitch_angle_rad',
            p.pitch_angle,
            f'a pitch larger than the bollard flow angle atan({k_fwd:.3f}) with positive lift',
        )
    # ½ A (1 + k²) (C_L cos β - C_D sin β) = A_p Δβ k²  ->  A.
    blade_area = (
        2.0 * duct_area * p.momentum_flux_coefficient * k_fwd**2 / ((1.0 + k_fwd**2) * force_term)
    )
    k_rev = k_fwd * math.sqrt(p.reverse_thrust_ratio)
    s2a_r, c2a_r, cb_r, sb_r = _lift_drag_terms(p.pitch_angle, k_rev)
    needed = (
        2.0 * duct_area * p.momentum_flux_coefficient * k_rev**2 / ((1.0 + k_rev**2) * blade_area)
    )
    reverse_lift_factor = (needed + p.drag_coefficient_max * c2a_r * sb_r) / (
        p.lift_coefficient_max * s2a_r * cb_r
    )
    alpha_1 = []
    alpha_2 = []
    for k, s2, c2, c_b, s_b, eta in (
        (k_fwd, s2a, c2a, cb, sb, 1.0),
        (k_rev, s2a_r, c2a_r, cb_r, sb_r, reverse_lift_factor),
    ):
        lift = eta * p.lift_coefficient_max * s2
        drag = p.drag_coefficient_max * c2
        alpha_1.append(r07 * (lift * s_b + drag * c_b) / (lift * c_b - drag * s_b))
        alpha_2.append(p.water_density * duct_area * p.momentum_flux_coefficient * k**2 * r07**2)
    calibration = ThrusterCalibration(
        blade_area=blade_area,
        reverse_lift_factor=reverse_lift_factor,
        flow_ratio=(k_fwd, k_rev),
        alpha_1=(alpha_1[0], alpha_1[1]),
        alpha_2=(alpha_2[0], alpha_2[1]),
        max_step=1.0,
    )
    return _with_max_step(params, calibration)


def _with_max_step(
    params: ThrusterModelParameters, calibration: ThrusterCalibration
) -> ThrusterCalibration:
    """Largest explicit-Euler step at full current: h ≤ σ / |λ|² for every eigenvalue.

    Euler is stable for an eigenvalue λ = -σ + iω when h < 2σ / |λ|²; we take half of that.
    For a real mode this is h |λ| ≤ 1, where Euler decays monotonically, without the
    oscillation it shows beyond. The time constants shrink as the propeller speeds up, so
    they are evaluated at the bollard state whose steady current is the current limit.
    """
    bank = ThrusterBank(params, 1, calibration)
    steps = []
    for thrust in (
        bank.max_steady_thrust(forward=True),
        -bank.max_steady_thrust(forward=False),
    ):
        omega, u_p = bank.bollard_state(thrust)
        f = np.array([thrust])
        x0 = np.array([omega, u_p])
        jac = np.zeros((2, 2))
        for j in range(2):
            h = 1e-6 * max(1.0, abs(x0[j]))
            xp, xm = x0.copy(), x0.copy()
            xp[j] += h
            xm[j] -= h
            jac[:, j] = (bank.derivatives(xp, f) - bank.derivatives(xm, f)) / (2.0 * h)
        for lam in np.linalg.eigvals(jac):
            sigma, mag = -float(lam.real), float(abs(lam))
            if sigma <= 0.0:
                raise ThrusterParameterError(
                    'thruster constants', params, 'a stable bollard equilibrium at full current'
                )
            steps.append(sigma / (mag * mag))
    max_step = min(steps)
    return ThrusterCalibration(
        blade_area=calibration.blade_area,
        reverse_lift_factor=calibration.reverse_lift_factor,
        flow_ratio=calibration.flow_ratio,
        alpha_1=calibration.alpha_1,
        alpha_2=calibration.alpha_2,
        max_step=max_step,
    )


class ThrusterBank:
    """A set of identical thrusters integrated together (eq. 11-15, compiled per thruster).

    Example:
        >>> bank = ThrusterBank(ThrusterModelParameters(), count=2)
        >>> for _ in range(1000):
        ...     thrust = bank.step(np.array([100.0, -50.0]), 0.001)
        >>> np.round(thrust, 1).tolist()
        [100.0, -50.0]
    """

    def __init__(
        self,
        params: ThrusterModelParameters,
        count: int,
        calibration: ThrusterCalibration | None = None,
    ) -> None:
        if count < 1:
            raise ThrusterParameterError('thruster count', count, '>= 1')
        self.params = params
        self.count = count
        self.calibration = calibration if calibration is not None else calibrate(params)
        p, c = params, self.calibration
        radius = p.propeller_diameter / 2.0
        duct_area = math.pi * radius * radius
        half_rho_a = 0.5 * p.water_density * c.blade_area
        self.constants = thruster_constants(
            r07=0.7 * radius,
            lift_k_forward=half_rho_a * p.lift_coefficient_max,
            lift_k_reverse=half_rho_a * p.lift_coefficient_max * c.reverse_lift_factor,
            drag_k=half_rho_a * p.drag_coefficient_max,
            sin2p=math.sin(2.0 * p.pitch_angle),
            cos2p=math.cos(2.0 * p.pitch_angle),
            duct_mass=p.water_density * duct_area * p.duct_length * p.duct_added_mass_ratio,
            duct_loss=p.water_density * duct_area * p.momentum_flux_coefficient,
            inv_sqrt_alpha_2_forward=1.0 / math.sqrt(c.alpha_2[0]),
            inv_sqrt_alpha_2_reverse=1.0 / math.sqrt(c.alpha_2[1]),
            ff_gain_forward=c.alpha_1[0] / p.motor_torque_constant,
            ff_gain_reverse=c.alpha_1[1] / p.motor_torque_constant,
            ff_friction=p.motor_viscous_friction / p.motor_torque_constant,
            speed_feedback_gain=p.speed_feedback_gain,
            max_motor_current=p.max_motor_current,
            motor_torque_constant=p.motor_torque_constant,
            motor_viscous_friction=p.motor_viscous_friction,
            motor_inertia=p.motor_inertia,
        )
        self.omega = np.zeros(count)
        self.u_p = np.zeros(count)
        self.omega_r = np.zeros(count)
        self.motor_current = np.zeros(count)
        self.thrust = np.zeros(count)
        self.torque = np.zeros(count)

    def reset(self) -> None:
        """Stop every propeller and the duct flow."""
        for a in (
            self.omega,
            self.u_p,
            self.omega_r,
            self.motor_current,
            self.thrust,
            self.torque,
        ):
            a[:] = 0.0

    def blade_forces(self, omega: FloatArray, u_p: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Thrust T (N) and shaft torque Q (N m) of the blade element at 0.7 R (eq. 14-15)."""
        forces = [blade_element(self.constants, float(w), float(u))
                  for w, u in zip(np.ravel(omega), np.ravel(u_p), strict=True)]
        thrust, torque = np.array(forces, dtype=np.float64).reshape(-1, 2).T
        return thrust, torque

    def derivatives(self, state: FloatArray, f_td: FloatArray) -> FloatArray:
        """Time derivative of the stacked state [Ω..., u_p...] for desired thrusts f_td."""
        n = f_td.size
        rates = [state_derivative(self.constants, float(f), float(w), float(u))
                 for f, w, u in zip(f_td, state[:n], state[n:], strict=True)]
        omega_dot, u_dot = np.array(rates, dtype=np.float64).reshape(-1, 2).T
        return np.concatenate([omega_dot, u_dot])

    def steady_current(self, thrust: float) -> float:
        """Motor current (A) that holds ``thrust`` at zero advance speed (eq. 12-13 at rest)."""
        omega, _ = self.bollard_state(thrust)
        index = 0 if thrust >= 0.0 else 1
        p = self.params
        torque = self.calibration.alpha_1[index] * thrust + p.motor_viscous_friction * omega
        return torque / p.motor_torque_constant

    def max_steady_thrust(self, forward: bool = True) -> float:
        """Largest bollard thrust magnitude (N) the current limit can hold, per direction."""
        c, p = self.calibration, self.params
        index = 0 if forward else 1
        # K_t i = α_1 T + K_f sqrt(T / α_2): a quadratic in sqrt(T).
        a, b = c.alpha_1[index], p.motor_viscous_friction / math.sqrt(c.alpha_2[index])
        rhs = p.motor_torque_constant * p.max_motor_current
        root = (-b + math.sqrt(b * b + 4.0 * a * rhs)) / (2.0 * a)
        return root * root

    def bollard_state(self, thrust: float) -> tuple[float, float]:
        """Steady (Ω, u_p) that produce ``thrust`` at zero advance speed."""
        c = self.calibration
        index = 0 if thrust >= 0.0 else 1
        omega = math.copysign(math.sqrt(abs(thrust) / c.alpha_2[index]), thrust)
        return omega, c.flow_ratio[index] * float(self.constants[0]['r07']) * omega

    def step(self, f_td: FloatArray, dt: float) -> FloatArray:
        """Advance every thruster by dt (s) under desired thrusts f_td (N); return thrusts.

        Explicit Euler, sub-stepped so that no step exceeds the calibrated stability bound.
        The returned array is the bank's own buffer of actual thrusts F_t,act (eq. 15).

        Raises:
            ThrusterInputError: if f_td has the wrong size or is not finite, or dt < 0.
        """
        f_td = np.asarray(f_td, dtype=np.float64)
        if not (math.isfinite(dt) and dt >= 0.0):
            raise ThrusterInputError(f'time step dt = {dt} s must be finite and >= 0')
        if f_td.shape != (self.count,) or not euler_step_bank(
            self.constants, f_td, float(dt), self.calibration.max_step, self.omega, self.u_p,
            self.omega_r, self.motor_current, self.thrust, self.torque,
        ):
            raise ThrusterInputError(
                f'desired thrusts must be {self.count} finite values, got {f_td.tolist()}'
            )
        return self.thrust
