"""The ROS 2 way: colcon builds the repository, and its installed nodes talk over Fast DDS.

The README's "With ROS 2 Jazzy" steps on the wheel underlay: ``colcon build``, then each
node started as ``ros2 run`` starts it (``install/<package>/lib/<package>/<executable>``
after ``source install/setup.bash``) with the README's ``--ros-args``, in real time, as
separate processes; an rclpy subscriber in this process checks what they publish.

The wheel venv stands in for ``/opt/ros/jazzy``: AMENT_PREFIX_PATH and CMAKE_PREFIX_PATH
point at it, its ``bin`` comes first on PATH and CMake builds uvms_msgs for its Python.
colcon runs on the interpreter of the tests, as apt's colcon shares ``/usr/bin/python3``
with ROS: the console scripts it installs then start that interpreter, which has rclpy.
The workspace is built once for the module (about 40 s on 2 cores).
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import shlex
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
import rclpy
from geometry_msgs.msg import WrenchStamped
from mcap.reader import make_reader
from nav_msgs.msg import Odometry
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState

from uvms_msgs.msg import ActuatorCommand, GeneralizedForce

pytestmark = pytest.mark.colcon

REPO = Path(__file__).resolve().parents[2]
#: The packages of src/, each built by colcon (interfaces/tf2_msgs carries a COLCON_IGNORE).
PACKAGES = ('uvms_analysis', 'uvms_bringup', 'uvms_cli', 'uvms_common', 'uvms_control',
            'uvms_description', 'uvms_model', 'uvms_msgs', 'uvms_recording', 'uvms_sim',
            'uvms_navigation', 'uvms_sweep', 'uvms_tasks', 'uvms_thrusters', 'uvms_viz',
            'uvms_hardware', 'uvms_twins', 'uvms_tune', 'uvms_identify', 'uvms_scenarios',
            'uvms_pilot', 'uvms_run')
#: Longest time the build may take (s); the packages build in about 40 s on 2 cores.
BUILD_TIMEOUT_S = 600.0
#: colcon on this interpreter (as the venv's ``colcon`` script would): colcon runs setup.py
#: on its own Python, which becomes the shebang of the installed nodes.
COLCON = (sys.executable, '-c',
          'import sys; from colcon_core.command import main; sys.exit(main())')
#: Where ``ros2 run PACKAGE EXECUTABLE`` looks: install/PACKAGE/lib/PACKAGE/EXECUTABLE.
EXECUTABLES = (
    ('uvms_sim', 'simulator'),
    ('uvms_control', 'controller'),
    ('uvms_thrusters', 'thruster_allocator'),
    ('uvms_recording', 'recorder'),
    ('uvms_viz', 'visualizer'),
    ('uvms_viz', 'foxglove_server'),
    ('uvms_cli', 'uvms'),
    ('uvms_tasks', 'mission'),
    ('uvms_navigation', 'estimator'),
)
NAMESPACE = '/uvms'
#: A domain of its own, so that no other DDS graph on this machine answers for ours.
DOMAIN_ID = 100 + os.getpid() % 100
#: Messages each topic must deliver (a fraction of a second at the nominal 500 Hz).
MIN_MESSAGES = 20
#: Longest wait for every node to start and every topic to deliver (s), on 2 shared cores.
GRAPH_TIMEOUT_S = 90.0
#: Time the graph runs on after the last topic delivered, for the recorder to write (s).
SETTLE_S = 2.0
#: Longest wait for a node to exit after SIGINT (s).
STOP_TIMEOUT_S = 20.0
#: Longest time from an installed node's first start to its first message (s), issue 22.
FIRST_START_S = 5.0
#: The topics each node publishes, with their message types.
PUBLISHED = {
    'simulator': {'/clock': Clock, f'{NAMESPACE}/joint_states': JointState,
                  f'{NAMESPACE}/odometry': Odometry},
    'controller': {f'{NAMESPACE}/command/generalized_force': GeneralizedForce},
    'thruster_allocator': {f'{NAMESPACE}/command/actuators': ActuatorCommand},
}


@dataclass(frozen=True)
class NodeRun:
    """One node process after SIGINT.

    Attributes:
        returncode: Its exit status; None when it did not exit within STOP_TIMEOUT_S.
        stderr: What it wrote to stderr (ROS 2 logs go there).
    """

    returncode: int | None
    stderr: str


@dataclass
class GraphRun:
    """What the node graph published, recorded and did on SIGINT.

    Attributes:
        counts: Messages received per topic.
        last: The last message received per topic.
        recording: The recorder's MCAP file.
        nodes: Each node's exit, by executable name.
    """

    counts: dict[str, int] = field(default_factory=dict)
    last: dict[str, Any] = field(default_factory=dict)
    recording: Path = Path()
    nodes: dict[str, NodeRun] = field(default_factory=dict)

    def diagnostics(self) -> str:
        """Counts and each node's exit and stderr tail, for a failure message."""
        lines = [f'messages per topic: {self.counts}']
        for name, run in self.nodes.items():
            lines.append(f'--- {name}: exit {run.returncode}\n{run.stderr[-3000:]}')
        return '\n'.join(lines)


