"""The constrained least-squares fit of the hull's terms, with confidence and identifiability.

``fit_hull`` solves ``y = Phi theta`` (``uvms_identify.regressor``) by bounded linear least
squares (``scipy.optimize.lsq_linear``: added mass, damping and buoyancy >= 0, so the mass
matrix stays symmetric positive definite and the damping dissipates), rows weighted by the
inverse residual standard deviation of their axis. A term is **unidentifiable** when the data
do not determine it: its regressor column is not excited (the column's RMS under
``MIN_EXCITATION``), or its 95 % confidence interval is wider than ``MAX_RELATIVE_CI`` of its
value. Unidentifiable terms keep the prior (the robot folder's
value) and the others are fitted again with them fixed.

Confidence intervals come from the residual covariance, ``s^2 (A^T A)^-1`` of the weighted
problem, widened by the residuals' lag-1 autocorrelation (the effective number of
independent samples, ``N (1 - rho) / (1 + rho)``): samples of a smooth time series are not
independent, and intervals without it would be far too narrow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import lsq_linear  # type: ignore[import-untyped]

from uvms_identify.errors import IdentifyError
from uvms_identify.regressor import AXES, LOWER_BOUNDS, N_PARAMETERS, PARAMETER_NAMES

FloatArray = NDArray[np.float64]

#: A term whose regressor column has an RMS under this (m/s^2, m/s, m^2/s^2 or their
#: rotational units; the sine of the tilt for the buoyancy's moments) is not excited.
MIN_EXCITATION = 0.01
#: A term whose 95 % CI half-width exceeds this fraction of its value is unidentifiable.
MAX_RELATIVE_CI = 0.5
#: A term within this relative CI is well determined (the report's "well excited").
WELL_DETERMINED_CI = 0.1
#: Typical magnitude per parameter kind, where the prior is 0 (kg, kg m^2, damping, N, N m).
_FLOOR = np.r_[np.full(3, 1.0), np.full(3, 0.01), np.full(3, 1.0), np.full(3, 0.01),
               np.full(3, 1.0), np.full(3, 0.01), 1.0, np.full(3, 0.05)]


@dataclass(frozen=True)
class HullFit:
    """The fitted hull terms.

    Attributes:
        theta: Parameters (22,) in the order of ``PARAMETER_NAMES``; unidentifiable ones
            hold the prior.
        ci95: Half-widths of their 95 % confidence intervals (22,), NaN where not fitted.
        status: Per parameter: ``well determined``, ``identified`` or ``unidentifiable: ...``.
        r2: Coefficient of determination of the force fit per axis (6,).
        residual_std: Standard deviation of the force residual per axis (6,) (N, N m).
        condition_number: Of the column-normalized weighted regressor of the fitted terms.
        samples: Number of time samples used.
    """

    theta: FloatArray
    ci95: FloatArray
    status: tuple[str, ...]
    r2: FloatArray
    residual_std: FloatArray
    condition_number: float
    samples: int

    def identified(self, index: int) -> bool:
        """Whether parameter ``index`` was fitted (not held at the prior)."""
        return not self.status[index].startswith('unidentifiable')

    def well_determined(self, index: int) -> bool:
        """Whether parameter ``index`` is within ``WELL_DETERMINED_CI`` (the report's list)."""
        return self.status[index] == 'well determined'


def _solve(a: FloatArray, b: FloatArray, lower: FloatArray) -> FloatArray:
    """Bounded least squares min |a x - b| with x >= lower, columns normalized."""
    norms = np.linalg.norm(a, axis=0)
    norms[norms == 0.0] = 1.0
    result = lsq_linear(a / norms, b, bounds=(lower * norms, np.full(a.shape[1], np.inf)),
                        method='bvls', lsq_solver='exact')
    x: FloatArray = result.x / norms
    return x


def _lag1(residual: FloatArray) -> float:
    """Largest lag-1 autocorrelation of the residual's axes, in [0, 0.99]."""
    worst = 0.0
    for column in residual.T:
        c = column - column.mean()
        denominator = float(c @ c)
        if denominator > 0.0 and c.size > 2:
            worst = max(worst, float(c[1:] @ c[:-1]) / denominator)
    return min(max(worst, 0.0), 0.99)


def fit_hull(y: FloatArray, phi: FloatArray, prior: FloatArray,
             fixed: tuple[int, ...] = ()) -> HullFit:
    """Fit theta of ``y = Phi theta`` with the physical bounds; see the module docstring.

    Args:
        y: Generalized force of the hull per sample (N, 6): thrust wrench minus the known
            terms of the robot (N, N m).
        phi: The hull regressor (N, 6, 22).
        prior: The robot folder's theta (22,): the value of terms the data cannot identify.
        fixed: Indices held at the prior whatever the data (e.g. terms the user fixes).

    Raises:
        IdentifyError: Shapes that do not match, non-finite data, or no term excited.
    """
    y = np.asarray(y, dtype=float)
    phi = np.asarray(phi, dtype=float)
    prior = np.asarray(prior, dtype=float)
    n = y.shape[0]
    if y.shape != (n, 6) or phi.shape != (n, 6, N_PARAMETERS) or prior.shape != (N_PARAMETERS,):
        raise IdentifyError(f'fit_hull: shapes y {y.shape}, phi {phi.shape}, prior '
                            f'{prior.shape} do not match (N, 6), (N, 6, 22), (22,)')
    if not (np.isfinite(y).all() and np.isfinite(phi).all()):
        raise IdentifyError('fit_hull: the data hold NaN or infinite values')
    scale = np.maximum(np.abs(prior), _FLOOR)
    axis_rms = np.sqrt(np.mean(y**2, axis=0))
    axis_rms[axis_rms == 0.0] = 1.0
    unidentifiable: dict[int, str] = {int(i): 'unidentifiable: fixed by the user' for i in fixed}
    for j in range(N_PARAMETERS):
        if j in unidentifiable:
            continue
        if float(np.sqrt(np.mean(phi[:, :, j] ** 2, axis=0)).max()) < MIN_EXCITATION:
            unidentifiable[j] = 'unidentifiable: not excited'
    weights = 1.0 / axis_rms
    theta = prior.copy()
    ci = np.full(N_PARAMETERS, np.nan)
    condition = math.nan
    for _ in range(4):
        free = [j for j in range(N_PARAMETERS) if j not in unidentifiable]
        if not free:
            break
        held = [j for j in range(N_PARAMETERS) if j in unidentifiable]
        a = (phi[:, :, free] * weights[None, :, None]).reshape(n * 6, len(free))
        b = ((y - phi[:, :, held] @ prior[held]) * weights).reshape(n * 6)
        theta = prior.copy()
        theta[free] = _solve(a, b, LOWER_BOUNDS[free])
        residual = y - phi @ theta
        sigma = residual.std(axis=0)
        sigma[sigma == 0.0] = 1.0
        weights = 1.0 / sigma
        a = (phi[:, :, free] * weights[None, :, None]).reshape(n * 6, len(free))
        weighted = (residual * weights).reshape(n * 6)
        dof = max(a.shape[0] - len(free), 1)
        rho = _lag1(residual)
        s2 = float(weighted @ weighted) / dof * (1.0 + rho) / (1.0 - rho)
        norms = np.linalg.norm(a, axis=0)
        norms[norms == 0.0] = 1.0
        normalized = a / norms
        condition = float(np.linalg.cond(normalized))
        covariance = np.linalg.pinv(normalized.T @ normalized) * s2
        ci = np.full(N_PARAMETERS, np.nan)
        ci[free] = 1.96 * np.sqrt(np.maximum(np.diag(covariance), 0.0)) / norms
        newly = {}
        for j in free:
            relative = ci[j] / max(abs(theta[j]), 1e-12)
            if relative > MAX_RELATIVE_CI and ci[j] > 0.05 * scale[j]:
                newly[j] = (f'unidentifiable: 95 % CI +-{ci[j]:.3g} about a '
                            f'fitted {theta[j]:.3g}')
        if not newly:
            break
        unidentifiable.update(newly)
    status = []
    for j in range(N_PARAMETERS):
        if j in unidentifiable:
            status.append(unidentifiable[j])
        elif ci[j] <= WELL_DETERMINED_CI * max(abs(theta[j]), 1e-12):
            status.append('well determined')
        else:
            status.append('identified')
    if all(s.startswith('unidentifiable') for s in status) and not fixed:
        raise IdentifyError('no hull term is excited by the recordings (the vehicle did not '
                            'move): run the experiments of `uvms identify plan`')
    residual = y - phi @ theta
    total = ((y - y.mean(axis=0)) ** 2).sum(axis=0)
    total[total == 0.0] = 1.0
    r2 = 1.0 - (residual**2).sum(axis=0) / total
    return HullFit(theta, ci, tuple(status), r2, residual.std(axis=0), condition, n)


def describe(fit: HullFit) -> list[str]:
    """One line per parameter: name, value, CI and status."""
    lines = []
    for j, name in enumerate(PARAMETER_NAMES):
        ci = '' if math.isnan(fit.ci95[j]) else f' +- {fit.ci95[j]:.3g}'
        lines.append(f'{name}: {fit.theta[j]:.4g}{ci} ({fit.status[j]})')
    return lines


__all__ = ['AXES', 'PARAMETER_NAMES', 'HullFit', 'describe', 'fit_hull']
