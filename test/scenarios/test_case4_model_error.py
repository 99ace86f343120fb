"""Case IV (paper sec. 5.2.4, Fig. 15): force tracking with M_hat = 0.9 M_tilde.

"A good degree of robustness" is judged against Case I on the same wall with the exact model,
and the overshoot in newtons as in test_case1_stiffness.py.
"""

from __future__ import annotations

from scenario_runs import ScenarioResult

F_D_N = 150.0
#: Case IV metrics at most this factor times Case I's (same wall, exact model): measured
#: RMS 1.094 / 1.061 N = 1.03, settling 0.882 / 0.880 s = 1.002.
TO_CASE_I = 1.5
#: Largest peak - F_d (N): measured 3.70 N (2x).
OVERSHOOT_BOUND_N = 7.5


def test_force_tracking_rms_error_with_10_percent_inertia_error_is_within_1_5_times_case_i(
    case4_model_error: ScenarioResult, case1_ke1e4: ScenarioResult
) -> None:
    """RMS of F - F_d after settling, up to the release: below 1.5x Case I's with M_hat = M."""
    wrong, exact = case4_model_error.metrics.force_rms_error, case1_ke1e4.metrics.force_rms_error
    assert wrong is not None and exact is not None
    assert wrong < TO_CASE_I * exact, f'{wrong:.3f} N against {exact:.3f} N'


def test_contact_force_with_inertia_error_settles_within_1_5_times_case_i(
    case4_model_error: ScenarioResult, case1_ke1e4: ScenarioResult
) -> None:
    """The model error does not keep the force out of the F_d ± 5 % band longer than 1.5x."""
    wrong, exact = case4_model_error.metrics.settling_time, case1_ke1e4.metrics.settling_time
    assert wrong is not None and exact is not None
    assert wrong < TO_CASE_I * exact, f'{wrong:.3f} s against {exact:.3f} s'


def test_contact_force_with_inertia_error_overshoots_by_under_7_5_n(
    case4_model_error: ScenarioResult,
) -> None:
    """Robustness: the peak normal force with M_hat = 0.9 M exceeds F_d by under 7.5 N."""
    assert case4_model_error.metrics.peak_force is not None
    overshoot = case4_model_error.metrics.peak_force - F_D_N
    assert overshoot < OVERSHOOT_BOUND_N, f'peak - F_d = {overshoot:.2f} N'
