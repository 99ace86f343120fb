"""Scenario files: the shipped ones are valid; bad ones stop before anything runs, clearly."""

from pathlib import Path

import pytest
from uvms_bringup.declared import check_scenario_overrides
from uvms_bringup.launch_helpers import SIMULATOR, config_dir
from uvms_scenarios.scenario import ScenarioError, load_scenario

from uvms_cli import cli

SCENARIOS = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'
CONFIG = config_dir()
PAPER_SCENARIOS = ('free_motion', 'case1_ke1e4', 'case1_ke1e5', 'case2_noise',
                   'case3_moving_wall', 'case4_model_error')
VALID = """\
name: test
description: a test scenario
duration_s: 1.5
seed: 3
simulator:
  contact:
    stiffness_n_m: 1e4
"""


def write(tmp_path: Path, text: str) -> Path:
    """A scenario file with this text."""
    path = tmp_path / 'scenario.yaml'
    path.write_text(text, encoding='utf-8')
    return path


@pytest.mark.parametrize('name', [*PAPER_SCENARIOS, 'impedance_only', 'hybrid_only'])
def test_shipped_scenario_follows_the_schema(name: str) -> None:
    """Every scenario of config/scenarios loads and is named after its file."""
    scenario = load_scenario(SCENARIOS / f'{name}.yaml')
    assert scenario.name == name
    assert scenario.duration_s > 0.0


def test_paper_cases_set_the_paper_values() -> None:
    """The Case I-IV files set the stiffness, noise, wall speed and mass scale of the paper."""
    def sim(name: str, key: str) -> object:
        return load_scenario(SCENARIOS / f'{name}.yaml').overrides['simulator'].get(key)

    assert sim('case1_ke1e4', 'contact.stiffness_n_m') == 1.0e4
    assert sim('case1_ke1e5', 'contact.stiffness_n_m') == 1.0e5
    assert sim('case2_noise', 'sensor.noise_fraction') == 0.001
    assert sim('case3_moving_wall', 'contact.wall_speed_m_s') == 0.05
    assert sim('free_motion', 'wall_enabled') is False
    case4 = load_scenario(SCENARIOS / 'case4_model_error.yaml')
    assert case4.overrides['controller']['model.mass_scale'] == 0.9


@pytest.mark.parametrize('name', [*PAPER_SCENARIOS, 'impedance_only', 'hybrid_only'])
def test_every_scenario_tracks_the_papers_150_n(name: str) -> None:
    """Each scenario's mission is one half circle with F_d = 150 N (paper sec. 5.1, 5.2).

    The scenario tests' claims (RMS error, overshoot, settling band) refer to this F_d, and
    their times to the path's start at 2 s.
    """
    [task] = load_scenario(SCENARIOS / f'{name}.yaml').mission
    assert task.force_n == 150.0
    assert task.half_circle is not None and task.half_circle.radius_m == 0.1
    assert task.start_time_s == 2.0


def test_case3_wall_starts_receding_at_the_set_point() -> None:
    """Case III's wall moves off once the force reaches F_d = 150 N (docs/results.md)."""
    scenario = load_scenario(SCENARIOS / 'case3_moving_wall.yaml')
    assert scenario.overrides['simulator']['wall_motion_start_force_n'] == 150.0


@pytest.mark.parametrize('name', [*PAPER_SCENARIOS, 'impedance_only', 'hybrid_only'])
def test_overrides_of_shipped_scenarios_are_declared_parameters(name: str) -> None:
    """Each override is a parameter its node declares, with that type."""
    check_scenario_overrides(load_scenario(SCENARIOS / f'{name}.yaml'))


@pytest.mark.parametrize('name', ['bluerov2_alpha5_free_motion', 'bluerov2_alpha5_contact',
                                  'bluerov2_alpha5_thruster_fault'])
def test_bluerov2_scenarios_name_their_robot_and_declared_parameters(name: str) -> None:
    """robot: bluerov2_alpha5, and every override is a parameter of that robot's nodes."""
    scenario = load_scenario(SCENARIOS / f'{name}.yaml')
    assert scenario.robot == 'bluerov2_alpha5'
    assert scenario.name == name
    check_scenario_overrides(scenario)


def test_valid_file_gives_flat_dotted_overrides_and_yaml12_floats(tmp_path: Path) -> None:
    """Nested mappings become dotted names; 1e4 reads as a float as in ROS 2 parameter files."""
    scenario = load_scenario(write(tmp_path, VALID))
    assert scenario.overrides['simulator'] == {'contact.stiffness_n_m': 1.0e4}
    assert scenario.node_overrides('simulator')['sensor.seed'] == 3


