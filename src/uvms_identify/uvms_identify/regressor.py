"""The hull's hydrodynamic terms as a linear regressor (Fossen's model, body frame).

The vehicle rows of the equations of motion (eq. 8 of the model, base_link_frd about O)::

    M_0 w_dot + bias_0(q, w) + M_A nu_dot + C_A(nu) nu + D_l nu + D_q |nu| nu - f_B(q) = tau

where ``M_0`` and ``bias_0`` are the robot without the hull's hydrodynamics (rigid bodies,
weights, the arm's added mass, drag and buoyancy: known from the robot folder) and the hull's
terms are linear in the parameters ``theta``::

    theta = [A_1..A_6, d_l1..d_l6, d_q1..d_q6, B, B x_b, B y_b, B z_b]

with ``M_A = diag(A)`` (magnitudes, kg and kg m^2), ``D_l = diag(d_l)``, ``D_q = diag(d_q)``
and the hull's buoyancy ``B`` (N) acting at ``r_b`` (m): ``f_B = [-B g_b; r_b x (-B g_b)]``
where ``g_b = R^T e_z`` is the direction of gravity in base_link_frd. ``C_A(nu) nu`` is
``[omega x a_lin; v x a_lin + omega x a_ang]`` with ``a = M_A nu`` (Fossen 2011, eq. 6.43).
The model of the simulator computes these exactly (a test compares them).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

AXES = ('surge', 'sway', 'heave', 'roll', 'pitch', 'yaw')
#: Parameter names in the order of theta, with their units.
PARAMETER_NAMES: tuple[str, ...] = (
    *(f'added_mass_{axis}' for axis in AXES),
    *(f'linear_damping_{axis}' for axis in AXES),
    *(f'quadratic_damping_{axis}' for axis in AXES),
    'buoyancy_n', 'buoyancy_moment_x_n_m', 'buoyancy_moment_y_n_m', 'buoyancy_moment_z_n_m',
)
N_PARAMETERS = len(PARAMETER_NAMES)
ADDED_MASS = slice(0, 6)
LINEAR_DAMPING = slice(6, 12)
QUADRATIC_DAMPING = slice(12, 18)
BUOYANCY = 18
BUOYANCY_MOMENT = slice(19, 22)
#: Lower bounds of theta: added mass, damping and buoyancy are non-negative (M SPD, D >= 0).
LOWER_BOUNDS: FloatArray = np.r_[np.zeros(19), np.full(3, -np.inf)]


def unit(index: int) -> str:
    """The unit of parameter ``index`` of theta."""
    if index < 3:
        return 'kg'
    if index < 6:
        return 'kg m^2'
    if index < 9:
        return 'N s/m'
    if index < 12:
        return 'N m s/rad'
    if index < 15:
        return 'N s^2/m^2'
    if index < 18:
        return 'N m s^2/rad^2'
    return 'N' if index == BUOYANCY else 'N m'


def hull_regressor(nu: FloatArray, nu_dot: FloatArray, gravity_body: FloatArray) -> FloatArray:
    """Phi (N, 6, 22) with the hull's generalized force Phi @ theta (left-hand side of eq. 8).

    Args:
        nu: Body velocities (N, 6): u, v, w (m/s), p, q, r (rad/s), base_link_frd.
        nu_dot: Their time derivatives (N, 6).
        gravity_body: Unit direction of gravity in base_link_frd, R^T e_z (N, 3).
    """
    nu = np.asarray(nu, dtype=float)
    nu_dot = np.asarray(nu_dot, dtype=float)
    g = np.asarray(gravity_body, dtype=float)
    n = nu.shape[0]
    phi = np.zeros((n, 6, N_PARAMETERS))
    v, omega = nu[:, :3], nu[:, 3:]
    for i in range(6):
        phi[:, i, i] = nu_dot[:, i]
        a = np.zeros((n, 6))
        a[:, i] = nu[:, i]
        phi[:, :3, i] += np.cross(omega, a[:, :3])
        phi[:, 3:, i] += np.cross(v, a[:, :3]) + np.cross(omega, a[:, 3:])
        phi[:, i, 6 + i] = nu[:, i]
        phi[:, i, 12 + i] = np.abs(nu[:, i]) * nu[:, i]
    phi[:, :3, BUOYANCY] = g
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1.0
        phi[:, 3:, 19 + k] = np.cross(e, g)
    return phi


def hull_force(theta: FloatArray, nu: FloatArray, nu_dot: FloatArray,
               gravity_body: FloatArray) -> FloatArray:
    """The hull's generalized force (N, 6) of ``theta`` (``hull_regressor`` @ theta)."""
    result: FloatArray = np.asarray(
        hull_regressor(nu, nu_dot, gravity_body) @ np.asarray(theta, float), dtype=float)
    return result


def theta_from_hull(added_mass_kg: FloatArray, linear_damping: FloatArray,
                    quadratic_damping: FloatArray, buoyancy_n: float,
                    center_of_buoyancy_m: FloatArray) -> FloatArray:
    """Theta of a hull given as the hydrodynamics file gives it."""
    theta: FloatArray = np.concatenate([
        np.asarray(added_mass_kg, float), np.asarray(linear_damping, float),
        np.asarray(quadratic_damping, float), [float(buoyancy_n)],
        float(buoyancy_n) * np.asarray(center_of_buoyancy_m, float)])
    return theta
