"""The Jazzy launch file parses and starts the graph's executables from the right packages."""

import ast
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from uvms_bringup.launch_helpers import (
    CORE_NODES,
    RECORDER,
    file_parameters,
    graph_nodes,
    node_parameters,
    parameters_file_text,
)

LAUNCH_FILE = (Path(__file__).resolve().parents[2] / 'src' / 'uvms_bringup' / 'launch'
               / 'uvms.launch.py')
TREE = ast.parse(LAUNCH_FILE.read_text(encoding='utf-8'), filename=str(LAUNCH_FILE))


def calls_named(name: str) -> list[ast.Call]:
    """Every call of a function or class with this (unqualified) name."""
    return [node for node in ast.walk(TREE) if isinstance(node, ast.Call)
            and getattr(node.func, 'id', getattr(node.func, 'attr', None)) == name]


def keyword_string(call: ast.Call, name: str) -> str | None:
    """A string literal keyword argument of a call, if present."""
    for keyword in call.keywords:
        if keyword.arg == name and isinstance(keyword.value, ast.Constant):
            return str(keyword.value.value)
    return None


def test_launch_file_defines_generate_launch_description() -> None:
    """ros2 launch calls generate_launch_description()."""
    names = {node.name for node in TREE.body if isinstance(node, ast.FunctionDef)}
    assert 'generate_launch_description' in names


def test_launch_file_imports_launch_and_launch_ros() -> None:
    """It builds on the Jazzy launch and launch_ros APIs."""
    modules = {node.module for node in ast.walk(TREE) if isinstance(node, ast.ImportFrom)}
    assert {'launch', 'launch.actions', 'launch_ros.actions',
            'ament_index_python.packages'} <= modules


def test_launch_arguments_are_declared() -> None:
    """scenario, use_sim_time, mode and output_path are launch arguments."""
    declared = {call.args[0].value for call in calls_named('DeclareLaunchArgument')
                if call.args and isinstance(call.args[0], ast.Constant)}
    assert {'scenario', 'use_sim_time', 'mode', 'output_path'} <= declared


def test_node_actions_take_package_and_executable_from_the_graph_spec() -> None:
    """The Node action uses each NodeSpec's package, executable, name and namespace."""
    (node_call,) = calls_named('Node')
    arguments = {keyword.arg: ast.unparse(keyword.value) for keyword in node_call.keywords}
    assert arguments['package'] == 'spec.package'
    assert arguments['executable'] == 'spec.executable'
    assert arguments['name'] == 'spec.name'
    assert arguments['namespace'] == 'namespace'
    assert 'spec.parameter_files' in arguments['parameters']


@pytest.mark.parametrize(
    ('name', 'package', 'executable'),
    [('simulator', 'uvms_sim', 'simulator'),
     ('controller', 'uvms_control', 'controller'),
     ('thruster_allocator', 'uvms_thrusters', 'thruster_allocator'),
     ('recorder', 'uvms_recording', 'recorder'),
     ('visualizer', 'uvms_viz', 'visualizer'),
     ('foxglove_server', 'uvms_viz', 'foxglove_server')],
)
def test_graph_spec_names_the_console_scripts(name: str, package: str, executable: str) -> None:
    """Each node runs the console script its package's setup.py installs."""
    spec = {s.name: s for s in graph_nodes(record=True, foxglove=True)}[name]
    assert (spec.package, spec.executable) == (package, executable)
    setup = (LAUNCH_FILE.parents[2] / package / 'setup.py').read_text(encoding='utf-8')
    assert f"'{executable} = " in setup


def test_recorder_only_runs_with_an_output() -> None:
    """Without output_path the launch starts simulator, controller and allocator only."""
    assert graph_nodes(record=False) == CORE_NODES
    assert graph_nodes(record=True)[-1] is RECORDER


def test_simulator_is_the_clock_source_and_the_others_use_sim_time() -> None:
    """The simulator never gets use_sim_time; the other nodes run on /clock."""
    for spec in graph_nodes(record=True):
        values = node_parameters(spec, None, 'realtime', None, '/tmp/x.mcap')
        assert values.get('use_sim_time', False) is (spec.name != 'simulator')


