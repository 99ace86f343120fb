"""Held-out prediction: the body velocity a hull model predicts from the recorded inputs.

From the measured velocity and attitude at a start time, the vehicle's velocity and
attitude are integrated over a horizon with the recorded thrusts and arm motion as inputs
(semi-implicit Euler on the recording's grid: the velocity first, the attitude with it)::

    (M_0,vv + M_A) nu_dot = tau - bias_0(q, w) - M_0,va q_ddot - hull(theta, nu, 0)
    R_dot = R [omega]x

and compared with the measured velocity at the horizon's end. The arm is taken as recorded
(the controller moves it); the attitude is predicted, because the restoring moment of
weight and buoyancy is what bounds roll and pitch: with the recorded attitude instead, the
moment does not answer the predicted motion, and a torque error of 0.01 N m (the arm's,
the thrusts') integrates for the whole horizon. On issue 50's acceptance recordings that
made even the true hull predict roll, pitch and yaw worse at 10 s than the shipped one
(docs/identification.md, "Held-out prediction").
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from uvms_model.model import UvmsModel

from uvms_identify.recording import Series
from uvms_identify.regressor import ADDED_MASS, hull_regressor
from uvms_identify.signals import euler_zyx, rpy_matrix

FloatArray = NDArray[np.float64]


def rotation_step(rates_rad_s: FloatArray, dt_s: float) -> FloatArray:
    """The body rotation (3, 3) over ``dt_s`` at constant body rates (Rodrigues)."""
    angle = float(np.linalg.norm(rates_rad_s)) * dt_s
    x, y, z = rates_rad_s * dt_s
    skew: FloatArray = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]], dtype=float)
    if angle < 1e-9:
        sine, versine = 1.0, 0.5
    else:
        sine, versine = np.sin(angle) / angle, (1.0 - np.cos(angle)) / angle**2
    result: FloatArray = np.eye(3) + sine * skew + versine * skew @ skew
    return result


def simulate(model: UvmsModel, theta: FloatArray, series: Series, start: int,
             steps: int) -> FloatArray:
    """Predicted body velocities (steps + 1, 6) from sample ``start`` of ``series``.

    The attitude starts at the recorded one and follows the predicted rates.
    """
    nu = series.nu[start].copy()
    rotation = rpy_matrix(*series.rpy[start])
    out = np.empty((steps + 1, 6))
    out[0] = nu
    q = np.zeros(model.n_dof)
    w = np.zeros(model.n_dof)
    added = np.diag(theta[ADDED_MASS])
    for k in range(steps):
        i = start + k
        dt = series.t_s[i + 1] - series.t_s[i]
        q[3:6] = euler_zyx(rotation[None])[0]
        q[6:] = series.joints[i]
        w[:6] = nu
        w[6:] = series.joint_rates[i]
        mass = model.mass_matrix_body(q)
        bias = model.bias_body(q, w)[:6] + mass[:6, 6:] @ series.joint_accelerations[i]
        hull = hull_regressor(nu[None, :], np.zeros((1, 6)),
                              rotation[2][None, :])[0] @ theta
        nu = nu + dt * np.linalg.solve(mass[:6, :6] + added, series.tau[i] - bias - hull)
        rotation = rotation @ rotation_step(nu[3:], dt)
        out[k + 1] = nu
    return out


def horizon_errors(model: UvmsModel, theta: FloatArray, series_list: list[Series],
                   horizon_s: float, every_s: float = 1.0) -> tuple[FloatArray, int]:
    """RMS velocity error per axis (6,) at ``horizon_s`` over start points every ``every_s``.

    Returns:
        The RMS errors (m/s, rad/s) and the number of windows.
    """
    errors = []
    for series in series_list:
        dt = float(np.median(np.diff(series.t_s)))
        steps = round(horizon_s / dt)
        stride = max(round(every_s / dt), 1)
        for start in range(0, len(series.t_s) - steps - 1, stride):
            predicted = simulate(model, theta, series, start, steps)
            errors.append(predicted[-1] - series.nu[start + steps])
    if not errors:
        return np.full(6, np.nan), 0
    array = np.array(errors)
    return np.sqrt(np.mean(array**2, axis=0)), len(errors)
