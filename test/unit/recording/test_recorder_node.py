"""Tests of the recorder node in one process: what the graph publishes ends up in the MCAP."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import rclpy
from builtin_interfaces.msg import Time
from geometry_msgs.msg import TransformStamped, WrenchStamped
from mcap.reader import make_reader
from rclpy.context import Context
from rclpy.exceptions import ParameterException
from rclpy.executors import Executor, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from rosbags.highlevel import AnyReader
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage
from uvms_common.node_main import make_executor
from uvms_recording.errors import RecordingError
from uvms_recording.mcap_reader import open_recording
from uvms_recording.mcap_writer import RUN_METADATA_NAME
from uvms_recording.recorded_topics import DEFAULT_TOPICS
from uvms_recording.recorder_node import RecorderNode

from uvms_msgs.msg import ContactTaskRecord, ControllerState


@pytest.fixture
def context() -> Iterator[Context]:
    """An initialized rclpy context of its own, shut down after the test."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def _recorder(context: Context, path: Path, **parameters: object) -> RecorderNode:
    overrides = [Parameter('output_path', value=str(path))]
    overrides += [Parameter(name, value=value) for name, value in parameters.items()]
    return RecorderNode(context=context, namespace='/uvms', parameter_overrides=overrides)


def _spin_until(executor: SingleThreadedExecutor, done: Callable[[], bool],
                timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not done():
        assert time.monotonic() < deadline, 'timed out spinning'
        executor.spin_once(timeout_sec=0.01)


def _wait_matched(*publishers: Any) -> None:
    deadline = time.monotonic() + 10.0
    while any(p.get_subscription_count() == 0 for p in publishers):
        assert time.monotonic() < deadline, 'the recorder never matched'
        time.sleep(0.01)


def _clock_and_wrench(context: Context) -> tuple[Any, Any]:
    """A talker's /clock and wrench publishers."""
    talker = Node('talker', namespace='/uvms', context=context)
    return (talker.create_publisher(Clock, '/clock', 10),
            talker.create_publisher(WrenchStamped, 'wrench', 10))


def _joint_state(k: int) -> JointState:
    return JointState(name=['joint_1', 'joint_2', 'joint_3'],
                      position=[0.1 * k, 0.2, 0.3], velocity=[0.0, 0.0, 0.0],
                      effort=[1.0, 2.0, float(k)])


def test_recorder_writes_the_published_bytes_of_each_topic(context: Context,
                                                           tmp_path: Path) -> None:
    """Graph topics are recorded as a raw subscriber receives them, in order, resolved names.

    The reference is an independent raw subscription: Fast DDS's wire bytes differ from
    serialize_message's in padding (measured), so those are no reference for raw recording.
    """
    path = tmp_path / 'run.mcap'
    recorder = _recorder(context, path)
    talker = Node('talker', namespace='/uvms', context=context)
    joint_states = talker.create_publisher(JointState, 'joint_states', 10)
    wrench = talker.create_publisher(WrenchStamped, 'wrench', 10)
    state = talker.create_publisher(ControllerState, 'controller/state', 10)
    received: list[tuple[str, bytes]] = []
    for topic, cls in (('/uvms/joint_states', JointState), ('/uvms/wrench', WrenchStamped),
                       ('/uvms/controller/state', ControllerState)):
        talker.create_subscription(cls, topic, lambda d, t=topic: received.append((t, d)), 100,
                                   raw=True)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(recorder)
    executor.add_node(talker)
    sent = []
    for k in range(5):
        messages = [(joint_states, '/uvms/joint_states', _joint_state(k)),
                    (wrench, '/uvms/wrench', WrenchStamped()),
                    (state, '/uvms/controller/state', ControllerState(weight=0.1 * k))]
        for publisher, topic, message in messages:
            publisher.publish(message)
            sent.append((topic, message))
    _spin_until(executor, lambda: (recorder.recorder.message_count == len(sent)
                                   and len(received) == len(sent)))
    recorder.destroy_node()
    talker.destroy_node()

    recorded = [(m.topic, m.data) for m in open_recording(path).messages()]
    for topic, cls in (('/uvms/joint_states', JointState), ('/uvms/wrench', WrenchStamped),
                       ('/uvms/controller/state', ControllerState)):
        mine = [d for t, d in recorded if t == topic]
        assert mine == [d for t, d in received if t == topic]
        assert [deserialize_message(d, cls) for d in mine] == [m for t, m in sent if t == topic]


def test_recording_decodes_with_rosbags_to_the_published_values(context: Context,
                                                                tmp_path: Path) -> None:
    """Rosbags reads back the field values that were published (independent decoder)."""
    path = tmp_path / 'run.mcap'
    recorder = _recorder(context, path)
    talker = Node('talker', namespace='/uvms', context=context)
    joint_states = talker.create_publisher(JointState, 'joint_states', 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(recorder)
    joint_states.publish(_joint_state(7))
    _spin_until(executor, lambda: recorder.recorder.message_count == 1)
    recorder.destroy_node()
    with AnyReader([path]) as reader:
        (value,) = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()]
    assert list(value.name) == ['joint_1', 'joint_2', 'joint_3']
    assert list(value.position) == pytest.approx([0.7, 0.2, 0.3])
    assert list(value.effort) == pytest.approx([1.0, 2.0, 7.0])


def test_every_default_topic_is_a_channel_of_the_file(context: Context, tmp_path: Path) -> None:
    """All graph topics, resolved in the namespace, are channels even before any message."""
    path = tmp_path / 'run.mcap'
    _recorder(context, path).destroy_node()
    expected = {spec.rpartition(':')[0] for spec in DEFAULT_TOPICS}
    expected = {t if t.startswith('/') else f'/uvms/{t}' for t in expected}
    assert set(open_recording(path).topics) == expected


def test_log_time_is_the_simulated_clock_under_use_sim_time(context: Context,
                                                            tmp_path: Path) -> None:
    """With use_sim_time, a message's log time is the last /clock the recorder received."""
    path = tmp_path / 'run.mcap'
    recorder = _recorder(context, path, use_sim_time=True)
    clock, wrench = _clock_and_wrench(context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(recorder)
    clock.publish(Clock(clock=Time(sec=5, nanosec=250)))
    _spin_until(executor, lambda: recorder.get_clock().now().nanoseconds == 5_000_000_250)
    wrench.publish(WrenchStamped())
    _spin_until(executor, lambda: recorder.recorder.message_count == 2)
    recorder.destroy_node()
    times = {m.topic: m.log_time_ns for m in open_recording(path).messages()}
    assert times['/uvms/wrench'] == 5_000_000_250


def test_recorded_clock_is_the_only_clock_subscription(context: Context, tmp_path: Path) -> None:
    """Under use_sim_time the recording's /clock subscription also sets the node clock."""
    recorder = _recorder(context, tmp_path / 'run.mcap', use_sim_time=True)
    assert sum(1 for s in recorder.subscriptions if s.topic_name == '/clock') == 1
    assert recorder.get_clock().ros_time_is_active
    recorder.destroy_node()


def test_latched_tf_static_published_before_the_recorder_is_recorded(context: Context,
                                                                      tmp_path: Path) -> None:
    """/tf_static is subscribed transient local, so an earlier latched message arrives."""
    talker = Node('talker', context=context)
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    tf_static = talker.create_publisher(TFMessage, '/tf_static', latched)
    message = TFMessage(transforms=[TransformStamped(child_frame_id='base_link_frd')])
    tf_static.publish(message)
    path = tmp_path / 'run.mcap'
    recorder = _recorder(context, path)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(recorder)
    _spin_until(executor, lambda: recorder.recorder.message_count == 1)
    recorder.destroy_node()
    (recorded,) = open_recording(path).messages()
    assert recorded.topic == '/tf_static'
    assert deserialize_message(recorded.data, TFMessage) == message


def test_topics_parameter_chooses_what_is_recorded(context: Context, tmp_path: Path) -> None:
    """Only the 'topic:type' entries of the topics parameter become channels."""
    path = tmp_path / 'run.mcap'
    _recorder(context, path, topics=['wrench:geometry_msgs/msg/WrenchStamped']).destroy_node()
    recording = open_recording(path)
    assert list(recording.topics) == ['/uvms/wrench']
    assert recording.topics['/uvms/wrench'].type_name == 'geometry_msgs/msg/WrenchStamped'


def test_run_parameters_are_stored_for_replay(context: Context, tmp_path: Path) -> None:
    """run.scenario, run.seed and run.parameters land in the 'uvms' metadata record."""
    path = tmp_path / 'run.mcap'
    yaml_text = '/uvms/controller:\n  ros__parameters:\n    force_setpoint_n: 150.0\n'
    _recorder(context, path, **{'run.scenario': 'case1_ke1e4', 'run.seed': 3,
                                'run.parameters': yaml_text}).destroy_node()
    metadata = open_recording(path).metadata[RUN_METADATA_NAME]
    assert metadata == {'scenario': 'case1_ke1e4', 'seed': '3', 'parameters': yaml_text}


def test_destroying_the_node_leaves_a_complete_file(context: Context, tmp_path: Path) -> None:
    """destroy_node() writes the summary with its Statistics record."""
    path = tmp_path / 'run.mcap'
    _recorder(context, path).destroy_node()
    with path.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    assert summary.statistics is not None


def test_missing_output_path_stops_the_node_naming_the_parameter(context: Context) -> None:
    """Without output_path the node refuses to start, naming the parameter."""
    with pytest.raises(RecordingError, match="'output_path' is required"):
        RecorderNode(context=context)


def test_invalid_compression_names_the_value_and_the_choices(context: Context,
                                                             tmp_path: Path) -> None:
    """An unknown compression stops the node with the value and the valid values."""
    with pytest.raises(RecordingError, match=r"'gzip'; valid values: zstd, lz4, none"):
        _recorder(context, tmp_path / 'x.mcap', compression='gzip')


def test_malformed_topic_entry_is_rejected(context: Context, tmp_path: Path) -> None:
    """A topics entry without ':type' stops the node naming the entry."""
    with pytest.raises(RecordingError, match="entry 'wrench'"):
        _recorder(context, tmp_path / 'x.mcap', topics=['wrench'])


def test_chunk_size_outside_its_range_stops_the_node_with_the_range(context: Context,
                                                                    tmp_path: Path) -> None:
    """chunk_size_bytes below 1024 is refused by its descriptor, naming the bounds."""
    with pytest.raises(ParameterException, match=r'chunk_size_bytes.*Min: 1024'):
        _recorder(context, tmp_path / 'x.mcap', chunk_size_bytes=5)


def test_a_recorder_nobody_closed_leaves_a_complete_file_at_exit(tmp_path: Path) -> None:
    """A process that loses its recorder node unclosed still leaves a closed MCAP file.

    A stop signal at the very end of the node's start-up leaves run_node no node to close;
    the node then closes its file at interpreter exit.
    """
    import subprocess
    import sys

    path = tmp_path / 'abandoned.mcap'
    script = (
        'import rclpy\n'
        'from rclpy.parameter import Parameter\n'
        'from uvms_recording.recorder_node import RecorderNode\n'
        'rclpy.init()\n'
        f"RecorderNode(parameter_overrides=[Parameter('output_path', value={str(path)!r})])\n"
        'raise SystemExit(0)  # the node is neither closed nor destroyed\n'
    )
    result = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                            timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    with path.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None and summary.statistics is not None


def _task_record(force_n: float) -> ContactTaskRecord:
    return ContactTaskRecord(goal_id=list(range(16)), force_n=force_n)


def test_messages_not_yet_taken_at_the_stop_are_in_the_file(context: Context,
                                                              tmp_path: Path) -> None:
    """What reached the recorder but not its callbacks (a busy recorder) is written by close.

    Measured on a loaded machine: the controller's one task record sat in the recorder's
    subscription when the stop's drain ended, and the file lost it.
    """
    path = tmp_path / 'run.mcap'
    recorder = _recorder(context, path)
    talker = Node('talker', namespace='/uvms', context=context)
    records = talker.create_publisher(ContactTaskRecord, 'controller/task_record', 10)
    joint_states = talker.create_publisher(JointState, 'joint_states', 10)
    _wait_matched(records, joint_states)
    records.publish(_task_record(150.0))
    for k in range(5):
        joint_states.publish(_joint_state(k))
    time.sleep(0.5)  # delivered to the recorder's subscriptions; its executor never spins
    recorder.destroy_node()
    topics = [message.topic for message in open_recording(path).messages()]
    assert topics.count('/uvms/controller/task_record') == 1
    assert topics.count('/uvms/joint_states') == 5


def _spin_for(executor: Executor, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.01)


def test_a_batch_logs_each_message_at_the_clock_of_its_arrival(context: Context,
                                                               tmp_path: Path) -> None:
    """A wrench that arrived between clocks 5 s and 6 s is logged at 5 s, taken after both."""
    path = tmp_path / 'run.mcap'
    recorder = _recorder(context, path, use_sim_time=True)
    clock, wrench = _clock_and_wrench(context)
    _wait_matched(clock, wrench)
    clock.publish(Clock(clock=Time(sec=5)))
    time.sleep(0.05)
    wrench.publish(WrenchStamped())
    time.sleep(0.05)
    clock.publish(Clock(clock=Time(sec=6)))
    time.sleep(0.2)  # all three arrived; nothing spun, nothing taken yet
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(recorder)
    _spin_for(executor, 0.3)  # a batch or more
    recorder.destroy_node()
    times = {(m.topic, m.log_time_ns) for m in open_recording(path).messages()}
    assert times == {('/clock', 5_000_000_000), ('/uvms/wrench', 5_000_000_000),
                     ('/clock', 6_000_000_000)}


def test_on_the_wall_clock_a_message_is_logged_at_its_arrival(context: Context,
                                                              tmp_path: Path) -> None:
    """Taken 0.3 s after it arrived, a message is still logged at its arrival."""
    path = tmp_path / 'run.mcap'
    recorder = _recorder(context, path)
    talker = Node('talker', namespace='/uvms', context=context)
    wrench = talker.create_publisher(WrenchStamped, 'wrench', 10)
    _wait_matched(wrench)
    sent_ns = time.time_ns()
    wrench.publish(WrenchStamped())
    time.sleep(0.3)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(recorder)
    _spin_for(executor, 0.3)
    recorder.destroy_node()
    (message,) = list(open_recording(path).messages())
    assert 0 <= message.log_time_ns - sent_ns < 100_000_000


@pytest.mark.parametrize('kind', ['single', 'events'])
def test_every_message_is_recorded_whichever_executor_spins_the_recorder(
        context: Context, tmp_path: Path, kind: str) -> None:
    """Batches (SingleThreadedExecutor) or callbacks (EventsExecutor): 300 of 300, in order."""
    path = tmp_path / 'run.mcap'
    recorder = _recorder(context, path)
    talker = Node('talker', namespace='/uvms', context=context)
    wrench = talker.create_publisher(WrenchStamped, 'wrench', 10)
    _wait_matched(wrench)
    executor = make_executor(kind, context=context)
    executor.add_node(recorder)
    for k in range(300):
        sent = WrenchStamped()
        sent.wrench.force.x = float(k)
        wrench.publish(sent)
        executor.spin_once(timeout_sec=0.001)
    _spin_for(executor, 0.5)
    executor.remove_node(recorder)
    recorder.destroy_node()
    forces = [deserialize_message(m.data, WrenchStamped).wrench.force.x
              for m in open_recording(path).messages()]
    assert forces == [float(k) for k in range(300)]
