"""The actuators' terms: the thrusters' gain and time constant, the arm joints' friction.

**Thrusters.** The recorded thrusts ``f`` (what the robot commanded) and the wrench they make
on the hull are related by a gain ``k``, a first-order lag ``T`` and a transport delay ``d``::

    tau(t) = k E L_T[f](t - d),   L_T: T x_dot + x = u  (exact discretization, zero-order hold)

Given ``T`` and ``d``, the hull's equation (``uvms_identify.regressor``) is linear in the
hull's terms and in ``k``: ``L - known = Phi theta + (1 - k) L`` with ``L = E L_T[f]``.
``search_thrust_path`` scores every (``T``, ``d``) of a grid by the weighted residual of
that least-squares problem (projections on the hull regressor, unconstrained: the score
only chooses ``T`` and ``d``) and takes the best; ``k`` and its 95 % CI follow from the
same projection (Frisch-Waugh-Lovell: the coefficient and variance of the joint fit). The
interval of ``T`` is its profile's: the grid values whose best residual over ``d`` stays
within the likelihood-ratio bound ``N_eff ln(S / S_min) <= 3.84``. A lag and a delay act
alike on slow inputs: when the data cannot tell them apart the interval is wide and ``T``
is named unidentifiable.

**Arm joints.** Per joint ``i``, the torque the robot commanded minus the arm rows of its
model (``M q_ddot + bias``, rigid bodies, weights, links' hydrodynamics) is its friction::

    tau_i - (M w_dot + b)_i = f_v,i q_dot_i + f_c,i tanh(q_dot_i / COULOMB_SMOOTHING_RAD_S)

fitted per joint by bounded least squares (both >= 0), 95 % CIs as the hull's
(``uvms_identify.fit``: residual covariance widened by the lag-1 autocorrelation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter  # type: ignore[import-untyped]

from uvms_identify.fit import MAX_RELATIVE_CI, WELL_DETERMINED_CI, _lag1, _solve

FloatArray = NDArray[np.float64]

#: First-order lags searched (s): 0 (the recorded thrust is the thrust) to 0.2 s.
TIME_CONSTANTS_S = tuple(round(0.01 * i, 3) for i in range(21))
#: Velocity scale of the smoothed Coulomb friction (rad/s).
COULOMB_SMOOTHING_RAD_S = 0.01
#: A joint whose rate has an RMS under this (rad/s) did not move: its friction not excited.
MIN_JOINT_RATE_RAD_S = 0.01
#: chi-square(1) at 95 %: the profile likelihood's bound.
CHI2_95 = 3.841


@dataclass(frozen=True)
class Term:
    """One identified term with its interval and status.

    Attributes:
        name: The term's name (``thrust_gain``, ``joint_1_viscous_friction_n_m_s`` ...).
        value: Identified value, or the prior when unidentifiable.
        ci95: Half-width of the 95 % interval (NaN when not fitted).
        status: ``well determined``, ``identified`` or ``unidentifiable: ...``.
        unit: Its unit.
    """

    name: str
    value: float
    ci95: float
    status: str
    unit: str

    @property
    def identified(self) -> bool:
        """Whether the data determined it (not held at the prior)."""
        return not self.status.startswith('unidentifiable')


def status_of(value: float, ci95: float, floor: float) -> str:
    """The status rule of the hull's terms (``uvms_identify.fit``) for one term."""
    if ci95 > MAX_RELATIVE_CI * max(abs(value), 1e-12) and ci95 > 0.05 * floor:
        return f'unidentifiable: 95 % CI +-{ci95:.3g} about a fitted {value:.3g}'
    if ci95 <= WELL_DETERMINED_CI * max(abs(value), 1e-12):
        return 'well determined'
    return 'identified'


def first_order_lag(values: FloatArray, dt_s: float, time_constant_s: float) -> FloatArray:
    """``values`` (N, k) through T x_dot + x = u (zero-order hold), starting at rest at u_0."""
    values = np.asarray(values, dtype=float)
    if time_constant_s <= 0.0:
        return values
    a = math.exp(-dt_s / time_constant_s)
    initial = (a * values[0])[None, :]
    lagged, _ = lfilter([1.0 - a], [1.0, -a], values, axis=0, zi=initial)
    return np.asarray(lagged, dtype=float)


def delayed(t_s: FloatArray, values: FloatArray, delay_s: float) -> FloatArray:
    """``values`` (N, k) at t - delay_s (linear interpolation, held at the ends)."""
    if delay_s == 0.0:
        return np.asarray(values, dtype=float)
    return np.column_stack([np.interp(t_s - delay_s, t_s, column) for column in values.T])