@dataclass(frozen=True)
class Workspace:
    """A built colcon workspace.

    Attributes:
        root: The workspace directory (src/, build/, install/, log/).
        underlay: The prefix of the wheel venv (what /opt/ros/jazzy would be).
        build_seconds: Wall time of ``colcon build`` (s).
        build_output: What ``colcon build`` printed (stdout and stderr).
    """

    root: Path
    underlay: Path
    build_seconds: float
    build_output: str

    @property
    def install(self) -> Path:
        """The install space, as ``source install/setup.bash`` uses it."""
        return self.root / 'install'

    def environment(self) -> dict[str, str]:
        """The shell environment before ``source install/setup.bash``: the underlay alone."""
        env = dict(os.environ)
        env.pop('COLCON_PREFIX_PATH', None)  # no other workspace is chained in
        env['AMENT_PREFIX_PATH'] = str(self.underlay)
        env['CMAKE_PREFIX_PATH'] = str(self.underlay)
        env['PATH'] = os.pathsep.join([str(self.underlay / 'bin'), env.get('PATH', '')])
        env['COLCON_HOME'] = str(self.root / '.colcon')  # no user defaults or mixins
        env['ROS_LOG_DIR'] = str(self.root / 'ros_log')
        return env


def tracked_files(repo: Path) -> list[str]:
    """Files a clone would hold, plus new files not ignored: what the workspace builds."""
    listed = subprocess.run(
        ['git', 'ls-files', '--cached', '--others', '--exclude-standard', '-z'],
        cwd=repo, capture_output=True, check=True,
    ).stdout.decode()
    return [name for name in listed.split('\0') if name and (repo / name).is_file()]


def copy_repository(repo: Path, destination: Path) -> None:
    """Copy the repository's files (no venv, no build artefacts) to ``destination``."""
    for name in tracked_files(repo):
        target = destination / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(repo / name, target)


@pytest.fixture(scope='module')
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Workspace:
    """``colcon build`` of a workspace with this repository in src/uvms, once for the module."""
    if importlib.util.find_spec('colcon_core') is None:
        pytest.fail("colcon is not installed for this interpreter: pip install -e '.[test]' "
                    '(colcon-common-extensions is pinned in pyproject.toml)')
    root = tmp_path_factory.mktemp('colcon_ws')
    copy_repository(REPO, root / 'src' / 'uvms')
    underlay = Path(sys.prefix)
    pending = Workspace(root, underlay, 0.0, '')
    command = [
        *COLCON, 'build',
        '--event-handlers', 'console_cohesion+',
        '--cmake-args', f'-DPython3_EXECUTABLE={sys.executable}', '-DBUILD_TESTING=OFF',
    ]
    start = time.monotonic()
    result = subprocess.run(command, cwd=root, env=pending.environment(), text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            timeout=BUILD_TIMEOUT_S, check=False)
    built = Workspace(root, underlay, time.monotonic() - start, result.stdout)
    if result.returncode != 0:
        pytest.fail(f'colcon build exited {result.returncode}:\n{result.stdout[-6000:]}')
    return built


