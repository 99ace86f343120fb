"""The whole graph in one process: rates, the lockstep chain, recordings, determinism."""

from __future__ import annotations

import dataclasses
import functools
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path

import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from uvms_run.graph import GraphError, RunResult, build_graph, run_graph
from uvms_scenarios.scenario import Scenario, load_scenario

from uvms_cli import cli

SCENARIOS = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'
DURATION_S = 0.5
STATE_TOPICS = ('/clock', '/uvms/joint_states', '/uvms/odometry', '/uvms/wrench',
                '/uvms/ee_pose', '/uvms/contact')
ANSWER_TOPICS = ('/uvms/command/generalized_force', '/uvms/controller/state',
                 '/uvms/command/actuators', '/uvms/thrusters/state')
SCHEMAS = {
    '/clock': 'rosgraph_msgs/msg/Clock',
    '/uvms/joint_states': 'sensor_msgs/msg/JointState',
    '/uvms/odometry': 'nav_msgs/msg/Odometry',
    '/uvms/wrench': 'geometry_msgs/msg/WrenchStamped',
    '/uvms/ee_pose': 'geometry_msgs/msg/PoseStamped',
    '/uvms/contact': 'uvms_msgs/msg/ContactState',
    '/uvms/command/generalized_force': 'uvms_msgs/msg/GeneralizedForce',
    '/uvms/controller/state': 'uvms_msgs/msg/ControllerState',
    '/uvms/controller/task_record': 'uvms_msgs/msg/ContactTaskRecord',
    '/uvms/controller/mode': 'std_msgs/msg/String',  # pilot, task or hold (latched)
    '/uvms/command/actuators': 'uvms_msgs/msg/ActuatorCommand',
    '/uvms/thrusters/state': 'uvms_msgs/msg/ThrusterState',
    '/uvms/thrusters/health': 'uvms_msgs/msg/ThrusterHealth',
    '/tf': 'tf2_msgs/msg/TFMessage',
    '/tf_static': 'tf2_msgs/msg/TFMessage',
    '/robot_description': 'std_msgs/msg/String',
    '/uvms/markers': 'visualization_msgs/msg/MarkerArray',
    '/uvms/ocean/current': 'geometry_msgs/msg/TwistStamped',  # its channel, empty in still water
}


def scenario(name: str, seed: int | None = None) -> Scenario:
    """A shipped scenario, cut to DURATION_S."""
    return load_scenario(SCENARIOS / f'{name}.yaml').with_changes(duration_s=DURATION_S,
                                                                   seed=seed)


def record(tmp_path: Path, name: str, seed: int | None = None) -> tuple[RunResult, Path]:
    """Run a scenario in lockstep with the recorder; return the result and the file."""
    path = tmp_path / f'{name}_{seed}.mcap'
    graph = build_graph(scenario(name, seed), 'lockstep', output_path=path)
    return run_graph(graph), path


def payloads(path: Path) -> dict[str, list[bytes]]:
    """Message payloads per topic, in file order (mcap reader)."""
    result: dict[str, list[bytes]] = defaultdict(list)
    with path.open('rb') as stream:
        for _, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            result[channel.topic].append(message.data)
    return result


@functools.cache
def stamps(path: Path) -> dict[str, list[int]]:
    """Header stamps (ns) per topic, decoded by rosbags (once per recording: read-only).

    Twelve tests read the stamps of the module's one recording; decoding it takes 0.2-0.3 s
    of CPU each time.
    """
    result: dict[str, list[int]] = defaultdict(list)
    with AnyReader([path]) as reader:
        for connection, _, raw in reader.messages():
            if connection.topic in ('/robot_description', '/uvms/markers',
                                    '/uvms/controller/mode'):
                continue  # no header of their own
            msg = reader.deserialize(raw, connection.msgtype)
            stamp = msg.clock if connection.topic == '/clock' else (
                msg.transforms[0].header.stamp if connection.topic.startswith('/tf')
                else msg.header.stamp)
            result[connection.topic].append(stamp.sec * 1_000_000_000 + stamp.nanosec)
    return result


@pytest.fixture(scope='module')
def case1(tmp_path_factory: pytest.TempPathFactory) -> tuple[RunResult, Path]:
    """One lockstep run of case1_ke1e4 (0.5 s) with recording."""
    return record(tmp_path_factory.mktemp('case1'), 'case1_ke1e4')