@dataclass(frozen=True)
class ThrustPath:
    """The recorded thrusts' path to the hull: gain, lag and delay.

    Attributes:
        gain: ``thrust_gain`` (-): the thrust made per thrust recorded.
        time_constant: ``thrust_time_constant_s`` (s): the first-order lag.
        delay_s: The transport delay (s) (best of the grid; reported, not a robot key).
        weights: Per axis, the inverse residual standard deviation used (6,).
    """

    gain: Term
    time_constant: Term
    delay_s: float
    weights: FloatArray

    def wrench(self, t_s: FloatArray, tau: FloatArray) -> FloatArray:
        """The wrench (N, 6) the recorded thrust wrench ``tau`` makes on the hull."""
        dt = float(np.median(np.diff(t_s))) if t_s.size > 1 else 0.02
        lagged = first_order_lag(delayed(t_s, tau, self.delay_s), dt,
                                 self.time_constant.value)
        return self.gain.value * lagged


def _project(q: FloatArray, x: FloatArray) -> FloatArray:
    projected: FloatArray = x - q @ (q.T @ x)
    return projected


def search_thrust_path(series_t: list[FloatArray], series_tau: list[FloatArray],
                       known: list[FloatArray], phi: FloatArray, weights: FloatArray,
                       delays_s: tuple[float, ...],
                       time_constants_s: tuple[float, ...] = TIME_CONSTANTS_S,
                       gain: Term | None = None) -> ThrustPath:
    """The gain, lag and delay of the thrusts that fit the hull's equation best.

    Args:
        series_t: Per series, its times (N_i,) (s).
        series_tau: Per series, the recorded thrust wrench (N_i, 6).
        known: Per series, the known terms of the robot (N_i, 6).
        phi: The hull regressor of all series, concatenated (N, 6, P).
        weights: Per axis, the rows' weight (6,): inverse residual standard deviation.
        delays_s: The delays searched (s).
        time_constants_s: The lags searched (s).
        gain: A gain already decided (its value is used, not fitted), or None to fit it.
    """
    n = phi.shape[0]
    a = (phi * weights[None, :, None]).reshape(n * 6, phi.shape[2])
    norms = np.linalg.norm(a, axis=0)
    a = a[:, norms > 0.0]
    q, _ = np.linalg.qr(a)
    rows = n * 6
    known_perp = _project(q, (np.concatenate(known) * weights).reshape(rows))
    scores: dict[tuple[float, float], tuple[float, float, float]] = {}
    for time_constant in time_constants_s:
        lagged = []
        for t, tau in zip(series_t, series_tau, strict=True):
            dt = float(np.median(np.diff(t)))
            lagged.append((t, first_order_lag(tau, dt, time_constant)))
        for delay in delays_s:
            drive = np.concatenate([delayed(t, tau, delay) for t, tau in lagged])
            g_perp = _project(q, (drive * weights).reshape(rows))
            y_perp = g_perp - known_perp
            gg = float(g_perp @ g_perp)
            if gain is not None:
                c = 1.0 - gain.value
            else:
                c = float(g_perp @ y_perp) / gg if gg > 0.0 else 0.0
            residual = y_perp - c * g_perp
            scores[(time_constant, delay)] = (float(residual @ residual), c, gg)
    (time_constant, delay), (best, c, gg) = min(scores.items(), key=lambda item: item[1][0])
    # Effective independent samples: the residual's lag-1 autocorrelation (as the hull's CIs).
    drive_lagged = []
    for t, tau in zip(series_t, series_tau, strict=True):
        dt = float(np.median(np.diff(t)))
        drive_lagged.append(delayed(t, first_order_lag(tau, dt, time_constant), delay))
    g_perp = _project(q, (np.concatenate(drive_lagged) * weights).reshape(rows))
    rho = _lag1(((1.0 - c) * g_perp - known_perp).reshape(n, 6))
    # The lag's profile: per T, the best over the delays; its 95 % interval.
    profile = {tc: min(scores[(tc, d)][0] for d in delays_s) for tc in time_constants_s}
    n_eff = rows * (1.0 - rho) / (1.0 + rho)
    if best <= 0.0:
        inside = [time_constant]
    else:
        inside = [tc for tc, s in profile.items() if n_eff * math.log(max(s, best) / best)
                  <= CHI2_95]
    lag_ci = max(abs(tc - time_constant) for tc in inside)
    grid_edge = min(inside) == min(time_constants_s) and max(inside) == max(time_constants_s)
    if grid_edge and len(time_constants_s) > 1:
        lag_status = (f'unidentifiable: every lag {min(time_constants_s):g}-'
                      f'{max(time_constants_s):g} s fits within the 95 % bound (a lag and '
                      'the delay act alike on these inputs)')
    else:
        lag_status = status_of(time_constant, lag_ci, 0.2)
    lag = Term('thrust_time_constant_s', time_constant, lag_ci, lag_status, 's')
    if not lag.identified:
        # The prior (the first lag of the grid: none) and the delay that fits best with it.
        time_constant = time_constants_s[0]
        delay = min(delays_s, key=lambda d: scores[(time_constant, d)][0])
        best, c, gg = scores[(time_constant, delay)]
        lag = Term(lag.name, time_constant, lag_ci, lag_status, 's')
    dof = max(rows - q.shape[1] - 1, 1)
    s2 = best / dof * (1.0 + rho) / (1.0 - rho)
    gain_value = 1.0 - c
    gain_ci = 1.96 * math.sqrt(s2 / gg) if gg > 0.0 else math.inf
    gain_status = status_of(gain_value, gain_ci, 1.0) if gg > 0.0 else \
        'unidentifiable: not excited'
    if gain is None:
        gain = Term('thrust_gain', gain_value if not gain_status.startswith('unidentifiable')
                    else 1.0, gain_ci, gain_status, '-')
    return ThrustPath(gain, lag, delay, weights)


