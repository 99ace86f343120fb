"""Integration: recorder process and signals, record then replay, controller re-run."""

from __future__ import annotations

import os
import selectors
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import rclpy
from geometry_msgs.msg import WrenchStamped
from mcap.reader import make_reader
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState
from uvms_recording.mcap_reader import open_recording
from uvms_recording.mcap_writer import McapRecorder
from uvms_recording.recorded_topics import DEFAULT_TOPICS
from uvms_recording.recorder_node import RecorderNode
from uvms_recording.replay import ReplayNode, ReplayOptions
from uvms_run.graph import build_graph, run_graph
from uvms_scenarios.scenario import load_scenario

from uvms_recording import replay, rerun

REPO = Path(__file__).resolve().parents[2]
SOURCES = [REPO / 'src' / name for name in
           ('uvms_common', 'uvms_bringup', 'uvms_model', 'uvms_sim', 'uvms_control',
            'uvms_thrusters')]


def _start_recorder(*parameters: str) -> subprocess.Popen[str]:
    """Start `python -m uvms_recording.recorder_node` with -p parameters."""
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([*map(str, SOURCES), env.get('PYTHONPATH', '')])
    arguments = [item for parameter in parameters for item in ('-p', parameter)]
    return subprocess.Popen(
        [sys.executable, '-m', 'uvms_recording.recorder_node', '--ros-args',
         '-r', '__ns:=/uvms', *arguments],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd=REPO,
    )


def _wait_for_output(process: subprocess.Popen[str], text: str, timeout_s: float) -> str:
    """Read the process's output until a line contains text; return everything read."""
    assert process.stdout is not None
    selector = selectors.DefaultSelector()
    selector.register(process.stdout, selectors.EVENT_READ)
    seen = ''
    deadline = time.monotonic() + timeout_s
    while text not in seen:
        remaining = deadline - time.monotonic()
        assert remaining > 0, f'no {text!r} from the process; output so far:\n{seen}'
        if selector.select(timeout=remaining):
            line = process.stdout.readline()
            if not line:
                pytest.fail(f'process exited early ({process.wait()}):\n{seen}')
            seen += line
    return seen


@pytest.mark.parametrize('signum', [signal.SIGTERM, signal.SIGINT], ids=['SIGTERM', 'SIGINT'])
def test_signal_closes_the_recorder_process_with_a_complete_file(
    tmp_path: Path, signum: signal.Signals
) -> None:
    """SIGTERM or SIGINT makes the recorder exit 0 leaving an MCAP with Statistics."""
    path = tmp_path / 'run.mcap'
    process = _start_recorder(f'output_path:={path}')
    try:
        _wait_for_output(process, 'recording', timeout_s=60.0)
        process.send_signal(signum)
        output, _ = process.communicate(timeout=30.0)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 0, output
    assert 'Traceback' not in output
    with path.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    assert summary.statistics is not None
    recording = open_recording(path)
    assert not recording.truncated
    assert len(recording.topics) == len(DEFAULT_TOPICS)


def test_what_reached_a_stopping_recorder_is_in_its_file(context: Context, tmp_path: Path) -> None:
    """Messages waiting in the recorder when SIGINT comes are recorded, not lost.

    A recorder behind on a busy machine (stood for by SIGSTOP) gets its stop with messages
    not yet taken: the controller's one task record of a run among them. 100 messages fit
    the stopped process's socket buffers (300 did not: the rest wait for the writer's repeat).
    """
    path = tmp_path / 'run.mcap'
    process = _start_recorder(f'output_path:={path}')
    talker = Node('talker', namespace='/uvms', context=context)
    keep_all = QoSProfile(history=HistoryPolicy.KEEP_ALL, depth=1,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE)
    wrench = talker.create_publisher(WrenchStamped, 'wrench', keep_all)
    try:
        _wait_for_output(process, 'recording', timeout_s=60.0)
        deadline = time.monotonic() + 30.0
        while wrench.get_subscription_count() == 0:
            assert time.monotonic() < deadline, 'the recorder never subscribed to wrench'
            time.sleep(0.05)
        process.send_signal(signal.SIGSTOP)
        for k in range(100):
            message = WrenchStamped()
            message.wrench.force.x = float(k)
            wrench.publish(message)
        time.sleep(0.5)  # the messages are in the stopped process's socket buffers
        process.send_signal(signal.SIGCONT)
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=30.0)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        talker.destroy_node()
    assert process.returncode == 0, output
    recorded = [m for m in open_recording(path).messages() if m.topic == '/uvms/wrench']
    assert len(recorded) == 100, output