def test_run_reaches_the_scenario_duration(case1: tuple[RunResult, Path]) -> None:
    """The lockstep run stops at duration_s of simulated time."""
    result, _ = case1
    assert result.sim_time_s == pytest.approx(DURATION_S)
    assert not result.interrupted


@pytest.mark.parametrize('topic', [*STATE_TOPICS, *ANSWER_TOPICS])
def test_every_state_and_its_answer_flow_at_500_hz(
    case1: tuple[RunResult, Path], topic: str
) -> None:
    """Each topic carries one message per 2 ms of simulated time, stamped t_k."""
    _, path = case1
    expected = [2_000_000 * k for k in range(round(DURATION_S * 500) + 1)]
    assert sorted(stamps(path)[topic]) == expected


def test_tf_flows_at_50_hz(case1: tuple[RunResult, Path]) -> None:
    """/tf comes every 20 ms of simulated time, /tf_static once."""
    _, path = case1
    recorded = stamps(path)
    assert recorded['/tf'] == [20_000_000 * k for k in range(round(DURATION_S * 50) + 1)]
    assert len(recorded['/tf_static']) == 1


def test_simulator_never_stepped_without_the_command_of_its_step(
    case1: tuple[RunResult, Path]
) -> None:
    """Every state got its actuator command with the same stamp, and no timeout occurred."""
    result, path = case1
    recorded = stamps(path)
    assert result.lockstep_timeouts == 0
    assert recorded['/uvms/command/actuators'] == recorded['/uvms/joint_states']


def test_recording_opens_with_mcap_reader_and_rosbags(case1: tuple[RunResult, Path]) -> None:
    """The MCAP has every graph topic with its ros2msg schema, readable by both libraries."""
    _, path = case1
    with path.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    channels = {c.topic: summary.schemas[c.schema_id] for c in summary.channels.values()}
    assert {topic: schema.name for topic, schema in channels.items()} == SCHEMAS
    assert {schema.encoding for schema in channels.values()} == {'ros2msg'}
    with AnyReader([path]) as reader:
        assert {c.topic for c in reader.connections} == set(SCHEMAS)
        count = sum(1 for _ in reader.messages())
    assert count == summary.statistics.message_count


@pytest.fixture(scope='module')
def seed_5_run(
    tmp_path_factory: pytest.TempPathFactory
) -> Callable[[str], dict[str, list[bytes]]]:
    """The payloads of one lockstep run of a scenario with seed 5, each run once a module.

    The first run of the same-seed test and the seed-5 run of the other-seed test are the
    same run (a lockstep run: its bytes do not depend on when it ran); each test still runs
    its second one.
    """
    runs: dict[str, dict[str, list[bytes]]] = {}

    def run(name: str) -> dict[str, list[bytes]]:
        if name not in runs:
            runs[name] = payloads(record(tmp_path_factory.mktemp(f'{name}_seed_5'), name, 5)[1])
        return runs[name]

    return run


@pytest.mark.parametrize('name', ['case2_noise', 'case1_current'])
def test_same_seed_gives_byte_identical_payloads(
    tmp_path: Path, name: str, seed_5_run: Callable[[str], dict[str, list[bytes]]]
) -> None:
    """Two lockstep runs with the same seed record the same bytes: sensor noise, noisy current.

    In still water (case2_noise) the ocean current's channel holds no message. No task ends
    within 5 s, so there is no task record either.
    """
    first, second = seed_5_run(name), payloads(record(tmp_path, name, 5)[1])
    still_water = {'/uvms/ocean/current'} if name == 'case2_noise' else set()
    assert set(first) == set(SCHEMAS) - still_water - {'/uvms/controller/task_record'}
    for topic in SCHEMAS:
        assert first[topic] == second[topic], topic


def test_other_seed_changes_the_sensor_noise(
    tmp_path: Path, seed_5_run: Callable[[str], dict[str, list[bytes]]]
) -> None:
    """A different seed gives different wrench readings in the noisy case."""
    first = seed_5_run('case2_noise')['/uvms/wrench']
    second = payloads(record(tmp_path, 'case2_noise', 6)[1])['/uvms/wrench']
    assert first != second


