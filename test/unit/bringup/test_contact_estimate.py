"""Scenario contact estimate: first contact and force ramp known before the run."""

from __future__ import annotations

from pathlib import Path

import pytest
from uvms_scenarios.scenario import (
    contact_estimate,
    load_scenario,
    parse_scenario,
    short_duration_warning,
)

SCENARIOS = Path(__file__).resolve().parents[3] / 'config' / 'scenarios'
#: First contact of the paper's scenarios as recorded (docs/results.md, uvms report).
RECORDED_FIRST_CONTACT_S = 8.050


@pytest.mark.parametrize('name', ['case1_ke1e4', 'case2_noise', 'case3_moving_wall'])
def test_paper_scenario_estimate_matches_the_recorded_first_contact(name: str) -> None:
    """X_d of the half circle reaches the wall at the recorded 8.05 s; F_d by 9.05 s."""
    estimate = contact_estimate(load_scenario(SCENARIOS / f'{name}.yaml'))
    assert estimate is not None
    assert estimate.first_contact_s == pytest.approx(RECORDED_FIRST_CONTACT_S, abs=0.01)
    assert estimate.force_reached_s == pytest.approx(RECORDED_FIRST_CONTACT_S + 1.0, abs=0.01)


def test_nine_seconds_of_case2_warn_and_twenty_do_not() -> None:
    """9 s ends during the force ramp (warned); the scenario's own 20 s does not."""
    scenario = load_scenario(SCENARIOS / 'case2_noise.yaml')
    warning = short_duration_warning(scenario, 9.0)
    assert warning is not None and '9.05 s' in warning
    assert short_duration_warning(scenario, 20.0) is None


@pytest.mark.parametrize('name', ['free_motion', 'idle_wall'])
def test_scenario_without_a_force_task_has_no_estimate(name: str) -> None:
    """No mission force (free motion, goals from outside): nothing to estimate or warn."""
    scenario = load_scenario(SCENARIOS / f'{name}.yaml')
    assert contact_estimate(scenario) is None
    assert short_duration_warning(scenario, 0.5) is None


def test_path_task_touches_where_its_waypoints_cross_the_wall(tmp_path: Path) -> None:
    """Waypoints x = 1.0 -> 2.0 m over 0-10 s from t = 3 s, wall at 1.5 m: contact at 8 s."""
    data = {
        'name': 'press', 'description': 'a straight press', 'duration_s': 20.0,
        'simulator': {'contact': {'wall_position_m': 1.5}},
        'mission': [{'path': [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
                     'time_from_start_s': [0.0, 10.0], 'normal': [1.0, 0.0, 0.0],
                     'force_n': 50.0, 'force_ramp_s': 2.0, 'start_time_s': 3.0}],
    }
    estimate = contact_estimate(parse_scenario(data, tmp_path / 'press.yaml'))
    assert estimate is not None
    assert estimate.first_contact_s == pytest.approx(8.0)
    assert estimate.force_reached_s == pytest.approx(10.0)