def checked_gain(path: ThrustPath, other: Term) -> ThrustPath:
    """``path`` with its gain named unidentifiable when ``other`` (other rows) disagrees.

    The gain scales every hull term at once; only the robot's known terms (the rigid-body
    mass, the weight's moment) tell it from them, so a torque or force the model lacks moves
    it while its interval stays narrow. Two estimates from different rows (all axes, the
    translations alone) that differ by more than their intervals together show it: the
    gain keeps its prior (1) and the hull is fitted with the thrusts as recorded.
    """
    gain = path.gain
    if not gain.identified or not other.identified:
        return path
    if abs(gain.value - other.value) <= gain.ci95 + other.ci95:
        return path
    status = (f'unidentifiable: all axes give {gain.value:.3g} +- {gain.ci95:.2g}, surge, '
              f'sway and heave alone {other.value:.3g} +- {other.ci95:.2g} (the gain trades '
              'with the hull terms; a force the model lacks moves it)')
    return ThrustPath(Term(gain.name, 1.0, gain.ci95, status, gain.unit), path.time_constant,
                      path.delay_s, path.weights)


def fit_joint_friction(joint_rates: FloatArray, torque: FloatArray,
                       names: list[str]) -> list[Term]:
    """Viscous and Coulomb friction per joint (2 terms per joint, in joint order).

    Args:
        joint_rates: Joint rates (N, n) (rad/s).
        torque: Commanded torque minus the model's arm rows (N, n) (N m).
        names: The joints' names (n).
    """
    terms = []
    for i, name in enumerate(names):
        rate = joint_rates[:, i]
        viscous_name = f'{name}_viscous_friction_n_m_s'
        coulomb_name = f'{name}_coulomb_friction_n_m'
        if float(np.sqrt(np.mean(rate**2))) < MIN_JOINT_RATE_RAD_S:
            terms += [Term(viscous_name, 0.0, math.nan, 'unidentifiable: not excited',
                           'N m s/rad'),
                      Term(coulomb_name, 0.0, math.nan, 'unidentifiable: not excited', 'N m')]
            continue
        a = np.column_stack([rate, np.tanh(rate / COULOMB_SMOOTHING_RAD_S)])
        b = torque[:, i]
        x = _solve(a, b, np.zeros(2))
        residual = b - a @ x
        rho = _lag1(residual[:, None])
        dof = max(b.size - 2, 1)
        s2 = float(residual @ residual) / dof * (1.0 + rho) / (1.0 - rho)
        covariance = np.linalg.pinv(a.T @ a) * s2
        ci = 1.96 * np.sqrt(np.maximum(np.diag(covariance), 0.0))
        for value, half, term_name, unit, floor in (
                (x[0], ci[0], viscous_name, 'N m s/rad', 0.1),
                (x[1], ci[1], coulomb_name, 'N m', 0.1)):
            status = status_of(float(value), float(half), floor)
            kept = float(value) if not status.startswith('unidentifiable') else 0.0
            terms.append(Term(term_name, kept, float(half), status, unit))
    return terms