def test_bad_node_parameter_stops_the_build_naming_node_and_parameter() -> None:
    """A parameter out of range stops the graph before it runs, naming node and parameter."""
    with pytest.raises(GraphError, match=r'simulator.*physics_rate_hz'):
        build_graph(scenario('case1_ke1e4'), extra_overrides={
            'simulator': {'physics_rate_hz': -1.0}})


def test_cli_run_records_the_scenario(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`uvms run NAME --duration --output --quiet` exits 0, writes the recording, says where."""
    output = tmp_path / 'out' / 'run.mcap'
    status = cli.main(['run', 'free_motion', '--duration', '0.1', '--output', str(output),
                       '--quiet'])
    err = capsys.readouterr().err
    assert status == 0, err
    assert len(payloads(output)['/uvms/joint_states']) == 51
    summary = [line for line in err.splitlines() if line.startswith('uvms run: simulated')]
    assert len(summary) == 1 and summary[0].endswith(f'; recorded {output}'), err


def test_realtime_graph_holds_and_names_a_controller_left_unconfigured(
    tmp_path: Path,
) -> None:
    """Real time, ``controller: {autostart: false}``: no physics, then an error naming it.

    Before issue 29 the simulator integrated from its first tick with zero commands.
    """
    run = scenario('free_motion')
    # Long enough for discovery of the nodes' get_state services on a slow, loaded machine
    # (2 s once named both nodes 'not running' here): the error must name the state.
    overrides = {**run.overrides, 'controller': {'autostart': False},
                 'simulator': {**run.overrides.get('simulator', {}), 'startup.timeout_s': 8.0}}
    graph = build_graph(dataclasses.replace(run, overrides=overrides), 'realtime',
                        duration_s=0.3)
    # The controller is named; its state as 'unconfigured', or as 'not running' when its
    # get_state service was not seen: once in a whole-suite run on Python 3.12 (both nodes
    # 'not running' after 8 s in one process; 4 of 4 alone passed): under investigation.
    with pytest.raises(GraphError, match=r'controller is (unconfigured|not running)') as error:
        run_graph(graph)
    assert 't = 0.000 s' in str(error.value)
    assert 'control loop did not close' in str(error.value)


@pytest.mark.parametrize(('node', 'topic'), [
    ('thruster_allocator', '/uvms/command/actuators'),
    ('controller', '/uvms/command/generalized_force'),
])
def test_lockstep_graph_runs_with_a_node_left_unconfigured(tmp_path: Path, node: str,
                                                           topic: str) -> None:
    """``NODE: {autostart: false}``: its zeros answer every state, the run ends on time.

    Before issue 29 ``uvms run`` waited forever at t = 0 (the node answered nothing).
    """
    path = tmp_path / 'unconfigured.mcap'
    run = scenario('case1_ke1e4').with_changes(duration_s=0.1)
    overrides = {**run.overrides, node: {'autostart': False}}
    result = run_graph(build_graph(dataclasses.replace(run, overrides=overrides), 'lockstep',
                                   output_path=path))
    assert result.sim_time_s == pytest.approx(0.1)
    assert result.lockstep_timeouts == 0
    with AnyReader([path]) as reader:
        connections = [c for c in reader.connections if c.topic == topic]
        commands = [reader.deserialize(raw, c.msgtype)
                    for c, _, raw in reader.messages(connections=connections)]
    assert len(commands) == 51
    for command in commands:
        values = (list(command.thrust) if hasattr(command, 'thrust') else [
            command.vehicle_wrench.force.x, command.vehicle_wrench.force.z,
            command.vehicle_wrench.torque.y])
        assert not any(values) and not any(command.joint_torques)


def test_realtime_graph_runs_on_wall_clock_timers(tmp_path: Path) -> None:
    """In real time simulated time follows the wall clock and the commands flow."""
    path = tmp_path / 'realtime.mcap'
    graph = build_graph(scenario('free_motion'), 'realtime', duration_s=0.3, output_path=path)
    result = run_graph(graph)
    assert result.sim_time_s == pytest.approx(0.3)
    assert result.wall_time_s >= 0.3
    assert len(payloads(path)['/uvms/command/actuators']) > 10
