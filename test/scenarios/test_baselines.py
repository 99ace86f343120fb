"""The two laws the unified controller combines, each alone on the Case I wall (paper sec. 2).

Hybrid position/force control alone switches into force control with a large force surge;
impedance control alone touches softly but cannot produce a force it is not told the
environment for (the wall's position and stiffness are unknown to it).
"""

from __future__ import annotations

from scenario_runs import ScenarioResult

F_D_N = 150.0


def test_hybrid_control_alone_hits_the_wall_at_least_twice_as_hard(
    hybrid_only: ScenarioResult, case1_ke1e4: ScenarioResult
) -> None:
    """Largest force within 0.5 s of first touch: hybrid alone > 2 x the unified controller's."""
    hybrid, unified = hybrid_only.metrics, case1_ke1e4.metrics
    assert hybrid.first_contact_time is not None
    assert hybrid_only.run.contact is not None
    assert hybrid_only.run.contact.t[-1] >= hybrid.first_contact_time + 0.5
    assert hybrid.impact_peak_force is not None and unified.impact_peak_force is not None
    assert hybrid.impact_peak_force > 2.0 * unified.impact_peak_force


def test_hybrid_control_alone_overshoots_the_set_point_at_impact(
    hybrid_only: ScenarioResult,
) -> None:
    """The force surge at the first touch of the hybrid law exceeds F_d itself."""
    assert hybrid_only.metrics.impact_peak_force is not None
    assert hybrid_only.metrics.impact_peak_force > F_D_N


def test_impedance_control_alone_stays_far_below_150_n_on_the_unknown_wall(
    impedance_only: ScenarioResult,
) -> None:
    """Impedance alone: the contact force never reaches half of F_d, a steady shortfall."""
    assert impedance_only.metrics.contact_count >= 1
    assert impedance_only.metrics.peak_force is not None
    assert impedance_only.metrics.peak_force < 0.5 * F_D_N