@pytest.mark.parametrize(
    ('text', 'expected'),
    [
        (VALID + 'speed: 3\n', "unknown key 'speed'"),
        (VALID.replace('duration_s: 1.5\n', ''), "missing required key 'duration_s'"),
        (VALID.replace('name: test', 'name: [a, b]'), "key 'name': expected str"),
        (VALID.replace('1.5', '"20 s"'), "key 'duration_s': expected number (float, s)"),
        (VALID.replace('1.5', '-2.0'), 'positive number of seconds'),
        (VALID.replace('seed: 3', 'seed: 1.5'), "key 'seed': expected int"),
        (VALID + 'controller: 3\n', "key 'controller': expected mapping"),
        (VALID + '    damping_n_s_m: [1, a]\n', "'simulator.contact.damping_n_s_m'"),
        (VALID + '    wall_speed_m_s:\n', "'simulator.contact.wall_speed_m_s': expected"),
        ('- a\n- b\n', 'expected a mapping'),
        ('name: [unclosed\n', 'not valid YAML'),
    ],
)
def test_bad_file_error_names_file_key_and_expected_type(
    tmp_path: Path, text: str, expected: str
) -> None:
    """Unknown keys, missing fields and wrong types raise ScenarioError naming file and key."""
    path = write(tmp_path, text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(path) in str(info.value)
    assert expected in str(info.value)


def test_missing_file_is_a_scenario_error(tmp_path: Path) -> None:
    """A file that does not exist is reported with its path."""
    with pytest.raises(ScenarioError, match='cannot read'):
        load_scenario(tmp_path / 'nope.yaml')


def test_override_of_undeclared_parameter_names_it_with_a_suggestion(tmp_path: Path) -> None:
    """A misspelt simulator parameter stops the run, naming the key and the closest names."""
    scenario = load_scenario(write(tmp_path, VALID.replace('stiffness_n_m', 'stifness_n_m')))
    with pytest.raises(ScenarioError) as info:
        check_scenario_overrides(scenario, [SIMULATOR])
    message = str(info.value)
    assert "'simulator.contact.stifness_n_m'" in message
    assert 'contact.stiffness_n_m' in message


def test_override_of_int_on_a_float_parameter_is_taken_as_float(tmp_path: Path) -> None:
    """An int where the simulator declares a float becomes a float, as in sweep files."""
    scenario = load_scenario(write(tmp_path, VALID.replace('1e4', '10000')))
    checked = check_scenario_overrides(scenario, [SIMULATOR])
    value = checked.overrides['simulator']['contact.stiffness_n_m']
    assert isinstance(value, float) and value == 10000.0


def test_override_of_wrong_parameter_type_names_expected_type(tmp_path: Path) -> None:
    """A string where the simulator declares a float is refused, naming the expected type."""
    scenario = load_scenario(write(tmp_path, VALID.replace('1e4', 'stiff')))
    with pytest.raises(ScenarioError, match=r"contact\.stiffness_n_m': expected float"):
        check_scenario_overrides(scenario, [SIMULATOR])


def test_cli_reports_bad_scenario_in_one_line_with_exit_status_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`uvms run bad.yaml` prints one error line, no traceback, and exits with 2."""
    path = write(tmp_path, VALID + 'speed: 3\n')
    status = cli.main(['run', str(path), '--quiet'])
    err = capsys.readouterr().err
    assert status == 2
    assert err.startswith('uvms run: error: ') and "unknown key 'speed'" in err
    assert 'Traceback' not in err
    assert len(err.strip().splitlines()) == 1


def test_the_check_builds_its_nodes_where_no_graph_of_the_caller_sees_them(
    tmp_path: Path,
) -> None:
    """The throwaway nodes join a domain of their own, not the caller's (a running graph's).

    A participant made and destroyed per checked node, discovering a running graph's
    participants, is what livelocked Fast DDS 2.14 in destroy_node and hung a test run.
    An observer in the caller's domain watches the graph while the check runs.
    """
    import threading
    import time

    import rclpy
    from rclpy.context import Context
    from uvms_bringup.declared import CHECK_DOMAIN_ID

    context = Context()
    rclpy.init(args=[], context=context)
    assert context.get_domain_id() != CHECK_DOMAIN_ID
    observer = rclpy.create_node('observer', context=context)
    seen: set[str] = set()
    done = threading.Event()

    def watch() -> None:
        while not done.is_set():
            seen.update(f'{ns}/{name}' for name, ns in observer.get_node_names_and_namespaces())
            time.sleep(0.02)

    watcher = threading.Thread(target=watch)
    watcher.start()
    try:
        checked = check_scenario_overrides(load_scenario(write(tmp_path, VALID)), config=CONFIG)
    finally:
        done.set()
        watcher.join()
        observer.destroy_node()
        rclpy.try_shutdown(context=context)
    assert checked.overrides['simulator']['contact.stiffness_n_m'] == 1e4
    assert not any(name.startswith('/uvms') or 'declared_check' in name for name in seen), seen