@pytest.mark.parametrize('signum', [signal.SIGTERM, signal.SIGINT], ids=['SIGTERM', 'SIGINT'])
def test_signal_stops_a_looping_replay_process_cleanly(
    tmp_path: Path, signum: signal.Signals
) -> None:
    """`uvms replay --loop` stops on SIGTERM or SIGINT between messages and exits 0."""
    path = tmp_path / 'slow.mcap'
    data = serialize_message(WrenchStamped())
    with McapRecorder(path) as recorder:
        recorder.add_topic('/uvms/wrench', 'geometry_msgs/msg/WrenchStamped')
        for k in range(20):
            recorder.write('/uvms/wrench', data, k * 50_000_000)
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([*map(str, SOURCES), env.get('PYTHONPATH', '')])
    # A replay keeps an inherited SIG_IGN (a background job); this test wants SIGINT delivered
    # even when the suite itself runs as such a job.
    process = subprocess.Popen(
        [sys.executable, '-m', 'uvms_recording.replay', str(path), '--loop'],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd=REPO,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        _wait_for_output(process, 'replaying', timeout_s=60.0)
        time.sleep(0.5)
        process.send_signal(signum)
        output, _ = process.communicate(timeout=30.0)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 0, output
    assert '(stopped)' in output
    assert 'Traceback' not in output


def test_recorder_process_without_output_path_exits_1_naming_it() -> None:
    """Started without output_path, the recorder logs the parameter and exits 1, no traceback."""
    process = _start_recorder()
    output, _ = process.communicate(timeout=60.0)
    assert process.returncode == 1
    assert "parameter 'output_path' is required" in output
    assert 'Traceback' not in output


@pytest.fixture
def context() -> Iterator[Context]:
    """An initialized rclpy context of its own, shut down after the test."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def _spin_until(executor: SingleThreadedExecutor, done: Callable[[], bool],
                timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not done():
        assert time.monotonic() < deadline, 'timed out spinning'
        executor.spin_once(timeout_sec=0.01)


def test_recorded_then_replayed_messages_reach_a_subscriber_unchanged(
    context: Context, tmp_path: Path
) -> None:
    """Publish -> record -> replay -> subscribe gives back the messages first published.

    Compared as messages: Fast DDS's wire bytes differ from serialize_message's in padding
    and trailing bytes (measured), so the bytes of a publication are not a stable reference.
    """
    path = tmp_path / 'run.mcap'
    recorder = RecorderNode(context=context, namespace='/uvms',
                            parameter_overrides=[Parameter('output_path', value=str(path))])
    talker = Node('talker', namespace='/uvms', context=context)
    joint_states = talker.create_publisher(JointState, 'joint_states', 10)
    wrench = talker.create_publisher(WrenchStamped, 'wrench', 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(recorder)
    published: dict[str, list[bytes]] = {'/uvms/joint_states': [], '/uvms/wrench': []}
    for k in range(30):
        joint = JointState(name=['joint_1'], position=[0.01 * k])
        force = WrenchStamped()
        force.wrench.force.x = 150.0 + k
        joint_states.publish(joint)
        wrench.publish(force)
        published['/uvms/joint_states'].append(serialize_message(joint))
        published['/uvms/wrench'].append(serialize_message(force))
        executor.spin_once(timeout_sec=0.0)
    _spin_until(executor, lambda: recorder.recorder.message_count == 60)
    executor.remove_node(recorder)
    recorder.destroy_node()

    received: dict[str, list[bytes]] = {topic: [] for topic in published}
    listener = Node('listener', context=context)
    keep_all = QoSProfile(history=HistoryPolicy.KEEP_ALL, depth=1,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE)
    for topic, cls in (('/uvms/joint_states', JointState), ('/uvms/wrench', WrenchStamped)):
        listener.create_subscription(cls, topic, lambda d, t=topic: received[t].append(d),
                                     keep_all, raw=True)
    executor.add_node(listener)
    replay = ReplayNode(open_recording(path), list(published), context=context)
    replay.play(ReplayOptions(rate=1e6))
    _spin_until(executor, lambda: sum(map(len, received.values())) == 60)
    classes = {'/uvms/joint_states': JointState, '/uvms/wrench': WrenchStamped}
    for topic, cls in classes.items():
        assert ([deserialize_message(d, cls) for d in received[topic]]
                == [deserialize_message(d, cls) for d in published[topic]])


@pytest.fixture(scope='module')
def lockstep_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """0.3 s of the case1_ke1e4 scenario run in lockstep and recorded."""
    path = tmp_path_factory.mktemp('rerun') / 'case1.mcap'
    scenario = load_scenario(REPO / 'config' / 'scenarios' / 'case1_ke1e4.yaml')
    run_graph(build_graph(scenario.with_changes(duration_s=0.3), 'lockstep', output_path=path))
    return path


def test_rerun_controller_reproduces_its_recorded_outputs_exactly(
    lockstep_recording: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Re-running the unchanged controller gives every recorded output back, deviation 0."""
    status = replay.main([str(lockstep_recording), '--rerun-controller', '--tolerance', '0'])
    out = capsys.readouterr().out
    assert status == 0, out
    assert 'PASS' in out
    recording = open_recording(lockstep_recording)
    report = rerun.rerun_controller(recording, tolerance=0.0)
    outputs = ('/uvms/command/generalized_force', '/uvms/controller/state')
    assert report.compared == sum(recording.topics[t].message_count for t in outputs)
    assert {d.max_abs for d in report.deviations.values()} == {0.0}


def test_rerun_with_changed_gains_reports_the_deviation_and_fails(
    lockstep_recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A --params-file that changes the gains makes the re-run deviate and exit 1."""
    gains = tmp_path / 'gains.yaml'
    gains.write_text('/uvms/controller:\n  ros__parameters:\n'
                     '    impedance.stiffness_n_m: [4000.0, 4000.0, 4000.0]\n'
                     '    hybrid.position_kp: [150.0, 150.0, 150.0]\n')
    status = replay.main([str(lockstep_recording), '--rerun-controller',
                          '--params-file', str(gains)])
    out = capsys.readouterr().out
    assert status == 1
    assert 'FAIL' in out
    assert 'vehicle force        N' in out
    assert '> tolerance' in out
    assert str(gains) in out


def test_rerun_on_a_cut_recording_compares_what_is_left(
    lockstep_recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A cut recording re-runs up to its last complete chunk, with a 'cut short' warning."""
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(lockstep_recording.read_bytes()[:-300])
    status = replay.main([str(cut), '--rerun-controller'])
    captured = capsys.readouterr()
    assert status == 0, captured.out + captured.err
    assert 'cut short' in captured.err
    assert 'PASS' in captured.out


def test_rerun_needs_recorded_controller_outputs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A recording without controller commands gives a clear error and exit 1."""
    path = tmp_path / 'inputs_only.mcap'
    with McapRecorder(path) as recorder:
        recorder.add_topic('/uvms/wrench', 'geometry_msgs/msg/WrenchStamped')
    status = replay.main([str(path), '--rerun-controller'])
    err = capsys.readouterr().err
    assert status == 1
    assert 'no command/generalized_force topic' in err
    assert 'Traceback' not in err
