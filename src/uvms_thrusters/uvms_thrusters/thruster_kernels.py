"""Compiled per-thruster formulas of the Healey thruster model (paper eq. 11-15).

One copy of each formula, for one thruster at a time: the blade element at 0.7 R, the motor
driver, and the explicit-Euler sub-steps of a bank. ``ThrusterBank`` in
``thruster_dynamics`` (which derives the constants and states the model) calls them; its
vector methods loop over the thrusters here instead of building numpy temporaries.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from uvms_model.jit import kernel

FloatArray = npt.NDArray[np.float64]


#: The constants the kernels read (SI units), one record derived by ``ThrusterBank``:
#: r07 0.7 R, blade-element radius (m); lift_k_forward, lift_k_reverse ½ ρ A C_Lmax, times
#: η_r in reverse (Ω < 0) (kg/m); drag_k ½ ρ A C_Dmax (kg/m); sin2p, cos2p of the blade
#: pitch p (-); duct_mass ρ A_p L_d γ (kg); duct_loss ρ A_p Δβ (kg/m);
#: inv_sqrt_alpha_2_forward/_reverse 1/sqrt(α_2) of eq. 11 (rad/(s sqrt(N)));
#: ff_gain_forward/_reverse α_1 / K_t of eq. 12 (A/N); ff_friction K_f / K_t (A s/rad);
#: speed_feedback_gain K_fb (A s/rad); max_motor_current i_max (A); motor_torque_constant
#: K_t (N m/A); motor_viscous_friction K_f (N m s/rad); motor_inertia J_m (kg m²).
#: A record array, not a tuple: Numba passes an array to a kernel in well under a
#: microsecond, a tuple of 18 floats in several.
THRUSTER_CONSTANTS = np.dtype([(name, np.float64) for name in (
    'r07', 'lift_k_forward', 'lift_k_reverse', 'drag_k', 'sin2p', 'cos2p', 'duct_mass',
    'duct_loss', 'inv_sqrt_alpha_2_forward', 'inv_sqrt_alpha_2_reverse', 'ff_gain_forward',
    'ff_gain_reverse', 'ff_friction', 'speed_feedback_gain', 'max_motor_current',
    'motor_torque_constant', 'motor_viscous_friction', 'motor_inertia',
)])


def thruster_constants(**values: float) -> npt.NDArray[np.void]:
    """The one-record array of ``THRUSTER_CONSTANTS`` the kernels take, from its fields.

    Raises:
        TypeError: A field is missing or unknown (named).
    """
    names = THRUSTER_CONSTANTS.names or ()
    missing, unknown = set(names) - set(values), set(values) - set(names)
    if missing or unknown:
        msg = f'thruster constants: missing {sorted(missing)}, unknown {sorted(unknown)}'
        raise TypeError(msg)
    return np.array([tuple(float(values[name]) for name in names)], dtype=THRUSTER_CONSTANTS)


@kernel
def blade_element(
    constants: npt.NDArray[np.void], omega: float, u_p: float
) -> tuple[float, float]:
    """Thrust T (N) and shaft torque Q (N m) of the blade element at 0.7 R (eq. 14-15).

    Written without trigonometric calls: with V² = u_p² + V_t², cos 2β = (V_t² - u_p²)/V²
    and sin 2β = 2 u_p V_t / V², so V² sin 2α and V² cos 2α (α = p - β) are polynomials.
    """
    c = constants[0]
    v_t = c['r07'] * omega
    uu = u_p * u_p
    tt = v_t * v_t
    c2b = tt - uu  # V² cos 2β
    s2b = 2.0 * u_p * v_t  # V² sin 2β
    # ½ρA C_Lmax V² sin 2α, with C_Lmax scaled by η_r in reverse rotation.
    lift_k = c['lift_k_forward'] if omega >= 0.0 else c['lift_k_reverse']
    lift = (c['sin2p'] * c2b - c['cos2p'] * s2b) * lift_k
    # ½ρA C_Dmax V² (1 - cos 2α).
    drag = c['drag_k'] * (uu + tt - c['cos2p'] * c2b - c['sin2p'] * s2b)
    inv_v = 1.0 / max(np.sqrt(uu + tt), 1e-9)  # L and D vanish as V², so T, Q -> 0
    thrust = (lift * v_t - drag * u_p) * inv_v  # L cos β - D sin β
    torque = c['r07'] * (lift * u_p + drag * v_t) * inv_v  # 0.7 R (L sin β + D cos β)
    return thrust, torque


@kernel
def motor_driver(
    constants: npt.NDArray[np.void], f_td: float, omega: float
) -> tuple[float, float]:
    """Reference speed Ω_r (rad/s, eq. 11) and motor current i_m (A, eq. 12, sign-corrected).

    i_m = (α_1 F_td + K_f Ω_r) / K_t + K_fb (Ω_r - Ω), clamped to ±i_max.
    """
    c = constants[0]
    if f_td >= 0.0:
        omega_r = c['inv_sqrt_alpha_2_forward'] * np.sqrt(f_td)
        current = c['ff_gain_forward'] * f_td
    else:
        omega_r = -c['inv_sqrt_alpha_2_reverse'] * np.sqrt(-f_td)
        current = c['ff_gain_reverse'] * f_td
    current += c['ff_friction'] * omega_r
    current += c['speed_feedback_gain'] * (omega_r - omega)
    current = min(max(current, -c['max_motor_current']), c['max_motor_current'])
    return omega_r, current


@kernel
def state_derivative(
    constants: npt.NDArray[np.void], f_td: float, omega: float, u_p: float
) -> tuple[float, float]:
    """(Ω_dot, u_p_dot) of one thruster (eq. 13 and the duct flow, eq. 15).

    J_m Ω_dot = K_t i_m - K_f Ω - Q;  ρ A_p L_d γ u_p_dot = T - ρ A_p Δβ u_p |u_p|.
    """
    c = constants[0]
    _, current = motor_driver(constants, f_td, omega)
    thrust, torque = blade_element(constants, omega, u_p)
    omega_dot = (c['motor_torque_constant'] * current - c['motor_viscous_friction'] * omega
                 - torque) / c['motor_inertia']
    u_dot = (thrust - c['duct_loss'] * u_p * abs(u_p)) / c['duct_mass']
    return omega_dot, u_dot


@kernel
def euler_step_bank(
    constants: npt.NDArray[np.void],
    f_td: FloatArray,
    dt: float,
    max_step: float,
    omega: FloatArray,
    u_p: FloatArray,
    omega_r: FloatArray,
    current: FloatArray,
    thrust: FloatArray,
    torque: FloatArray,
) -> bool:
    """Advance every thruster by dt (s) toward desired thrusts f_td (N), in place.

    Explicit Euler in ceil(dt / max_step) equal sub-steps (none for dt = 0). On entry
    ``thrust`` and ``torque`` hold the blade forces of the current (Ω, u_p), so each sub-step
    evaluates the blade element once; on return the six arrays hold the new Ω and u_p, the
    driver's Ω_r and i_m of the last sub-step, and the blade forces of the new state.

    Returns:
        False, with nothing changed, if f_td holds a NaN or Inf; True otherwise.
    """
    for k in range(f_td.size):
        if not np.isfinite(f_td[k]):
            return False
    c = constants[0]
    substeps = max(1, int(np.ceil(dt / max_step))) if dt > 0.0 else 0
    h = dt / max(substeps, 1)
    for k in range(f_td.size):
        w, u = omega[k], u_p[k]
        t, q = thrust[k], torque[k]
        w_r, i_m = motor_driver(constants, f_td[k], w)
        for i in range(substeps):
            if i > 0:
                w_r, i_m = motor_driver(constants, f_td[k], w)
                t, q = blade_element(constants, w, u)
            w_next = w + h / c['motor_inertia'] * (
                c['motor_torque_constant'] * i_m - c['motor_viscous_friction'] * w - q)
            u = u + h / c['duct_mass'] * (t - c['duct_loss'] * u * abs(u))
            w = w_next
        if substeps > 0:
            t, q = blade_element(constants, w, u)
        omega[k], u_p[k] = w, u
        omega_r[k], current[k] = w_r, i_m
        thrust[k], torque[k] = t, q
    return True
