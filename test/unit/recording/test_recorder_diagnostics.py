"""The recorder's /diagnostics: file, messages written, their rate, and dropped messages."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from uvms_common.node_main import make_executor
from uvms_recording.recorder_node import RecorderNode


@pytest.fixture
def context() -> Iterator[Context]:
    """An initialized rclpy context of its own, shut down after the test."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def test_recorder_reports_messages_written_and_its_file(context: Context,
                                                        tmp_path: Path) -> None:
    """'recorder: recording' counts what it wrote; closed, later messages count as dropped."""
    path = tmp_path / 'run.mcap'
    recorder = RecorderNode(context=context, namespace='/uvms', parameter_overrides=[
        Parameter('output_path', value=str(path)),
        Parameter('topics', value=['joint_states:sensor_msgs/msg/JointState'])])
    talker = Node('talker', namespace='/uvms', context=context)
    publisher = talker.create_publisher(JointState, 'joint_states', 10)
    arrays: list[DiagnosticArray] = []
    talker.create_subscription(DiagnosticArray, '/diagnostics', arrays.append, 10)
    executor = make_executor('events', context)
    for node in (recorder, talker):
        executor.add_node(node)

    def spin_until(done: Callable[[], bool], timeout_s: float = 5.0) -> None:
        deadline = time.monotonic() + timeout_s
        while not done():
            assert time.monotonic() < deadline, 'timed out spinning'
            executor.spin_once(timeout_sec=0.01)

    def status() -> tuple[DiagnosticStatus, dict[str, str]]:
        [found] = [s for s in arrays[-1].status if s.name == 'recorder: recording']
        return found, {kv.key: kv.value for kv in found.values}

    try:
        spin_until(lambda: publisher.get_subscription_count() > 0)
        for _ in range(5):
            publisher.publish(JointState(name=['joint_1'], position=[0.0]))
        spin_until(lambda: recorder.recorder.message_count == 5)
        spin_until(lambda: len(arrays) >= 1, 3.0)
        found, values = status()
        assert (found.level, found.message) == (DiagnosticStatus.OK, 'recording')
        assert values['file'] == str(path)
        assert (values['messages_written'], values['dropped']) == ('5', '0')
        recorder.close()
        publisher.publish(JointState(name=['joint_1'], position=[0.0]))
        count = len(arrays)
        spin_until(lambda: len(arrays) > count, 3.0)
        found, values = status()
        assert (found.level, found.message) == (DiagnosticStatus.WARN, 'dropping messages')
        assert (values['messages_written'], values['dropped']) == ('5', '1')
    finally:
        executor.shutdown()
        talker.destroy_node()
        recorder.destroy_node()
