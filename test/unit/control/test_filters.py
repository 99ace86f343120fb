"""Tests of the filtered derivative."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uvms_control.core.law.filters import DirtyDerivative


def test_dirty_derivative_of_a_ramp_converges_to_its_slope() -> None:
    """d/dt of 30 t is 30 once the filter has settled (a few time constants)."""
    f = DirtyDerivative(cutoff_hz=20.0)
    dt = 1e-3
    for k in range(500):
        y = f.update(30.0 * k * dt, dt)
    assert y == pytest.approx(30.0, rel=1e-9)


@pytest.mark.parametrize('frequency_hz', [2.0, 20.0, 200.0])
def test_dirty_derivative_gain_follows_the_first_order_roll_off(frequency_hz: float) -> None:
    """For a sine, the output amplitude is ω / sqrt(1 + (ω τ)²): low-pass at the cut-off."""
    cutoff = 20.0
    f = DirtyDerivative(cutoff_hz=cutoff)
    dt = 1e-5
    omega = 2.0 * math.pi * frequency_hz
    t = np.arange(0.0, 10.0 / frequency_hz + 0.5, dt)
    out = np.array([f.update(math.sin(omega * tk), dt) for tk in t])
    settled = out[t > 0.5]
    expected = omega / math.sqrt(1.0 + (omega / (2.0 * math.pi * cutoff)) ** 2)
    assert float(np.max(np.abs(settled))) == pytest.approx(expected, rel=0.02)


def test_dirty_derivative_attenuates_white_noise() -> None:
    """Sensor-like noise (0.2 N at 1 kHz) gives a far smaller derivative than a raw difference."""
    rng = np.random.default_rng(3)
    noise = rng.normal(0.0, 0.2, 5000)
    dt = 1e-3
    f = DirtyDerivative(cutoff_hz=20.0)
    filtered = np.array([f.update(float(x), dt) for x in noise])
    raw = np.diff(noise) / dt
    assert np.std(filtered[100:]) < 0.2 * np.std(raw)


def test_dirty_derivative_first_sample_and_zero_step_give_zero_rate() -> None:
    """The first sample initialises the filter; a repeated stamp (dt = 0) changes nothing."""
    f = DirtyDerivative(cutoff_hz=20.0)
    assert f.update(5.0, 0.0) == 0.0
    assert f.update(9.0, 0.0) == 0.0
