"""Tests of uvms_hardware.t200_curve: the T200 table of the robot folder and its inverse."""

from __future__ import annotations

import numpy as np
import pytest
from uvms_hardware.t200_curve import KGF_N, T200Curve, clamp_pwm, robot_curve

CURVE = robot_curve('bluerov2_alpha5')


def test_curve_passes_through_the_published_16v_points() -> None:
    """Blue Robotics' 16 V points are reproduced exactly (the table is the data)."""
    for pwm_us, kgf in ((1100, -4.069), (1300, -1.438), (1700, 1.823), (1900, 5.245)):
        assert CURVE.thrust_from_pwm(pwm_us, 16.0) == pytest.approx(kgf * KGF_N, abs=1e-9)


def test_thrust_is_monotone_in_pwm_and_zero_in_the_dead_band() -> None:
    """Thrust never decreases with the pulse; 1472-1528 µs gives none."""
    pwm = np.arange(1100.0, 1900.5, 0.5)
    thrust = np.array([CURVE.thrust_from_pwm(p, 16.0) for p in pwm])
    assert np.all(np.diff(thrust) >= 0.0)
    dead = (pwm >= 1472.0) & (pwm <= 1528.0)
    np.testing.assert_array_equal(thrust[dead], 0.0)
    assert np.all(thrust[pwm > 1528.0] > 0.0) and np.all(thrust[pwm < 1472.0] < 0.0)


def test_extremes_are_the_published_ones() -> None:
    """About +51.4 N at 1900 µs and -39.9 N at 1100 µs at 16 V."""
    assert CURVE.thrust_from_pwm(1900.0, 16.0) == pytest.approx(51.4, abs=0.1)
    assert CURVE.thrust_from_pwm(1100.0, 16.0) == pytest.approx(-39.9, abs=0.1)


@pytest.mark.parametrize('voltage_v', [12.0, 16.0, 18.5, None])
def test_zero_thrust_is_neutral(voltage_v: float | None) -> None:
    """0 N (and NaN) gives 1500 µs at any voltage."""
    assert CURVE.pwm_from_thrust(0.0, voltage_v) == 1500.0
    assert CURVE.pwm_from_thrust(float('nan'), voltage_v) == 1500.0


@pytest.mark.parametrize('voltage_v', [10.0, 14.8, 16.0, 20.0])
@pytest.mark.parametrize('fraction', [-0.95, -0.2, -0.001, 0.001, 0.03, 0.5, 0.99])
def test_round_trip_thrust_pwm_thrust(fraction: float, voltage_v: float) -> None:
    """thrust_from_pwm(pwm_from_thrust(F)) = F inside the thruster's range at that voltage."""
    extreme_n = CURVE.thrust_from_pwm(1900.0 if fraction > 0 else 1100.0, voltage_v)
    thrust_n = abs(fraction) * extreme_n
    pwm_us = CURVE.pwm_from_thrust(thrust_n, voltage_v)
    assert CURVE.thrust_from_pwm(pwm_us, voltage_v) == pytest.approx(thrust_n, rel=1e-4, abs=1e-4)


def test_pwm_is_monotone_in_thrust_and_skips_the_dead_band() -> None:
    """More thrust, longer pulse; any non-zero thrust starts outside 1472-1528 µs."""
    thrust = np.linspace(-60.0, 60.0, 481)
    pwm = np.array([CURVE.pwm_from_thrust(f, 16.0) for f in thrust])
    assert np.all(np.diff(pwm) >= 0.0)
    assert CURVE.pwm_from_thrust(1e-6, 16.0) >= 1528.0
    assert CURVE.pwm_from_thrust(-1e-6, 16.0) <= 1472.0


@pytest.mark.parametrize(('thrust_n', 'pwm_us'), [(500.0, 1900.0), (-500.0, 1100.0)])
def test_beyond_the_extremes_clamps(thrust_n: float, pwm_us: float) -> None:
    """Thrust beyond the table clamps to 1100-1900 µs."""
    assert CURVE.pwm_from_thrust(thrust_n, 16.0) == pwm_us
    assert CURVE.thrust_from_pwm(pwm_us + np.sign(thrust_n) * 300.0, 16.0) == \
        CURVE.thrust_from_pwm(pwm_us, 16.0)
    assert clamp_pwm(2500.0) == 1900 and clamp_pwm(900.0) == 1100 and clamp_pwm(np.nan) == 1500


def test_lower_voltage_gives_less_thrust_for_the_same_pulse() -> None:
    """The (assumed) voltage scaling: less thrust at 12 V than at 16 V, clamped to 10-20 V."""
    assert CURVE.thrust_from_pwm(1800.0, 12.0) < CURVE.thrust_from_pwm(1800.0, 16.0)
    assert CURVE.thrust_from_pwm(1800.0, 5.0) == CURVE.thrust_from_pwm(1800.0, 10.0)


def test_a_table_that_decreases_is_refused() -> None:
    """A table whose thrust decreases somewhere cannot be inverted: ValueError."""
    with pytest.raises(ValueError, match='not decrease'):
        T200Curve((1100.0, 1500.0, 1900.0), (0.0, -1.0, 1.0))