def in_sourced_workspace(workspace: Workspace, command: Sequence[str]) -> list[str]:
    """``bash -c 'source install/setup.bash && exec COMMAND'``, as a user's shell runs it."""
    return ['bash', '-c', f'source install/setup.bash && exec {shlex.join(command)}']


def node_command(workspace: Workspace, name: str, recording: Path) -> list[str]:
    """The README's command line of node ``name``, in real time (``timer`` triggers)."""
    config = workspace.install / 'uvms_bringup' / 'share' / 'uvms_bringup' / 'config'
    robot = ['--params-file', str(config / 'robot.yaml')]
    control = [*robot, '--params-file', str(config / 'controller.yaml'),
               '-p', 'trigger_mode:=timer']
    arguments = {
        'simulator': ('uvms_sim', [*robot, '-p', 'mode:=realtime']),
        'controller': ('uvms_control', control),
        'thruster_allocator': ('uvms_thrusters', control),
        'recorder': ('uvms_recording', ['-p', f'output_path:={recording}']),
    }
    package, ros_args = arguments[name]
    executable = workspace.install / package / 'lib' / package / name
    return [str(executable), '--ros-args', '-r', f'__ns:={NAMESPACE}', *ros_args]


def listen(graph: GraphRun, processes: dict[str, subprocess.Popen[bytes]]) -> None:
    """Subscribe to every published topic and count until each delivered MIN_MESSAGES."""
    context = Context()
    rclpy.init(args=[], context=context, domain_id=DOMAIN_ID,
               signal_handler_options=SignalHandlerOptions.NO)
    executor = SingleThreadedExecutor(context=context)
    node = rclpy.create_node('ros2_way_listener', context=context)
    try:
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)

        def receive(topic: str, msg: Any) -> None:
            graph.counts[topic] += 1
            graph.last[topic] = msg

        for topics in PUBLISHED.values():
            for topic, msg_type in topics.items():
                graph.counts[topic] = 0
                node.create_subscription(msg_type, topic,
                                         lambda msg, t=topic: receive(t, msg), qos)
        executor.add_node(node)
        deadline = time.monotonic() + GRAPH_TIMEOUT_S
        while (min(graph.counts.values()) < MIN_MESSAGES and time.monotonic() < deadline
               and all(p.poll() is None for p in processes.values())):
            executor.spin_once(timeout_sec=0.1)
        settle_end = time.monotonic() + SETTLE_S
        while time.monotonic() < settle_end:
            executor.spin_once(timeout_sec=0.1)
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def stop(process: subprocess.Popen[bytes]) -> int | None:
    """SIGINT, as Ctrl-C in the node's terminal; the exit status, or None if it hung."""
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
    try:
        return process.wait(timeout=STOP_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
        return None


@pytest.fixture(scope='module')
def graph(workspace: Workspace, tmp_path_factory: pytest.TempPathFactory) -> Iterator[GraphRun]:
    """The four installed nodes in real time: what they publish, and how SIGINT ends them."""
    logs = tmp_path_factory.mktemp('ros2_way_logs')
    run = GraphRun(recording=logs / 'run.mcap')
    env = workspace.environment()
    env['ROS_DOMAIN_ID'] = str(DOMAIN_ID)
    processes: dict[str, subprocess.Popen[bytes]] = {}
    # Stopped in this order: the recorder last, so its file covers the whole run.
    names = ('simulator', 'controller', 'thruster_allocator', 'recorder')
    try:
        for name in names:
            with (logs / f'{name}.stderr').open('wb') as stderr:
                processes[name] = subprocess.Popen(
                    in_sourced_workspace(workspace, node_command(workspace, name, run.recording)),
                    cwd=workspace.root, env=env, stdin=subprocess.DEVNULL,
                    stdout=subprocess.DEVNULL, stderr=stderr, start_new_session=True,
                )
        listen(run, processes)
        for name in ('thruster_allocator', 'controller', 'simulator', 'recorder'):
            returncode = stop(processes[name])
            stderr_text = (logs / f'{name}.stderr').read_text(errors='replace')
            run.nodes[name] = NodeRun(returncode, stderr_text)
    finally:
        for process in processes.values():
            if process.poll() is None:
                process.kill()
                process.wait()
    yield run


def test_colcon_builds_every_package_of_the_repository(workspace: Workspace) -> None:
    """Every package of src/ builds and installs, with its package.xml in its share directory."""
    assert f'Summary: {len(PACKAGES)} packages finished' in workspace.build_output, (
        workspace.build_output[-3000:])
    for package in PACKAGES:
        assert (workspace.install / package / 'share' / package / 'package.xml').is_file()


@pytest.mark.parametrize(('package', 'executable'), EXECUTABLES)
def test_executable_is_installed_where_ros2_run_looks(
    workspace: Workspace, package: str, executable: str
) -> None:
    """install/PKG/lib/PKG/EXE exists, is executable and starts the underlay's Python."""
    path = workspace.install / package / 'lib' / package / executable
    assert path.is_file(), f'{path} missing'
    assert os.access(path, os.X_OK)
    with path.open() as script:
        assert script.readline().strip() == f'#!{sys.executable}'


def test_bringup_installs_the_repository_config_files(workspace: Workspace) -> None:
    """setup.py's ../../config globs install every parameter and scenario file, unchanged."""
    share = workspace.install / 'uvms_bringup' / 'share' / 'uvms_bringup' / 'config'
    source = REPO / 'config'
    expected = sorted(str(p.relative_to(source)) for pattern in ('*.yaml', '*.xml',
                                                                 'scenarios/*.yaml',
                                                                 'tasks/*.yaml')
                      for p in source.glob(pattern))
    installed = sorted(str(p.relative_to(share)) for p in share.rglob('*') if p.is_file())
    assert installed == expected
    for name in expected:
        assert (share / name).read_bytes() == (source / name).read_bytes(), name


def test_description_installs_the_foxglove_layout(workspace: Workspace) -> None:
    """The Foxglove layout lands in share/uvms_description/foxglove, unchanged."""
    name = 'foxglove/uvms_layout.json'
    installed = workspace.install / 'uvms_description' / 'share' / 'uvms_description' / name
    assert installed.read_bytes() == (REPO / 'src' / 'uvms_description' / name).read_bytes()


def test_description_installs_every_robot_folder(workspace: Workspace) -> None:
    """share/uvms_description/robots/<name>/ holds each robot's files, unchanged."""
    source = REPO / 'src' / 'uvms_description' / 'robots'
    share = workspace.install / 'uvms_description' / 'share' / 'uvms_description' / 'robots'
    robots = sorted(p.name for p in source.iterdir() if p.is_dir())
    assert 'paper_uvms' in robots
    for robot in robots:
        for file in (source / robot).glob('*.*'):
            installed = share / robot / file.name
            assert installed.read_bytes() == file.read_bytes(), str(installed)


def test_sourced_workspace_runs_its_own_packages_on_the_underlay(workspace: Workspace) -> None:
    """After ``source install/setup.bash`` Python and the ament index find install/ first.

    Our packages (also installed in the venv: editable, and uvms_msgs by rosidl) resolve to
    the workspace, rclpy to the underlay, and uvms_common finds its installed DDS profile.
    """
    script = '\n'.join([
        'import importlib, json',
        'from ament_index_python.packages import get_package_prefix',
        'from uvms_common.ros_environment import loopback_profile_path',
        'modules = {name: importlib.import_module(name).__file__ for name in (',
        "    'uvms_common', 'uvms_description', 'uvms_model', 'uvms_sim', 'uvms_control',",
        "    'uvms_bringup', 'uvms_recording', 'uvms_analysis', 'uvms_viz', 'uvms_sweep',",
        "    'uvms_cli', 'uvms_navigation', 'uvms_thrusters',",
        "    'uvms_msgs.msg')}",
        "prefixes = {name: get_package_prefix(name) for name in ('uvms_bringup', 'uvms_msgs',",
        "                                                        'rclpy')}",
        "print(json.dumps({'modules': modules, 'prefixes': prefixes,",
        "                  'profile': str(loopback_profile_path())}))",
    ])
    result = subprocess.run(in_sourced_workspace(workspace, ['python', '-c', script]),
                            cwd=workspace.root, env=workspace.environment(), text=True,
                            capture_output=True, timeout=60, check=False)
    assert result.returncode == 0, result.stderr
    found = json.loads(result.stdout)
    install = workspace.install.resolve()
    for name, path in found['modules'].items():
        assert Path(path).resolve().is_relative_to(install / name.split('.')[0]), (name, path)
    assert found['prefixes'] == {
        'uvms_bringup': str(workspace.install / 'uvms_bringup'),
        'uvms_msgs': str(workspace.install / 'uvms_msgs'),
        'rclpy': str(workspace.underlay),
    }
    profile = Path(found['profile'])
    assert profile.resolve().is_relative_to(install / 'uvms_common')
    assert profile.read_bytes() == (
        REPO / 'src' / 'uvms_common' / 'uvms_common' / 'fastdds_loopback.xml').read_bytes()


def test_build_compiles_the_kernels_of_the_installed_packages(workspace: Workspace) -> None:
    """setup.py install ran the kernel cache: Numba's index files sit beside the installed code.

    Numba keys its cache by the module's path, so the copies in install/ need caches of their
    own; the build fills them before any node started (this test runs before the graph).
    """
    for package, folder in (('uvms_model', 'uvms_model'),
                            ('uvms_control', 'uvms_control/core/law'),
                            ('uvms_thrusters', 'uvms_thrusters')):
        lib = next((workspace.install / package / 'lib').glob('python3*/site-packages'))
        indexes = list((lib / folder / '__pycache__').glob('*.nbi'))
        assert indexes, f'no Numba cache under {lib / folder}'
    assert 'uvms_control: kernels compiled and cached' in workspace.build_output
    assert 'uvms_thrusters: kernels compiled and cached' in workspace.build_output


def test_installed_controller_publishes_within_5_s_of_its_first_start(
    workspace: Workspace, tmp_path: Path,
) -> None:
    """Its first start compiles nothing and logs before loading: a command within 5 s.

    The controller is fed still, valid inputs from this process (timer mode); NUMBA_DEBUG_CACHE
    makes Numba name every kernel it would save, which only a compilation does.
    """
    env = workspace.environment()
    env['ROS_DOMAIN_ID'] = str(DOMAIN_ID)
    env['NUMBA_DEBUG_CACHE'] = '1'
    env['PYTHONUNBUFFERED'] = '1'
    config = workspace.install / 'uvms_bringup' / 'share' / 'uvms_bringup' / 'config'
    executable = workspace.install / 'uvms_control' / 'lib' / 'uvms_control' / 'controller'
    command = [str(executable), '--ros-args', '-r', '__ns:=/first_start',
               '--params-file', str(config / 'robot.yaml'),
               '--params-file', str(config / 'controller.yaml'), '-p', 'trigger_mode:=timer']
    context = Context()
    rclpy.init(args=[], context=context, domain_id=DOMAIN_ID,
               signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node('first_start_feeder', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    joints = JointState(name=['joint_1', 'joint_2', 'joint_3'], position=[0.0, 0.4, -0.8],
                        velocity=[0.0] * 3)
    odometry = Odometry()
    odometry.header.frame_id, odometry.child_frame_id = 'map_ned', 'base_link_frd'
    odometry.pose.pose.orientation.w = 1.0
    inputs = [(node.create_publisher(type(msg), f'/first_start/{topic}', qos), msg)
              for topic, msg in (('joint_states', joints), ('odometry', odometry),
                                 ('wrench', WrenchStamped()))]
    first: list[float] = []
    node.create_subscription(GeneralizedForce, '/first_start/command/generalized_force',
                             lambda _msg: first.append(time.monotonic()), qos)
    output = tmp_path / 'controller.out'
    with output.open('wb') as stream:
        start = time.monotonic()
        process = subprocess.Popen(in_sourced_workspace(workspace, command),
                                   cwd=workspace.root, env=env, stdin=subprocess.DEVNULL,
                                   stdout=stream, stderr=subprocess.STDOUT)
        try:
            while not first and time.monotonic() - start < GRAPH_TIMEOUT_S:
                stamp = node.get_clock().now().to_msg()
                for publisher, msg in inputs:
                    msg.header.stamp = stamp
                    publisher.publish(msg)
                executor.spin_once(timeout_sec=0.01)
        finally:
            returncode = stop(process)
            executor.shutdown()
            node.destroy_node()
            rclpy.try_shutdown(context=context)
    text = output.read_text(errors='replace')
    assert first, f'no generalized force within {GRAPH_TIMEOUT_S} s:\n{text[-3000:]}'
    assert 'data saved to' not in text, f'kernels compiled at the first start:\n{text[-3000:]}'
    assert first[0] - start < FIRST_START_S, f'{first[0] - start:.1f} s:\n{text[-3000:]}'
    assert returncode == 0, text[-3000:]
    logs = [line for line in text.splitlines() if 'controller]: ' in line]
    assert 'loading the model and compiled kernels' in logs[0], logs


def test_simulator_publishes_clock_joint_states_and_odometry_in_realtime(
    graph: GraphRun,
) -> None:
    """``-p mode:=realtime``: /clock and the state topics flow without any other node's help."""
    for topic in PUBLISHED['simulator']:
        assert graph.counts[topic] >= MIN_MESSAGES, graph.diagnostics()


def test_controller_publishes_finite_generalized_force_from_the_simulator_state(
    graph: GraphRun,
) -> None:
    """Timer mode computes only once joint_states, odometry and wrench arrived: a loop."""
    topic = f'{NAMESPACE}/command/generalized_force'
    assert graph.counts[topic] >= MIN_MESSAGES, graph.diagnostics()
    msg = graph.last[topic]
    wrench = msg.vehicle_wrench
    values = [wrench.force.x, wrench.force.y, wrench.force.z,
              wrench.torque.x, wrench.torque.y, wrench.torque.z, *msg.joint_torques]
    assert all(math.isfinite(v) for v in values), values
    assert len(msg.joint_torques) == len(msg.joint_names) == 3


def test_allocator_publishes_actuator_commands_the_simulator_accepts(graph: GraphRun) -> None:
    """command/actuators flows in timer mode, and the simulator rejects none of it."""
    assert graph.counts[f'{NAMESPACE}/command/actuators'] >= MIN_MESSAGES, graph.diagnostics()
    assert 'rejected' not in graph.nodes['simulator'].stderr, graph.diagnostics()


def test_recorder_writes_every_published_topic_to_its_mcap_file(graph: GraphRun) -> None:
    """The recorder, stopped last, leaves a closed MCAP file with messages on each topic."""
    with graph.recording.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None and summary.statistics is not None, 'MCAP file not closed'
    counts = {summary.channels[channel_id].topic: count
              for channel_id, count in summary.statistics.channel_message_counts.items()}
    for topics in PUBLISHED.values():
        for topic in topics:
            assert counts.get(topic, 0) > 0, (topic, counts)


@pytest.mark.parametrize('name', ['simulator', 'controller', 'thruster_allocator', 'recorder'])
def test_sigint_stops_the_node_with_status_0_and_no_traceback(
    graph: GraphRun, name: str
) -> None:
    """Ctrl-C ends the running node cleanly, exit 0 as Jazzy's demo nodes, nothing raised."""
    run = graph.nodes[name]
    assert run.returncode == 0, graph.diagnostics()
    assert 'Traceback' not in run.stderr, run.stderr
    assert 'RCLError' not in run.stderr, run.stderr
