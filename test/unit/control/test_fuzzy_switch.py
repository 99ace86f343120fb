"""Tests of the fuzzy switch (paper sec. 4.3, Figs. 4 and 5)."""

from __future__ import annotations

import numpy as np
import pytest
from uvms_control.core.errors import ControlParameterError
from uvms_control.core.fuzzy_sets import FuzzySwitchParameters, Trapezoid
from uvms_control.core.law.fuzzy_switch import FuzzySwitch

RATIOS = np.linspace(-0.2, 1.6, 361)
VELOCITIES = np.linspace(-0.3, 0.4, 281)


@pytest.fixture(scope='module')
def switch() -> FuzzySwitch:
    """The switch with the documented default membership functions."""
    return FuzzySwitch()


def brute_force_centroid(switch: FuzzySwitch, strengths: np.ndarray) -> float:
    """Centroid of the clipped, max-aggregated output sets on a very fine grid (an oracle)."""
    p = switch.params
    x = np.linspace(-0.5, 1.5, 400_001)
    mu = np.stack([p.weight_large(x), p.weight_medium(x), p.weight_small(x)], axis=-1)
    g = np.max(np.minimum(mu, strengths), axis=-1)
    return float(np.sum(g * x) / np.sum(g))


@pytest.mark.parametrize(
    ('ratio', 'velocity', 'expected'),
    [
        (0.0, 0.3, 1.0),  # FS and VF fire fully: WL's centre
        (0.5, 0.0, 0.5),  # FM fires fully: WM's centre
        (0.5, 0.3, 0.5),
        (1.0, 0.0, 0.0),  # FL and VS fire fully: WS's centre
        (1.2, -0.1, 0.0),
    ],
)
def test_weight_at_rule_cores_is_the_rule_output_centre(
    switch: FuzzySwitch, ratio: float, velocity: float, expected: float
) -> None:
    """A fully firing rule gives exactly its output set's centre (FS&VF->1, FM->0.5, FL&VS->0)."""
    assert switch.weight(ratio, velocity) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(('ratio', 'velocity'), [(0.0, 0.0), (0.05, 0.02), (1.0, 0.3)])
def test_weight_where_no_rule_fires_is_the_impedance_law(
    switch: FuzzySwitch, ratio: float, velocity: float
) -> None:
    """Small force while slow, or large force while still approaching fast: W = 1."""
    assert switch.rule_strengths(ratio, velocity).max() == 0.0
    assert switch.weight(ratio, velocity) == 1.0


@pytest.mark.parametrize(
    'strengths',
    [(0.3, 0.6, 0.2), (0.2, 0.5, 0.9), (1.0, 0.4, 0.0), (0.0, 0.7, 0.7), (0.1, 0.0, 0.8)],
)
def test_defuzzification_matches_fine_grid_centroid(
    switch: FuzzySwitch, strengths: tuple[float, float, float]
) -> None:
    """The exact piecewise-linear centroid equals a 400k-point numerical centroid."""
    h = np.array(strengths)
    m = min(h.sum(), 1.0)
    expected = m * brute_force_centroid(switch, h) + (1.0 - m) * switch.params.no_rule_weight
    assert float(switch.defuzzify(h)) == pytest.approx(expected, abs=1e-8)
    assert switch.defuzzify_scalar(strengths) == pytest.approx(expected, abs=1e-8)


def test_scalar_and_vectorised_defuzzification_agree(switch: FuzzySwitch) -> None:
    """The per-step float path and the vectorised surface path give the same weight."""
    rng = np.random.default_rng(7)
    h = rng.random((500, 3)) * (rng.random((500, 3)) > 0.3)
    vectorised = switch.defuzzify(h)
    scalar = np.array([switch.defuzzify_scalar(row.tolist()) for row in h])
    np.testing.assert_allclose(scalar, vectorised, atol=1e-12)


@pytest.mark.parametrize('axis', [0, 1])
def test_surface_is_continuous(switch: FuzzySwitch, axis: int) -> None:
    """Jumps between neighbouring samples shrink with the grid step: no discontinuity (Fig. 5)."""

    def largest_jump(refine: int) -> float:
        ratios = np.linspace(
            RATIOS[0], RATIOS[-1], (RATIOS.size - 1) * (refine if axis else 1) + 1
        )
        velocities = np.linspace(
            VELOCITIES[0], VELOCITIES[-1], (VELOCITIES.size - 1) * (1 if axis else refine) + 1
        )
        return float(np.max(np.abs(np.diff(switch.surface(ratios, velocities), axis=axis))))

    coarse, fine = largest_jump(1), largest_jump(10)
    assert coarse < 0.05
    assert fine < coarse / 5.0


