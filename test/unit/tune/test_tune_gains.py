"""Searched gains to controller parameters and back, and the stability check before a run."""

from __future__ import annotations

import math

import pytest
from uvms_tune.driver import CONTROL_PERIOD_S
from uvms_tune.gains import as_candidate, controller_values, hand_tuned, stability
from uvms_tune.tune_file import GainRange

OMEGA = GainRange('impedance.natural_frequency_rad_s', 1.0, 30.0, True)
ZETA = GainRange('impedance.damping_ratio', 0.2, 3.0)
KP = GainRange('hybrid.force_kp', 0.001, 1.0, True)


def test_natural_frequency_and_damping_ratio_give_stiffness_and_damping() -> None:
    """K = P ω_n² and B_d = 2 ζ P ω_n per axis, with the base's P."""
    base = hand_tuned('bluerov2_alpha5')
    values = controller_values({OMEGA.name: 10.0, ZETA.name: 0.7}, base)
    p = base['impedance.inertia_kg'][0]
    assert values['impedance.stiffness_n_m'] == pytest.approx([p * 100.0] * 3)
    assert values['impedance.damping_n_s_m'] == pytest.approx([2 * 0.7 * p * 10.0] * 3)


def test_a_parameter_set_round_trips_through_its_candidate() -> None:
    """as_candidate then controller_values gives back the hand-tuned K and B_d."""
    base = hand_tuned('paper_uvms')
    values = controller_values(as_candidate(base, (OMEGA, ZETA, KP)), base)
    assert values['impedance.stiffness_n_m'] == pytest.approx(base['impedance.stiffness_n_m'])
    assert values['impedance.damping_n_s_m'] == pytest.approx(base['impedance.damping_n_s_m'])
    assert values['hybrid.force_kp'] == base['hybrid.force_kp']


def test_hand_tuned_gains_pass_the_stability_check() -> None:
    """The robot's own gains are stable on the stiffest wall it declares."""
    check = stability(hand_tuned('bluerov2_alpha5'), CONTROL_PERIOD_S, 1.0e5)
    assert check.stable and check.margin > 0.0


def test_a_force_gain_far_too_high_is_unstable() -> None:
    """K_fp = 10 on a 1e5 N/m wall: ρ > 1 at 500 Hz, a negative margin naming the loop."""
    base = hand_tuned('bluerov2_alpha5')
    check = stability({**base, 'hybrid.force_kp': 10.0}, CONTROL_PERIOD_S, 1.0e5)
    assert not check.stable and check.margin < 0.0 and 'K_e' in check.loop
    assert math.isfinite(check.margin)
