"""The actuators' terms on synthetic data with known values.

Thrusters' gain and lag, joints' friction: noise free, the values come back exactly; what
the data cannot tell is named.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from uvms_identify.actuators import (
    COULOMB_SMOOTHING_RAD_S,
    Term,
    ThrustPath,
    checked_gain,
    first_order_lag,
    fit_joint_friction,
    search_thrust_path,
)
from uvms_identify.regressor import N_PARAMETERS, hull_regressor

DT = 0.02
DELAYS_S = tuple(round(0.005 * i, 3) for i in range(-4, 9))


def _hull_data(seed: int = 0, n: int = 1500) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                      np.ndarray]:
    """Times, a rich recorded thrust wrench, the hull regressor and a theta (22,)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT
    tau = np.column_stack([sum(a * np.sin(2 * np.pi * f * t + p) for a, f, p in zip(
        rng.uniform(2, 20, 4), rng.uniform(0.05, 2.0, 4), rng.uniform(0, 6, 4), strict=True))
        for _ in range(6)])
    tau += np.repeat(rng.normal(0, 10, (n // 50, 6)), 50, axis=0)  # steps: a lag shows
    nu = np.cumsum(rng.normal(0, 0.01, (n, 6)), axis=0)
    nu_dot = np.gradient(nu, DT, axis=0)
    tilt = 0.2 * np.sin(0.3 * t)
    gravity = np.column_stack([-np.sin(tilt), np.sin(0.5 * tilt), np.cos(tilt)])
    phi = hull_regressor(nu, nu_dot, gravity)
    theta = np.abs(rng.normal(1.0, 0.3, N_PARAMETERS))
    return t, tau, phi, theta


@pytest.mark.parametrize(('gain', 'time_constant_s', 'delay_s'),
                         [(0.8, 0.08, 0.0), (1.0, 0.0, 0.01), (1.15, 0.05, 0.02)])
def test_thrusters_gain_lag_and_delay_come_back_exactly(gain: float, time_constant_s: float,
                                                         delay_s: float) -> None:
    """The wrench made is k L_T[f](t - d); from it and the hull's terms, k, T and d."""
    t, tau, phi, theta = _hull_data()
    made = gain * first_order_lag(np.column_stack([np.interp(t - delay_s, t, c)
                                                   for c in tau.T]), DT, time_constant_s)
    known = made - phi @ theta  # what the robot's own model explains
    path = search_thrust_path([t], [tau], [known], phi, np.ones(6), DELAYS_S)
    assert path.delay_s == pytest.approx(delay_s, abs=1e-12)
    assert path.time_constant.value == pytest.approx(time_constant_s, abs=1e-12)
    assert path.gain.value == pytest.approx(gain, rel=1e-9)
    assert path.gain.status == 'well determined'
    assert path.time_constant.identified
    assert np.allclose(path.wrench(t, tau), made, atol=1e-9)


def test_a_lag_the_inputs_cannot_tell_from_a_delay_is_named_unidentifiable() -> None:
    """Slow thrusts (0.05 Hz) with noise: lag and delay fit alike, the lag is not claimed."""
    rng = np.random.default_rng(3)
    t, _, phi, theta = _hull_data()
    tau = np.column_stack([10 * np.sin(2 * np.pi * 0.05 * t + i) for i in range(6)])
    made = first_order_lag(tau, DT, 0.05)
    known = made - phi @ theta + rng.normal(0, 0.5, made.shape)
    path = search_thrust_path([t], [tau], [known], phi, np.ones(6), DELAYS_S)
    assert not path.time_constant.identified, path.time_constant
    assert path.time_constant.status.startswith('unidentifiable')
    assert path.time_constant.value == 0.0  # the prior: no lag beyond the recorded thrust
    assert path.gain.value == pytest.approx(1.0, abs=0.02)  # the gain still is determined


def test_first_order_lag_is_the_exact_step_response() -> None:
    """A unit step through T = 0.1 s: 1 - exp(-t / T) at the samples; T = 0 passes it."""
    u = np.ones((50, 1))
    u[0] = 0.0
    lagged = first_order_lag(u, DT, 0.1)
    k = np.arange(1, 50)
    assert np.allclose(lagged[1:, 0], 1.0 - np.exp(-k * DT / 0.1), atol=1e-12)
    assert np.array_equal(first_order_lag(u, DT, 0.0), u)


def _joints(n: int = 4000) -> tuple[np.ndarray, list[str]]:
    t = np.arange(n) * DT
    rates = np.column_stack([0.3 * np.sin(0.7 * t), 0.2 * np.sin(1.3 * t + 1.0),
                             0.5 * np.sin(0.4 * t + 2.0), np.zeros(n)])
    return rates, ['joint_1', 'joint_2', 'joint_3', 'joint_4']


def test_joint_friction_comes_back_exactly_and_a_still_joint_is_named() -> None:
    """Viscous and Coulomb friction per joint from the torque the model does not explain."""
    rates, names = _joints()
    viscous = np.array([2.4, 2.2, 0.8, 0.36])
    coulomb = np.array([0.3, 0.0, 0.15, 0.1])
    torque = viscous * rates + coulomb * np.tanh(rates / COULOMB_SMOOTHING_RAD_S)
    terms = fit_joint_friction(rates, torque, names)
    assert [term.name for term in terms[:2]] == ['joint_1_viscous_friction_n_m_s',
                                                 'joint_1_coulomb_friction_n_m']
    for i in range(3):
        assert terms[2 * i].value == pytest.approx(viscous[i], abs=1e-9)
        assert terms[2 * i + 1].value == pytest.approx(coulomb[i], abs=1e-9)
        assert terms[2 * i].status == 'well determined'
    assert terms[6].status == terms[7].status == 'unidentifiable: not excited'
    assert terms[6].value == terms[7].value == 0.0


def test_joint_friction_buried_in_noise_is_named_unidentifiable() -> None:
    """0.01 N m s/rad under 1 N m of noise: the data cannot tell it; it is not claimed."""
    rng = np.random.default_rng(1)
    rates, names = _joints()
    torque = 0.01 * rates + rng.normal(0.0, 1.0, rates.shape)
    terms = fit_joint_friction(rates, torque, names)
    assert terms[0].status.startswith('unidentifiable: 95 % CI'), terms[0]
    assert terms[0].value == 0.0
    assert all(isinstance(term, Term) and not math.isnan(term.ci95) for term in terms[:6])


def test_a_thrust_path_of_unit_gain_and_no_lag_passes_the_wrench() -> None:
    """The prior path (gain 1, no lag, no delay) is the recorded wrench."""
    t, tau, _, _ = _hull_data(n=200)
    path = ThrustPath(Term('thrust_gain', 1.0, 0.0, 'well determined', '-'),
                      Term('thrust_time_constant_s', 0.0, 0.0, 'well determined', 's'),
                      0.0, np.ones(6))
    assert np.array_equal(path.wrench(t, tau), tau)


def test_a_gain_the_rows_disagree_on_is_named_unidentifiable_and_kept_at_1() -> None:
    """All axes 0.53 +- 0.04, the translations alone 0.17 +- 0.03: a force the model lacks.

    (issue 50's acceptance recordings; the truth is 1.) Agreeing estimates pass unchanged.
    """
    lag = Term('thrust_time_constant_s', 0.0, 0.03, 'unidentifiable: ...', 's')
    path = ThrustPath(Term('thrust_gain', 0.53, 0.044, 'well determined', '-'), lag, -0.005,
                      np.ones(6))
    checked = checked_gain(path, Term('thrust_gain', 0.17, 0.025, 'well determined', '-'))
    assert checked.gain.value == 1.0
    assert checked.gain.status.startswith('unidentifiable: all axes give 0.53')
    assert checked.delay_s == -0.005 and checked.time_constant is lag
    agreeing = checked_gain(path, Term('thrust_gain', 0.55, 0.03, 'well determined', '-'))
    assert agreeing is path
