"""The ocean current's Gauss-Markov process (uvms_model.ocean_current): statistics, seed, range."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uvms_model.ocean_current import (
    CurrentParameters,
    OceanCurrent,
    current_velocity_ned,
)

from uvms_model import ParameterError

MEAN, SIGMA, T = 1.0, 0.1, 1.0


def _speeds(h: float, duration_s: float, seed: int = 3) -> np.ndarray:
    """The speed every step h over duration_s, from a fixed seed (mean far from the clips)."""
    current = OceanCurrent(CurrentParameters(mean_speed_m_s=MEAN, sigma_m_s=SIGMA,
                                             time_constant_s=T, max_speed_m_s=10.0), seed)
    out = np.empty(round(duration_s / h))
    for k in range(out.size):
        current.step(h)
        out[k] = current.speed_m_s
    return out


@pytest.mark.parametrize('h', [0.02, 0.01])
def test_speed_has_the_closed_form_mean_variance_and_autocorrelation(h: float) -> None:
    """Over 2000 T: mean V_bar, variance sigma^2, lag-tau autocorrelation e^{-tau/T}, any step.

    The standard error of a sample mean of an OU process over a span S is sigma sqrt(2 T / S)
    (2.2 % of sigma here); the bounds are four of them, the variance's and correlations' a
    few per cent. Run at h and at h / 2 (the exact discretization keeps them).
    """
    speeds = _speeds(h, 2000.0 * T)
    standard_error = SIGMA * math.sqrt(2.0 * T / (2000.0 * T))
    assert abs(speeds.mean() - MEAN) < 4.0 * standard_error
    assert speeds.var() == pytest.approx(SIGMA**2, rel=0.1)
    centred = speeds - speeds.mean()
    for tau in (0.2, 0.5, 1.0, 2.0):
        lag = round(tau / h)
        correlation = float(centred[:-lag] @ centred[lag:]) / float(centred @ centred)
        assert correlation == pytest.approx(math.exp(-tau / T), abs=0.05), tau


def test_statistics_do_not_change_when_the_step_halves() -> None:
    """Variance and lag-T autocorrelation at h and h / 2 agree (uuv_simulator's do not)."""
    coarse, fine = _speeds(0.02, 1000.0), _speeds(0.01, 1000.0)
    assert coarse.var() == pytest.approx(fine.var(), rel=0.15)
    corr = []
    for speeds, h in ((coarse, 0.02), (fine, 0.01)):
        c, lag = speeds - speeds.mean(), round(T / h)
        corr.append(float(c[:-lag] @ c[lag:]) / float(c @ c))
    assert corr[0] == pytest.approx(corr[1], abs=0.06)


def test_same_seed_same_current_and_another_seed_another() -> None:
    """The scenario's seed fixes the sequence."""
    np.testing.assert_array_equal(_speeds(0.01, 5.0, seed=7), _speeds(0.01, 5.0, seed=7))
    assert not np.array_equal(_speeds(0.01, 5.0, seed=7), _speeds(0.01, 5.0, seed=8))


def test_speed_stays_within_zero_and_its_maximum() -> None:
    """A noisy current near its bounds is clipped to [0, V_max]."""
    current = OceanCurrent(CurrentParameters(mean_speed_m_s=0.05, sigma_m_s=0.5,
                                             time_constant_s=0.1, max_speed_m_s=0.3), 1)
    speeds = []
    for _ in range(2000):
        current.step(0.01)
        speeds.append(current.speed_m_s)
    assert min(speeds) == 0.0 and max(speeds) == 0.3


def test_still_water_by_default_and_constant_without_noise() -> None:
    """Default off (zero velocity, no draws); sigma 0: the current is its mean, constant."""
    still = OceanCurrent()
    still.step(0.01)
    assert not still.enabled and still.velocity_ned.tolist() == [0.0, 0.0, 0.0]
    steady = OceanCurrent(CurrentParameters(mean_speed_m_s=0.2, direction_rad=0.5 * math.pi))
    for _ in range(100):
        steady.step(0.01)
    np.testing.assert_allclose(steady.velocity_ned, [0.0, 0.2, 0.0], atol=1e-15)


def test_direction_is_from_north_toward_east_and_vertical_angle_down() -> None:
    """Direction 0 flows north (+x), pi/2 east (+y); alpha = pi/2 flows down (+z of NED)."""
    np.testing.assert_allclose(current_velocity_ned(1.0, 0.0, 0.0), [1.0, 0.0, 0.0])
    np.testing.assert_allclose(current_velocity_ned(1.0, math.pi / 2, 0.0), [0.0, 1.0, 0.0],
                               atol=1e-15)
    np.testing.assert_allclose(current_velocity_ned(1.0, 0.3, math.pi / 2), [0.0, 0.0, 1.0],
                               atol=1e-15)


def test_reconfiguring_restarts_at_the_new_mean() -> None:
    """A new mean speed set at run time is the current at once."""
    current = OceanCurrent(CurrentParameters(mean_speed_m_s=0.1, sigma_m_s=0.05), 2)
    current.step(0.01)
    current.configure(CurrentParameters(mean_speed_m_s=0.4, sigma_m_s=0.05))
    assert current.speed_m_s == 0.4


@pytest.mark.parametrize('field, value', [('mean_speed_m_s', -0.1), ('time_constant_s', 0.0),
                                          ('sigma_m_s', math.nan), ('vertical_angle_rad', 2.0)])
def test_out_of_range_parameters_are_refused_by_name(field: str, value: float) -> None:
    """ParameterError names ocean.current.<field> and its range."""
    with pytest.raises(ParameterError, match=f'ocean.current.{field}'):
        CurrentParameters(**{field: value})
