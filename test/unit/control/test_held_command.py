"""The held-slot prediction of the contact force (core/law/held_command.py, eq. 29 and 35).

What a user of the Alpha 5 at its device rates relies on: a clean force is predicted exactly
(a quadratic, and a ramp through a contact's onset), and a noisy one never feeds more noise
into eq. 29/35 than the measured force plus half the tolerance, whatever the noise level (the
quadratic alone: about 33 times the noise at the Alpha 5's h = 8.5 ms).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from uvms_control.core.law.held_command import (
    NOISE_TOLERANCE_N,
    HeldCommandForce,
    prediction_weight,
    quadratic_extrapolation,
    quadratic_increment_noise_gain,
)

#: The wrist sensor's sample period (s) and the Alpha 5's horizon (s): 2 ms + half a 77 Hz slot.
DT = 0.002
H = 0.002 + 0.5 / 77.0


def run(force: HeldCommandForce, signal: np.ndarray) -> np.ndarray:
    """The predictions for samples ``signal`` (k x 3) taken every DT."""
    return np.array([force.update(k * DT, tuple(row)) for k, row in enumerate(signal.tolist())])


def test_noise_gain_of_the_quadratic_is_about_33_at_the_alpha5_horizon() -> None:
    """The figure that makes the quadratic alone unusable with a noisy sensor."""
    rng = np.random.default_rng(3)
    samples = rng.standard_normal((200_000, 3))
    increments = (samples[2:] - samples[1:-1]) * (H + H * (DT + H) / (2 * DT)) / DT \
        - (samples[1:-1] - samples[:-2]) * (H * (DT + H) / (2 * DT)) / DT
    gain = quadratic_increment_noise_gain((0.0, DT, 2 * DT), H)
    assert gain == pytest.approx(32.6, abs=0.1)
    assert np.std(increments[:, 0]) == pytest.approx(gain, rel=0.01)


def test_a_quadratic_is_predicted_exactly() -> None:
    """A clean force: the third differences are 0, the whole increment is used."""
    t = DT * np.arange(40)
    signal = np.stack([3e3 * t * t + 5.0 * t + 1.0, -2e3 * t * t, np.full_like(t, 4.0)], axis=1)
    predicted = run(HeldCommandForce(H), signal)
    t_ahead = t + H
    assert predicted[3:, 0] == pytest.approx(3e3 * t_ahead[3:] ** 2 + 5.0 * t_ahead[3:] + 1.0)
    assert predicted[3:, 1] == pytest.approx(-2e3 * t_ahead[3:] ** 2)
    assert predicted[:3] == pytest.approx(signal[:3])  # no noise estimate yet: measured force



def test_a_sensor_on_its_own_clock_is_predicted_from_its_stamps_to_the_step() -> None:
    """Steps that get no new sample, one or two (as on the twin stand): exact at step + h.

    The Net F/T streams on its own clock, so a 500 Hz control step finds 0, 1 or 2 new
    samples, 1.4-11 ms old (measured on the twin stand). Each step passes the newest sample
    with its stamp and the step's time; the prediction is for h after the step. Taken at the
    step's time instead (as before), a repeated sample reads as a flat force and a skipped
    one as a jump: the prediction is then wrong by newtons (asserted too).
    """
    def f(t: float) -> float:
        return 3e3 * t * t + 5.0 * t + 1.0

    rng = np.random.default_rng(5)
    stamped, at_step = HeldCommandForce(H), HeldCommandForce(H)
    errors_stamped, errors_at_step = [], []
    for k in range(8, 400):
        now = k * DT + 0.0013
        newest = (k - int(rng.choice([1, 2, 3], p=[0.3, 0.45, 0.25]))) * DT  # 0-2 new
        value = (f(newest), 0.0, 0.0)
        errors_stamped.append(stamped.update(newest, value, now)[0] - f(now + H))
        errors_at_step.append(at_step.update(now, value)[0] - f(now + H))
    assert np.abs(errors_stamped[10:]).max() < 1e-6
    assert np.abs(errors_at_step[10:]).max() > 1.0


def test_a_contact_onset_is_not_taken_for_noise() -> None:
    """F = K max(x - x_w, 0) at constant speed: once past the kink, the ramp is exact.

    The kink makes three third differences large; their median over the window stays 0.
    """
    t = DT * np.arange(60)
    ramp = 1e4 * np.maximum(0.01 * (t - 0.05), 0.0)
    signal = np.stack([ramp, np.zeros_like(t), np.zeros_like(t)], axis=1)
    force = HeldCommandForce(H)
    predicted = run(force, signal)
    after = t > 0.05 + 3 * DT
    assert predicted[after, 0] == pytest.approx(1e4 * 0.01 * (t[after] + H - 0.05))
    assert force.noise_sd == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


@pytest.mark.parametrize('sd_n', [0.001, 0.01, 0.05, 0.29, 0.58, 5.0])
def test_noise_entering_the_cancellation_is_bounded(sd_n: float) -> None:
    """A 20 N force with white noise of any level: at most the sample's noise plus e / 2.

    With the estimate of sigma from the samples, g G sigma peaks at e / 2 (G sigma = e); the
    quadratic alone would add 33 sigma (19 N for the Alpha 5's 0.58 N).
    """
    rng = np.random.default_rng(11)
    signal = 20.0 + sd_n * rng.standard_normal((3000, 3))
    force = HeldCommandForce(H)
    cancelled = run(force, signal)[100:]
    assert np.std(cancelled, axis=0).max() <= sd_n + 0.5 * NOISE_TOLERANCE_N
    assert force.noise_sd == pytest.approx((sd_n, sd_n, sd_n), rel=0.25)


def test_free_water_noise_is_averaged() -> None:
    """No contact, the robot's 0.1 % noise: the mean over 2 h, less noise than one sample.

    The quadratic alone: 33 times the noise; eq. 29's measured force: once; here at most
    0.45 times (the mean of the 8 or 9 samples of 17 ms, 1 / sqrt(8) = 0.35, and the odd
    sample above 3 sigma taken as measured).
    """
    rng = np.random.default_rng(2)
    sd = np.array([0.58, 0.29, 0.29])
    signal = sd * rng.standard_normal((5000, 3))
    cancelled = run(HeldCommandForce(H), signal)[100:]
    assert (np.std(cancelled, axis=0) <= 0.45 * sd).all()


def test_the_robots_noise_leaves_the_measured_force() -> None:
    """At the wrist sensor's 0.1 % (0.58 N) the prediction is the measured force, as eq. 29."""
    assert prediction_weight(0.58, quadratic_increment_noise_gain((0.0, DT, 2 * DT), H),
                             NOISE_TOLERANCE_N) < 1e-3
    assert prediction_weight(0.0, 32.7, NOISE_TOLERANCE_N) == 1.0


def test_the_noise_estimate_restarts_with_reset_and_survives_a_gap() -> None:
    """reset() forgets the noise; a gap in the samples keeps it (the sensor is the same)."""
    rng = np.random.default_rng(5)
    force = HeldCommandForce(H)
    run(force, 0.5 * rng.standard_normal((100, 3)))
    noisy = force.noise_sd
    assert min(noisy) > 0.3
    assert force.update(10.0, (1.0, 1.0, 1.0)) == (1.0, 1.0, 1.0)  # a gap: measured force
    assert force.noise_sd == noisy
    force.reset()
    assert force.noise_sd == (0.0, 0.0, 0.0)


def test_invalid_settings_are_refused() -> None:
    """A tolerance or window that cannot weigh anything is a parameter error."""
    with pytest.raises(ValueError, match='tolerance'):
        HeldCommandForce(H, noise_tolerance_n=0.0)
    with pytest.raises(ValueError, match='window'):
        HeldCommandForce(H, noise_window=0)
    with pytest.raises(ValueError, match='horizon'):
        HeldCommandForce(-1.0)
    assert math.isfinite(quadratic_increment_noise_gain((0.0, DT, 2 * DT), 0.0))
    assert quadratic_extrapolation([(0.0, (1.0, 2.0, 3.0))], H) == (1.0, 2.0, 3.0)
