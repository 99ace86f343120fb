"""Tests of replaying a recording onto the graph in one process, and of `uvms replay` errors."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from recording_samples import GRAPH_TOPICS, graph_messages
from uvms_recording.mcap_reader import open_recording
from uvms_recording.mcap_writer import McapRecorder, QosDescription
from uvms_recording.recorder_node import message_class
from uvms_recording.replay import ReplayNode, ReplayOptions, main, select_topics

N_STEPS = 20


@pytest.fixture
def context() -> Iterator[Context]:
    """An initialized rclpy context of its own, shut down after the test."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


@pytest.fixture
def recording_path(tmp_path: Path) -> Path:
    """A recording of N_STEPS lockstep steps of every graph topic, plus a latched /tf_static."""
    path = tmp_path / 'run.mcap'
    with McapRecorder(path, chunk_size=4096) as recorder:
        for topic, type_name in GRAPH_TOPICS:
            recorder.add_topic(topic, type_name)
        for topic, _, t_ns, data in graph_messages(N_STEPS):
            recorder.write(topic, data, t_ns)
    return path


class Listener(Node):
    """Subscribes raw to topics and keeps what arrives, per topic."""

    def __init__(self, context: Context, topics: dict[str, str], qos: QoSProfile) -> None:
        super().__init__('listener', context=context)
        self.received: dict[str, list[bytes]] = {topic: [] for topic in topics}
        for topic, type_name in topics.items():
            self.create_subscription(message_class(type_name), topic,
                                     lambda data, t=topic: self.received[t].append(data),
                                     qos, raw=True)

    def count(self) -> int:
        """Messages received on all topics."""
        return sum(len(values) for values in self.received.values())


def _keep_all() -> QoSProfile:
    return QoSProfile(history=HistoryPolicy.KEEP_ALL, depth=1,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


def test_replay_publishes_the_recorded_bytes_in_order(context: Context,
                                                      recording_path: Path) -> None:
    """A subscriber receives, per topic, exactly the recorded bytes in recorded order."""
    recording = open_recording(recording_path)
    options = ReplayOptions(rate=1e6, clock=True)
    topics = select_topics(recording, options)
    listener = Listener(context, {t: recording.topics[t].type_name for t in topics}, _keep_all())
    replay = ReplayNode(recording, topics, context=context)
    published = replay.play(options)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(listener)
    deadline = time.monotonic() + 10.0
    while listener.count() < published and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.01)
    assert published == N_STEPS * len(GRAPH_TOPICS)
    for topic in topics:
        assert listener.received[topic] == [m.data for m in recording.messages([topic])]


def test_replay_offers_the_recorded_qos(context: Context, tmp_path: Path) -> None:
    """A topic recorded as transient local is replayed latched: a late subscriber gets it."""
    path = tmp_path / 'tf.mcap'
    data = b'\x00\x01\x00\x00' + bytes(4)  # an empty TFMessage
    with McapRecorder(path) as recorder:
        recorder.add_topic('/tf_static', 'tf2_msgs/msg/TFMessage',
                           QosDescription(durability='transient_local', depth=1))
        recorder.write('/tf_static', data, 0)
    recording = open_recording(path)
    replay = ReplayNode(recording, ['/tf_static'], context=context)
    replay.play(ReplayOptions())
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    listener = Listener(context, {'/tf_static': 'tf2_msgs/msg/TFMessage'}, latched)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(listener)
    deadline = time.monotonic() + 5.0
    while listener.count() < 1 and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.01)
    assert listener.received['/tf_static'] == [data]


def test_start_offset_skips_the_beginning(context: Context, recording_path: Path) -> None:
    """--start S publishes only messages logged S seconds or more after the first."""
    recording = open_recording(recording_path)
    replay = ReplayNode(recording, ['/uvms/wrench'], context=context)
    published = replay.play(ReplayOptions(rate=1e6, start_s=0.010))
    assert published == N_STEPS - 10


def test_cli_replays_a_cut_file_with_a_warning(recording_path: Path, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """`uvms replay` on a cut file warns 'cut short', replays what is left and exits 0."""
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(recording_path.read_bytes()[: recording_path.stat().st_size // 2])
    status = main([str(cut), '--rate', '1000'])
    err = capsys.readouterr().err
    assert status == 0
    assert 'cut short' in err
    assert 'Traceback' not in err


def test_cli_reports_a_file_that_is_not_mcap(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    """`uvms replay` on garbage prints one clear error and exits 1, without a traceback."""
    garbage = tmp_path / 'garbage.mcap'
    garbage.write_bytes(b'\x00garbage' * 100)
    status = main([str(garbage)])
    err = capsys.readouterr().err
    assert status == 1
    assert err.startswith('uvms replay: error: ')
    assert 'not an MCAP file' in err
    assert 'Traceback' not in err


@pytest.mark.parametrize('arguments', [['--rate', '0'], ['--rate', 'nan'],
                                       ['--tolerance', '-1'], ['--start', '-2']])
def test_cli_rejects_invalid_numbers(recording_path: Path, arguments: list[str],
                                     capsys: pytest.CaptureFixture[str]) -> None:
    """Invalid numeric options exit 2 with a message naming the option."""
    status = main([str(recording_path), *arguments])
    assert status == 2
    assert arguments[0] in capsys.readouterr().err


def test_cli_rejects_an_unknown_topic(recording_path: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    """Asking for a topic the recording lacks exits 1 and lists the recorded topics."""
    status = main([str(recording_path), '--topics', '/nope'])
    err = capsys.readouterr().err
    assert status == 1
    assert '/nope' in err
    assert '/uvms/wrench' in err


def test_cli_refuses_to_rerun_a_real_time_recording(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """--rerun-controller on a recording made in real time exits 1 saying it needs lockstep."""
    path = tmp_path / 'realtime.mcap'
    metadata = {'scenario': 'free_motion', 'seed': '1', 'parameters': '', 'mode': 'realtime'}
    with McapRecorder(path, metadata=metadata) as recorder:
        recorder.add_topic('/uvms/command/generalized_force', 'uvms_msgs/msg/GeneralizedForce')
    status = main([str(path), '--rerun-controller'])
    err = capsys.readouterr().err
    assert status == 1
    assert 'needs a lockstep recording' in err