def test_both_modes_trigger_controller_and_allocator_on_their_inputs() -> None:
    """Real time as lockstep: a step per state (controller) and per command (allocator).

    The simulator alone keeps the wall clock in real time; a second timer in the controller
    missed 13-18 % of its periods against it (issue 29).
    """
    controller, allocator = CORE_NODES[1], CORE_NODES[2]
    for mode, trigger in (('realtime', 'lockstep'), ('lockstep', 'lockstep')):
        assert node_parameters(controller, None, mode)['trigger_mode'] == trigger
        assert node_parameters(allocator, None, mode)['trigger_mode'] == trigger
        assert node_parameters(CORE_NODES[0], None, mode)['mode'] == mode


def test_a_controller_on_the_estimate_steps_on_each_estimate_in_real_time(tmp_path: Path
                                                                          ) -> None:
    """state_source estimate: the estimate lags its stamp, so real time steps on each estimate.

    Waiting for complete stamps, the launched case1_estimated stalled (INPUTS_STALE); on its
    timer the controller beat against the states (docs/running.md).
    """
    from uvms_scenarios.scenario import parse_scenario

    scenario = parse_scenario({'name': 's', 'description': 'd', 'duration_s': 1.0,
                               'controller': {'state_source': 'estimate'}},
                              tmp_path / 's.yaml')
    controller, allocator = CORE_NODES[1], CORE_NODES[2]
    assert node_parameters(controller, scenario, 'realtime')['trigger_mode'] == 'odometry'
    assert node_parameters(allocator, scenario, 'realtime')['trigger_mode'] == 'lockstep'
    assert node_parameters(controller, scenario, 'lockstep')['trigger_mode'] == 'lockstep'


def test_robot_reaches_every_node_that_loads_a_robot_folder(tmp_path: Path) -> None:
    """--robot (or a scenario's robot:) sets robot_name of simulator, controller, allocator."""
    from uvms_scenarios.scenario import parse_scenario

    scenario = parse_scenario({'name': 's', 'description': 'd', 'duration_s': 1.0,
                               'robot': 'mine'}, tmp_path / 's.yaml')
    for spec in CORE_NODES:
        given = node_parameters(spec, scenario, 'lockstep').get('robot_name')
        assert given == ('mine' if spec.takes_robot else None), spec.name
        override = node_parameters(spec, scenario, 'lockstep', robot='other').get('robot_name')
        assert override == ('other' if spec.takes_robot else None), spec.name
    assert [spec.name for spec in CORE_NODES if spec.takes_robot] == [
        'simulator', 'controller', 'thruster_allocator']
    assert 'robot_name' not in node_parameters(RECORDER, scenario, 'lockstep')


def test_parameter_file_sections_for_one_node_are_merged() -> None:
    """/** and /**/controller sections apply to /uvms/controller, flattened to dotted names."""
    config = LAUNCH_FILE.parents[3] / 'config'
    robot = file_parameters(config / 'robot.yaml', 'controller', 'uvms')
    gains = file_parameters(config / 'controller.yaml', 'controller', 'uvms')
    assert robot['contact.stiffness_n_m'] == 10000.0
    assert gains['fuzzy.no_rule_weight'] == 1.0
    assert 'rate_hz' not in gains  # the allocator's section


def test_run_parameters_file_loads_back_into_a_node(tmp_path: Path) -> None:
    """The recorded parameter file (nested from dotted names) configures a node."""
    text = parameters_file_text({'/uvms/probe': {'contact.stiffness_n_m': 1.0e5, 'mode': 'x'}})
    path = tmp_path / 'run.yaml'
    path.write_text(text, encoding='utf-8')
    context = Context()
    rclpy.init(args=[], context=context)
    try:
        node = Node('probe', namespace='uvms', context=context,
                    cli_args=['--ros-args', '--params-file', str(path)])
        assert node.declare_parameter('contact.stiffness_n_m', 0.0).value == 1.0e5
        assert node.declare_parameter('mode', '').value == 'x'
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)


def test_foxglove_server_joins_before_the_recorder_with_host_and_port() -> None:
    """--foxglove adds foxglove_server, the recorder stays last; host and port are passed."""
    names = [spec.name for spec in graph_nodes(record=True, foxglove=True)]
    assert names[-2:] == ['foxglove_server', 'recorder']
    assert 'foxglove_server' not in [spec.name for spec in graph_nodes(record=True)]
    spec = graph_nodes(record=False, foxglove=True)[-1]
    values = node_parameters(spec, None, 'lockstep', foxglove_address=('192.0.2.1', 9001))
    assert (values['host'], values['port'], values['use_sim_time']) == ('192.0.2.1', 9001, True)
    default = node_parameters(spec, None, 'lockstep')
    assert (default['host'], default['port']) == ('127.0.0.1', 8765)
