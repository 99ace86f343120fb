"""Integration: the recorder as a process closes its MCAP on signals; record then replay."""

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
from rclpy.serialization import serialize_message
from sensor_msgs.msg import JointState
from uvms_bringup.recorder_node import DEFAULT_TOPICS, RecorderNode
from uvms_bringup.recording import open_recording
from uvms_bringup.replay import ReplayNode, ReplayOptions

REPO = Path(__file__).resolve().parents[2]
SOURCES = [REPO / 'src' / name for name in
           ('uvms_bringup', 'uvms_model', 'uvms_sim', 'uvms_control', 'ros2_compat')]


def _start_recorder(path: Path) -> subprocess.Popen[str]:
    """Start `python -m uvms_bringup.recorder_node` (compat runtime) writing to path."""
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([*map(str, SOURCES), env.get('PYTHONPATH', '')])
    # An installed stack (pip install, editable too) activates ros2_compat through its .pth.
    return subprocess.Popen(
        [sys.executable, '-m', 'uvms_bringup.recorder_node', '--ros-args',
         '-r', '__ns:=/uvms', '-p', f'output_path:={path}'],
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
        assert remaining > 0, f'no {text!r} from the recorder; output so far:\n{seen}'
        if selector.select(timeout=remaining):
            line = process.stdout.readline()
            if not line:
                pytest.fail(f'recorder exited early ({process.wait()}):\n{seen}')
            seen += line
    return seen


@pytest.mark.parametrize('signum', [signal.SIGTERM, signal.SIGINT], ids=['SIGTERM', 'SIGINT'])
def test_signal_closes_the_recorder_process_with_a_complete_file(
    tmp_path: Path, signum: signal.Signals
) -> None:
    """SIGTERM or SIGINT makes the recorder exit 0 leaving an MCAP with Statistics."""
    path = tmp_path / 'run.mcap'
    process = _start_recorder(path)
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
    """Publish -> record -> replay -> subscribe gives back the bytes first published."""
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
    assert received == published
