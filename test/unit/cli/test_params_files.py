"""``uvms run/launch --params-file``: ROS 2 parameter files over a scenario, checked by name."""

from __future__ import annotations

from pathlib import Path

import pytest
from rclpy.parameter import Parameter
from uvms_bringup.launch_helpers import CONTROLLER, SIMULATOR, THRUSTER_ALLOCATOR
from uvms_scenarios.scenario import Scenario, ScenarioError
from uvms_sweep.params_files import apply_params_files, node_pattern

SPECS = (SIMULATOR, CONTROLLER, THRUSTER_ALLOCATOR)
DECLARED = {
    'simulator': {'sensor.seed': Parameter.Type.INTEGER, 'use_sim_time': Parameter.Type.BOOL},
    'controller': {'hybrid.force_kp': Parameter.Type.DOUBLE,
                   'impedance.stiffness_n_m': Parameter.Type.DOUBLE_ARRAY,
                   'use_sim_time': Parameter.Type.BOOL},
    'thruster_allocator': {'rate_hz': Parameter.Type.DOUBLE,
                           'use_sim_time': Parameter.Type.BOOL},
}


def scenario(**overrides: dict[str, object]) -> Scenario:
    """A scenario with the given overrides per node."""
    return Scenario(path=Path('s.yaml'), name='s', description='', duration_s=1.0,
                    overrides=overrides)  # type: ignore[arg-type]


def write(path: Path, text: str) -> str:
    """Write a parameter file; return its path as the command line gives it."""
    path.write_text(text, encoding='utf-8')
    return str(path)


@pytest.mark.parametrize(('key', 'matches'), [
    ('/**', True), ('/**/controller', True), ('/uvms/controller', True),
    ('uvms/controller', True), ('/uvms/*', True), ('/*/controller', True),
    ('controller', False), ('/controller', False), ('/**/simulator', False),
])
def test_section_keys_match_node_names_as_rcl_does(key: str, matches: bool) -> None:
    """Measured with rclpy: which keys reach /uvms/controller (a bare name means the root)."""
    assert bool(node_pattern(key).fullmatch('/uvms/controller')) is matches


def test_later_files_win_and_files_win_over_the_scenario(tmp_path: Path) -> None:
    """Two files and a scenario setting one gain: the last file's value is the node's."""
    first = write(tmp_path / 'a.yaml', '/**/controller:\n  ros__parameters:\n'
                  '    hybrid: {force_kp: 0.2}\n    impedance: {stiffness_n_m: [1, 2, 3]}\n')
    second = write(tmp_path / 'b.yaml',
                   '/uvms/controller:\n  ros__parameters:\n    hybrid: {force_kp: 0.3}\n')
    result = apply_params_files(scenario(controller={'hybrid.force_kp': 0.1}),
                                [first, second], SPECS, declared=DECLARED)
    assert result is not None
    assert result.overrides['controller'] == {'hybrid.force_kp': 0.3,
                                              'impedance.stiffness_n_m': [1.0, 2.0, 3.0]}


def test_a_wildcard_section_reaches_the_nodes_that_declare_the_name(tmp_path: Path) -> None:
    """/** with the allocator's rate: the allocator takes it, the others ignore it; a seed."""
    path = write(tmp_path / 'all.yaml',
                 '/**:\n  ros__parameters:\n    rate_hz: 250.0\n    sensor: {seed: 7}\n')
    result = apply_params_files(None, [path], SPECS, declared=DECLARED)
    assert result is not None
    assert result.overrides == {'thruster_allocator': {'rate_hz': 250.0}}
    assert result.seed == 7


@pytest.mark.parametrize(('text', 'message'), [
    ('/**/controller:\n  ros__parameters:\n    hybrid: {force_kpp: 0.2}\n',
     "the controller node has no parameter 'hybrid.force_kpp'; did you mean hybrid.force_kp?"),
    ('/**/controller:\n  ros__parameters:\n    hybrid: {force_kp: fast}\n',
     'hybrid.force_kp: expected float'),
    ('/**:\n  ros__parameters:\n    no_such: 1\n', "has no parameter 'no_such'"),
    ('controller:\n  ros__parameters:\n    hybrid: {force_kp: 0.2}\n',
     "section 'controller' matches no node of the run (/uvms/simulator, /uvms/controller"),
    ('/**/controller:\n  hybrid: {force_kp: 0.2}\n', 'has no ros__parameters mapping'),
])
def test_a_name_the_nodes_do_not_take_stops_the_run_naming_file_and_section(
        tmp_path: Path, text: str, message: str) -> None:
    """A typo is an error before anything starts, never a silently ignored gain."""
    path = write(tmp_path / 'bad.yaml', text)
    with pytest.raises(ScenarioError) as error:
        apply_params_files(scenario(), [path], SPECS, declared=DECLARED)
    assert str(error.value).startswith(f'--params-file {path}: ')
    assert message in str(error.value)


def test_without_files_the_scenario_is_unchanged() -> None:
    """No --params-file: the same scenario object."""
    given = scenario(controller={'hybrid.force_kp': 0.1})
    assert apply_params_files(given, [], SPECS, declared=DECLARED) is given
