"""The previous numpy implementation of the allocator step, kept as the tests' oracle.

Allocation F_td = T⁺ tau_v (eq. 10, T⁺ here by ``numpy.linalg.pinv``) with direction-
preserving saturation, and the thruster dynamics of eq. 11-15 vectorised over the thrusters
with numpy, as ``uvms_control`` computed them before the per-thruster kernels
(``uvms_thrusters.thruster_kernels``) took over. The calibration (``calibrate``) is shared:
it runs once at start-up, not in the step this oracle checks. ``bench/bench_model.py`` times
it as the allocator's "previous" implementation.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from uvms_thrusters.allocation import AllocatorParameters
from uvms_thrusters.thruster_dynamics import calibrate

FloatArray = NDArray[np.float64]


class ReferenceAllocator:
    """Allocation and thruster dynamics of eq. 10-15 in vectorised numpy."""

    def __init__(self, params: AllocatorParameters) -> None:
        self._t = params.thrust_matrix
        self._t_pinv = np.linalg.pinv(params.thrust_matrix)
        self._max_thrust = np.asarray(params.max_thrust, dtype=float)
        self._max_joint = np.asarray(params.max_joint_torque, dtype=float)
        p = params.thruster
        c = self.calibration = calibrate(p)
        count = self._t.shape[1]
        radius = p.propeller_diameter / 2.0
        duct_area = math.pi * radius * radius
        half_rho_a = 0.5 * p.water_density * c.blade_area
        self._p = p
        self._r07 = 0.7 * radius
        self._lift_k = (half_rho_a * p.lift_coefficient_max,
                        half_rho_a * p.lift_coefficient_max * c.reverse_lift_factor)
        self._drag_k = half_rho_a * p.drag_coefficient_max
        self._sin2p, self._cos2p = math.sin(2.0 * p.pitch_angle), math.cos(2.0 * p.pitch_angle)
        self._duct_mass = p.water_density * duct_area * p.duct_length * p.duct_added_mass_ratio
        self._duct_loss = p.water_density * duct_area * p.momentum_flux_coefficient
        self._inv_sqrt_alpha_2 = (1.0 / math.sqrt(c.alpha_2[0]), 1.0 / math.sqrt(c.alpha_2[1]))
        self._ff_gain = (c.alpha_1[0] / p.motor_torque_constant,
                         c.alpha_1[1] / p.motor_torque_constant)
        self._ff_friction = p.motor_viscous_friction / p.motor_torque_constant
        self.omega, self.u_p = np.zeros(count), np.zeros(count)
        self.omega_r, self.motor_current = np.zeros(count), np.zeros(count)
        self.thrust, self.torque = np.zeros(count), np.zeros(count)

    def allocate(self, tau_b: FloatArray) -> tuple[FloatArray, FloatArray, float, float]:
        """Desired thrusts (N), motor torques (N m) and both saturation scales (eq. 10)."""
        thrust = self._t_pinv @ tau_b[:6]
        joints = tau_b[6:].copy()
        scales = []
        for values, limits in ((thrust, self._max_thrust), (joints, self._max_joint)):
            worst = float(np.max(np.abs(values) / limits))
            scale = 1.0 if worst <= 1.0 else 1.0 / worst
            values *= scale
            scales.append(scale)
        return thrust, joints, scales[0], scales[1]

    def blade_forces(self, omega: FloatArray, u_p: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Thrust and torque of the blade element at 0.7 R (eq. 14-15), polynomial form."""
        v_t = self._r07 * omega
        uu, tt = u_p * u_p, v_t * v_t
        c2b, s2b = tt - uu, 2.0 * u_p * v_t
        lift = (self._sin2p * c2b - self._cos2p * s2b) * np.where(
            omega >= 0.0, self._lift_k[0], self._lift_k[1])
        drag = self._drag_k * (uu + tt - self._cos2p * c2b - self._sin2p * s2b)
        inv_v = 1.0 / np.maximum(np.sqrt(uu + tt), 1e-9)
        return ((lift * v_t - drag * u_p) * inv_v,
                self._r07 * (lift * u_p + drag * v_t) * inv_v)

    def driver(self, f_td: FloatArray, omega: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Reference speed Ω_r (eq. 11) and clamped motor current i_m (eq. 12)."""
        forward = f_td >= 0.0
        omega_r = np.where(forward, self._inv_sqrt_alpha_2[0], -self._inv_sqrt_alpha_2[1])
        omega_r = omega_r * np.sqrt(np.abs(f_td))
        current = (np.where(forward, self._ff_gain[0], self._ff_gain[1]) * f_td
                   + self._ff_friction * omega_r
                   + self._p.speed_feedback_gain * (omega_r - omega))
        return omega_r, np.clip(current, -self._p.max_motor_current, self._p.max_motor_current)

    def step(self, tau_b: FloatArray, dt: float) -> FloatArray:
        """Allocate tau_b and advance the thrusters by dt (s) in Euler sub-steps; thrusts."""
        f_td = self.allocate(np.asarray(tau_b, dtype=float))[0]
        p = self._p
        substeps = max(1, math.ceil(dt / self.calibration.max_step)) if dt > 0.0 else 0
        h = dt / max(substeps, 1)
        omega, u_p = self.omega, self.u_p
        omega_r, current = self.driver(f_td, omega)
        thrust, torque = self.thrust, self.torque
        for i in range(substeps):
            if i > 0:
                omega_r, current = self.driver(f_td, omega)
                thrust, torque = self.blade_forces(omega, u_p)
            omega_next = omega + h / p.motor_inertia * (
                p.motor_torque_constant * current - p.motor_viscous_friction * omega - torque)
            u_p = u_p + h / self._duct_mass * (thrust - self._duct_loss * u_p * np.abs(u_p))
            omega = omega_next
        if substeps:
            thrust, torque = self.blade_forces(omega, u_p)
        self.omega, self.u_p, self.omega_r, self.motor_current = omega, u_p, omega_r, current
        self.thrust, self.torque = thrust, torque
        return thrust
