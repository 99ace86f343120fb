"""Case I (paper sec. 5.3.1, Figs. 8-9): stable contact and force tracking on two wall stiffnesses.

The whole graph runs the paper's half circle into a wall at x = 1.7771 m of K_e = 1e4 and
1e5 N/m and tracks 150 N along the wall; the metrics are those of ``uvms report``
(``uvms_analysis.metrics``), the force is the simulator's ground truth. F_d = 150 N comes
with each scenario's mission, checked in test/integration/test_graph_scenario_files.py.

Bounds are about 2-3x what the runs give (measured values in the comments; the runs are
deterministic): a loss of force tracking that large is what the tests must catch, and a
change of the numerics should not trip them.
"""

from __future__ import annotations

import pytest
from scenario_runs import ScenarioResult, first_force_peak

F_D_N = 150.0
CASE_I = ('case1_ke1e4', 'case1_ke1e5')
#: Largest peak - F_d (N): measured 3.26 N (1e4) and 1.20 N (1e5): 2.3x and 2.5x.
OVERSHOOT_BOUND_N = {'case1_ke1e4': 7.5, 'case1_ke1e5': 3.0}
#: Settling into F_d ± 5 % (s): measured 0.880 s (1e4) and 0.828 s (1e5): 1.7-1.8x (the
#: set-point ramp alone takes 1 s of it, so a tighter factor would leave no room at all).
SETTLING_BOUND_S = 1.5
#: RMS of F - F_d after settling (N): measured 1.061 N (1e4) and 1.007 N (1e5): 1.9-2.0x.
#: 2.5 N let a force gain K_fp cut to 0.3x pass (2.44 N on 1e4); a doubled error is a loss
#: of tracking this test must see.
RMS_BOUND_N = 2.0
#: The stiff wall's impact spike comes within this time of the touch (s): measured 24 ms.
SPIKE_WITHIN_S = 0.05


@pytest.fixture(params=CASE_I)
def case1(request: pytest.FixtureRequest) -> ScenarioResult:
    """Case I on either wall."""
    result: ScenarioResult = request.getfixturevalue(request.param)
    return result


def test_contact_force_overshoots_the_set_point_by_a_few_newtons_at_most(
    case1: ScenarioResult,
) -> None:
    """A stable contact: the peak normal force exceeds F_d by under 7.5 N (1e4), 3 N (1e5)."""
    assert case1.metrics.peak_force is not None
    overshoot = case1.metrics.peak_force - F_D_N
    assert overshoot < OVERSHOOT_BOUND_N[case1.name], f'peak - F_d = {overshoot:.2f} N'


def test_contact_force_settles_within_5_percent_in_under_1_5_s(case1: ScenarioResult) -> None:
    """From the first touch the force enters F_d ± 5 % within 1.5 s and stays until release."""
    assert case1.metrics.settling_time is not None
    assert case1.metrics.settling_time < SETTLING_BOUND_S


def test_force_tracking_rms_error_is_under_2_n(case1: ScenarioResult) -> None:
    """RMS of F - F_d after settling, up to the release of the wall, is below 2 N (1.3 %)."""
    assert case1.metrics.force_rms_error is not None
    assert case1.metrics.force_rms_error < RMS_BOUND_N


def test_stiffer_wall_shows_an_impact_spike_the_soft_wall_does_not(
    case1_ke1e4: ScenarioResult, case1_ke1e5: ScenarioResult
) -> None:
    """The transient of the touch: a spike on K_e = 1e5, a plain rise on 1e4.

    The first local maximum of the force after the touch is, on 1e5, a 33.3 N spike 24 ms
    after it (the force then falls back to 18 N before it builds up); on 1e4 it is the
    set-point overshoot, 153.3 N at 1.0 s. Its value is therefore *not* larger on the
    stiffer wall, and neither is the overshoot over F_d (0.8 % against 2.2 %): the paper's
    "slightly higher overshoot" is not reproduced (docs/results.md); what the stiffer wall
    shows is a distinct impact at the touch.
    """
    soft_delay, soft_peak = first_force_peak(case1_ke1e4)
    stiff_delay, stiff_peak = first_force_peak(case1_ke1e5)
    assert stiff_delay < SPIKE_WITHIN_S, f'1e5: first peak {stiff_peak:.1f} N at {stiff_delay} s'
    assert stiff_peak < 0.5 * F_D_N  # an impact, not the approach to the set-point
    assert soft_delay > 0.5, f'1e4: first peak {soft_peak:.1f} N at {soft_delay} s'
    assert soft_peak > 0.9 * F_D_N  # no spike before the force reaches the set-point
