"""The whole graph with the controller on the estimate (state_source: estimate), lockstep."""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from uvms_analysis.estimate_errors import estimate_errors
from uvms_bringup.declared import check_scenario_overrides
from uvms_bringup.launch_helpers import ESTIMATOR, graph_nodes, uses_estimator
from uvms_control.core.parameters import topic_for
from uvms_run.graph import RunResult, build_graph, run_graph
from uvms_scenarios.scenario import load_scenario

from uvms_analysis import report

SCENARIOS = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'
DURATION_S = 1.0


def _series(path: Path) -> dict[str, dict[int, object]]:
    """Messages per topic keyed by header stamp (ns)."""
    out: dict[str, dict[int, object]] = defaultdict(dict)
    with AnyReader([path]) as reader:
        wanted = [c for c in reader.connections if c.topic in (
            '/uvms/odometry', '/uvms/odometry/filtered', '/uvms/joint_states',
            '/uvms/command/actuators', '/uvms/controller/state', '/uvms/ee_pose', '/uvms/imu',
            '/uvms/dvl', '/uvms/depth')]
        for connection, _, raw in reader.messages(connections=wanted):
            msg = reader.deserialize(raw, connection.msgtype)
            stamp = msg.header.stamp
            out[connection.topic][stamp.sec * 1_000_000_000 + stamp.nanosec] = msg
    return out


@pytest.fixture(scope='module')
def estimated(tmp_path_factory: pytest.TempPathFactory) -> tuple[RunResult, Path]:
    """One lockstep run of case1_estimated (1 s) with recording."""
    path = tmp_path_factory.mktemp('estimated') / 'case1_estimated.mcap'
    scenario = load_scenario(SCENARIOS / 'case1_estimated.yaml').with_changes(
        duration_s=DURATION_S)
    return run_graph(build_graph(scenario, 'lockstep', output_path=path)), path


def test_estimated_scenarios_start_the_estimator() -> None:
    """A scenario with state_source: estimate runs the estimator; the paper's do not."""
    for name in ('case1_estimated', 'bluerov2_alpha5_contact_estimated',
                 'case1_estimated_current', 'bluerov2_alpha5_contact_estimated_current'):
        scenario = load_scenario(SCENARIOS / f'{name}.yaml')
        assert scenario.name == name
        assert uses_estimator(scenario), name
        assert ESTIMATOR in graph_nodes(record=True, estimator=uses_estimator(scenario))
        assert scenario.overrides['simulator']['navigation.enabled'] is True
        check_scenario_overrides(scenario)  # every key a declared parameter of its node


@pytest.mark.parametrize(('name', 'still_water'), [
    ('case1_estimated_current', 'case1_estimated'),
    ('bluerov2_alpha5_contact_estimated_current', 'bluerov2_alpha5_contact_estimated'),
])
def test_estimated_current_scenarios_add_only_the_current(name: str, still_water: str) -> None:
    """The estimated runs in a current are their still-water twins plus the 0.2 m/s current.

    The current is the one of case1_current / bluerov2_alpha5_current (east, along the wall).
    """
    scenario = load_scenario(SCENARIOS / f'{name}.yaml').overrides
    twin = load_scenario(SCENARIOS / f'{still_water}.yaml').overrides
    current = {key: value for key, value in scenario['simulator'].items()
               if key.startswith('ocean.current.')}
    assert current['ocean.current.mean_speed_m_s'] == 0.2
    assert current['ocean.current.direction_rad'] == pytest.approx(math.pi / 2)
    rest = {key: value for key, value in scenario['simulator'].items() if key not in current}
    assert rest == twin['simulator']
    assert {k: v for k, v in scenario.items() if k != 'simulator'} == {
        k: v for k, v in twin.items() if k != 'simulator'}
    assert not uses_estimator(load_scenario(SCENARIOS / 'case1_ke1e4.yaml'))
    assert ESTIMATOR not in graph_nodes(record=True)
    assert topic_for('odometry', 'estimate') == 'odometry/filtered'
    assert topic_for('odometry', 'truth') == 'odometry'
    assert topic_for('wrench', 'estimate') == 'wrench'


def test_every_state_gets_an_estimate_and_a_command(estimated: tuple[RunResult, Path]) -> None:
    """odometry/filtered for each state; each state answered; the sensor topics recorded."""
    result, path = estimated
    series = _series(path)
    states = sorted(series['/uvms/joint_states'])
    assert len(states) == round(DURATION_S * 500) + 1
    assert sorted(series['/uvms/odometry/filtered']) == states
    assert sorted(series['/uvms/command/actuators']) == states
    assert len(series['/uvms/imu']) == round(DURATION_S * 200) + 1
    assert series['/uvms/dvl'] and series['/uvms/depth']
    assert result.sim_time_s == pytest.approx(DURATION_S)
    assert not result.interrupted


def test_controller_acts_on_the_estimate(estimated: tuple[RunResult, Path]) -> None:
    """The controller's X is the end effector seen through the estimate, not the truth.

    On truth X equals ee_pose to rounding; on the estimate it differs by the estimation
    error, which stays small, and the end effector holds its start point.
    """
    _, path = estimated
    series = _series(path)
    state, ee = series['/uvms/controller/state'], series['/uvms/ee_pose']
    stamps = sorted(set(state) & set(ee))
    x = np.array([[state[t].position.x, state[t].position.y, state[t].position.z] for t in stamps])
    truth = np.array([[ee[t].pose.position.x, ee[t].pose.position.y, ee[t].pose.position.z]
                      for t in stamps])
    gap = np.linalg.norm(x - truth, axis=1)
    assert gap.max() > 1e-4
    assert gap.max() < 0.1
    assert np.linalg.norm(truth - truth[0], axis=1).max() < 0.05


def test_report_gives_the_estimate_errors(estimated: tuple[RunResult, Path],
                                          capsys: pytest.CaptureFixture[str]) -> None:
    """Uvms report adds the estimator's errors against the truth, stamp by stamp."""
    _, path = estimated
    errors = estimate_errors(path)
    assert errors is not None
    assert errors.samples == round(DURATION_S * 500) + 1
    assert 0.0 < errors.position_rms_m <= errors.position_max_m < 0.1
    assert 0.0 < errors.velocity_rms_m_s <= errors.velocity_max_m_s < 0.05
    assert errors.true_e_contact_max_m is None  # no contact in the first second
    assert report.main([str(path)]) == 0
    out = capsys.readouterr().out
    assert 'case1_estimated' in out and 'estimate (odometry/filtered) against the truth' in out


def test_same_seed_gives_byte_identical_payloads_on_the_estimate(tmp_path: Path) -> None:
    """Two lockstep runs of case1_estimated with one seed record the same bytes, estimate too."""
    def payloads(index: int) -> dict[str, list[bytes]]:
        path = tmp_path / f'{index}.mcap'
        scenario = load_scenario(SCENARIOS / 'case1_estimated.yaml').with_changes(
            duration_s=0.4)
        run_graph(build_graph(scenario, 'lockstep', output_path=path))
        out: dict[str, list[bytes]] = defaultdict(list)
        with path.open('rb') as stream:
            for _, channel, message in make_reader(stream).iter_messages(log_time_order=False):
                out[channel.topic].append(message.data)
        return out

    first, second = payloads(1), payloads(2)
    assert {'/uvms/imu', '/uvms/dvl', '/uvms/depth', '/uvms/odometry/filtered'} <= set(first)
    assert first == second
