"""Case IV (paper sec. 5.2.4, Fig. 15): force tracking with M_hat = 0.9 M_tilde."""

from __future__ import annotations

from scenario_runs import ScenarioResult

F_D_N = 150.0


def test_force_tracking_rms_error_with_10_percent_inertia_error_is_under_10_percent(
    case4_model_error: ScenarioResult,
) -> None:
    """RMS of F - F_d after settling, up to the release, is below 0.1 F_d with M_hat = 0.9 M."""
    assert case4_model_error.metrics.force_rms_error is not None
    assert case4_model_error.metrics.force_rms_error < 0.1 * F_D_N


def test_contact_force_with_inertia_error_settles_within_5_percent_in_under_2_s(
    case4_model_error: ScenarioResult,
) -> None:
    """The model error does not keep the force out of the F_d ± 5 % band after 2 s."""
    assert case4_model_error.metrics.settling_time is not None
    assert case4_model_error.metrics.settling_time < 2.0


def test_contact_force_with_inertia_error_stays_below_1_2_times_the_set_point(
    case4_model_error: ScenarioResult,
) -> None:
    """Robustness: the peak normal force with M_hat = 0.9 M stays below 1.2 F_d."""
    assert case4_model_error.metrics.peak_force is not None
    assert case4_model_error.metrics.peak_force < 1.2 * F_D_N
