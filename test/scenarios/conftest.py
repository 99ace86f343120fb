"""Session fixtures of the scenario tests: one recorded run per scenario (see scenario_runs)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from scenario_runs import ScenarioResult, ScenarioRuns


def _wanted_scenarios(session: pytest.Session) -> list[str]:
    """Scenario fixtures the selected tests use, in the order the tests will ask for them."""
    names: dict[str, None] = {}
    for item in session.items:
        params = getattr(getattr(item, 'callspec', None), 'params', {})
        used = [*getattr(item, 'fixturenames', ()), *params.values()]
        names.update((name, None) for name in used
                     if isinstance(name, str) and name in SCENARIO_FIXTURES)
    return list(names)


@pytest.fixture(scope='session')
def scenario_runs(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[ScenarioRuns]:
    """Every scenario run of the session, recorded into a temporary directory."""
    runs = ScenarioRuns(tmp_path_factory.mktemp('scenarios'), _wanted_scenarios(request.session))
    yield runs
    runs.close()


@pytest.fixture(scope='session')
def free_motion(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """The half circle with no wall, 20 s."""
    return scenario_runs.get('free_motion')


@pytest.fixture(scope='session')
def case1_ke1e4(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """Case I, wall K_e = 1e4 N/m, 20 s."""
    return scenario_runs.get('case1_ke1e4')


@pytest.fixture(scope='session')
def case1_ke1e5(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """Case I, wall K_e = 1e5 N/m, 20 s."""
    return scenario_runs.get('case1_ke1e5')


@pytest.fixture(scope='session')
def case2_noise(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """Case II, K_e = 1e4 N/m with wrist sensor noise (0.1 % of range), 20 s."""
    return scenario_runs.get('case2_noise')


@pytest.fixture(scope='session')
def case3_moving_wall(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """Case III, the wall recedes at 0.05 m/s once the force reaches 150 N, 20 s."""
    return scenario_runs.get('case3_moving_wall')


@pytest.fixture(scope='session')
def case4_model_error(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """Case IV, M_hat = 0.9 M_tilde, 20 s."""
    return scenario_runs.get('case4_model_error')


@pytest.fixture(scope='session')
def impedance_only(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """Baseline: impedance law alone (W = 1), K_e = 1e4 N/m, 20 s."""
    return scenario_runs.get('impedance_only')


@pytest.fixture(scope='session')
def hybrid_only(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """Baseline: hybrid law alone (W = 0), K_e = 1e4 N/m, the first 5 s (see SHORTENED_S)."""
    return scenario_runs.get('hybrid_only')


@pytest.fixture(scope='session')
def bluerov2_alpha5_thruster_fault(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """bluerov2_alpha5_contact with thruster T1 off from 11 s (issue 32)."""
    return scenario_runs.get('bluerov2_alpha5_thruster_fault')


@pytest.fixture(scope='session')
def case1_thruster_fault(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """case1_ke1e4 with thruster 0 at efficiency 0.3 from 11 s (issue 32)."""
    return scenario_runs.get('case1_thruster_fault')


#: The scenario fixtures above: a selected test that uses one starts its run early.
@pytest.fixture(scope='session')
def bluerov2_alpha5_contact(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """The BlueROV2 Heavy + Alpha 5 contact scenario (Case I scaled to the arm)."""
    return scenario_runs.get('bluerov2_alpha5_contact')


@pytest.fixture(scope='session')
def bluerov2_alpha5_free_motion(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """The BlueROV2 Heavy + Alpha 5 free-motion scenario."""
    return scenario_runs.get('bluerov2_alpha5_free_motion')


@pytest.fixture(scope='session')
def case1_current(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """Case I in an ocean current of 0.2 m/s along the wall's plane, the first 14 s."""
    return scenario_runs.get('case1_current')


@pytest.fixture(scope='session')
def bluerov2_alpha5_current(scenario_runs: ScenarioRuns) -> ScenarioResult:
    """The BlueROV2 + Alpha 5 contact task in 0.2 m/s along the wall's plane, first 14 s."""
    return scenario_runs.get('bluerov2_alpha5_current')


SCENARIO_FIXTURES = frozenset({
    'free_motion', 'case1_ke1e4', 'case1_ke1e5', 'case2_noise', 'case3_moving_wall',
    'case4_model_error', 'impedance_only', 'hybrid_only', 'bluerov2_alpha5_contact',
    'bluerov2_alpha5_free_motion', 'case1_current', 'bluerov2_alpha5_current',
    'bluerov2_alpha5_thruster_fault', 'case1_thruster_fault', 'idle_wall',
})
