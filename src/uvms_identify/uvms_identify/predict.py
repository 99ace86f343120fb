"""Held-out prediction: the body velocity a hull model predicts from the recorded inputs.

From the measured velocity at a start time, the vehicle's velocity is integrated over a
horizon with the recorded thrusts, attitude and arm motion as inputs (semi-implicit Euler
on the recording's grid)::

    (M_0,vv + M_A) nu_dot = tau - bias_0(q, w) - M_0,va q_ddot - hull(theta, nu, 0)

and compared with the measured velocity at the horizon's end. Attitude and arm are taken
as recorded (not predicted): the figure is the velocity error of the hull model.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from uvms_model.model import UvmsModel

from uvms_identify.recording import Series
from uvms_identify.regressor import ADDED_MASS, hull_regressor

FloatArray = NDArray[np.float64]


def simulate(model: UvmsModel, theta: FloatArray, series: Series, start: int,
             steps: int) -> FloatArray:
    """Predicted body velocities (steps + 1, 6) from sample ``start`` of ``series``."""
    nu = series.nu[start].copy()
    out = np.empty((steps + 1, 6))
    out[0] = nu
    q = np.zeros(model.n_dof)
    w = np.zeros(model.n_dof)
    added = np.diag(theta[ADDED_MASS])
    for k in range(steps):
        i = start + k
        dt = series.t_s[i + 1] - series.t_s[i]
        q[3:6] = series.rpy[i]
        q[6:] = series.joints[i]
        w[:6] = nu
        w[6:] = series.joint_rates[i]
        mass = model.mass_matrix_body(q)
        bias = model.bias_body(q, w)[:6] + mass[:6, 6:] @ series.joint_accelerations[i]
        hull = hull_regressor(nu[None, :], np.zeros((1, 6)),
                              series.gravity_body[i][None, :])[0] @ theta
        nu = nu + dt * np.linalg.solve(mass[:6, :6] + added, series.tau[i] - bias - hull)
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