def test_surface_stays_within_unit_interval(switch: FuzzySwitch) -> None:
    """The weight never leaves [0, 1] although WS and WL extend beyond it."""
    surface = switch.surface(RATIOS, VELOCITIES)
    assert surface.min() >= 0.0
    assert surface.max() <= 1.0


def test_surface_layout_is_velocity_rows_ratio_columns(switch: FuzzySwitch) -> None:
    """surface()[i, j] is W at velocity i and ratio j, as weight() computes it."""
    ratios = np.array([0.0, 0.3, 0.7, 1.1])
    velocities = np.array([-0.1, 0.0, 0.1, 0.2, 0.3])
    surface = switch.surface(ratios, velocities)
    assert surface.shape == (5, 4)
    for i, v in enumerate(velocities):
        for j, r in enumerate(ratios):
            assert surface[i, j] == pytest.approx(switch.weight(float(r), float(v)), abs=1e-12)


def test_weight_decreases_as_contact_force_grows_at_rest(switch: FuzzySwitch) -> None:
    """At rest on the wall, more force hands control from impedance (1) to hybrid (0)."""
    weights = switch.surface(np.linspace(0.0, 1.2, 121), np.array([0.0]))[0]
    assert np.all(np.diff(weights) <= 1e-12)
    assert weights[0] == 1.0
    assert weights[-1] == 0.0


def test_receding_end_effector_counts_as_slow(switch: FuzzySwitch) -> None:
    """v_e < 0 (moving away from the wall) is fully VS, so a large force keeps W = 0."""
    assert switch.params.velocity_slow.scalar(-0.5) == 1.0
    assert switch.weight(1.0, -0.5) == 0.0


def test_membership_shapes_follow_their_corners() -> None:
    """Shoulders, triangles and trapezoids have the documented values at and between corners."""
    left = Trapezoid.left_shoulder(0.1, 0.5)
    right = Trapezoid.right_shoulder(0.5, 0.9)
    triangle = Trapezoid.triangle(0.1, 0.5, 0.9)
    x = np.array([-1.0, 0.1, 0.3, 0.5, 0.7, 0.9, 2.0])
    np.testing.assert_allclose(left(x), [1.0, 1.0, 0.5, 0.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(right(x), [0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0])
    np.testing.assert_allclose(triangle(x), [0.0, 0.0, 0.5, 1.0, 0.5, 0.0, 0.0])
    for value in x:
        assert triangle.scalar(float(value)) == pytest.approx(float(triangle(value)))


def test_unordered_corners_are_rejected_naming_the_set() -> None:
    """A membership function with b < a is a parameter error that names the set."""
    with pytest.raises(ControlParameterError, match=r'fuzzy\.force_ratio_medium'):
        Trapezoid(0.5, 0.1, 0.6, 0.9, 'fuzzy.force_ratio_medium')


def test_no_rule_weight_outside_unit_interval_is_rejected() -> None:
    """The no-rule answer must be a weight in [0, 1]."""
    with pytest.raises(ControlParameterError, match=r'fuzzy\.no_rule_weight'):
        FuzzySwitchParameters(no_rule_weight=1.5)


def test_overlapping_output_sets_defuzzify_alike_in_both_paths() -> None:
    """With three mutually overlapping output sets the float and vectorised paths agree."""
    params = FuzzySwitchParameters(
        weight_small=Trapezoid(-0.6, -0.1, 0.1, 0.9, 'ws'),
        weight_medium=Trapezoid.triangle(-0.2, 0.5, 1.2, 'wm'),
        weight_large=Trapezoid(0.1, 0.9, 1.1, 1.6, 'wl'),
    )
    switch = FuzzySwitch(params)
    h = np.random.default_rng(11).random((300, 3))
    scalar = np.array([switch.defuzzify_scalar(row.tolist()) for row in h])
    np.testing.assert_allclose(scalar, switch.defuzzify(h), atol=1e-12)
