"""A node whose teardown would hang in the middleware still stops at once, output closed.

The hang is made on purpose: a ``sitecustomize`` module on the children's PYTHONPATH replaces
rclpy's ``Node.destroy_node`` in the node processes named by ``UVMS_TEST_STUCK_NODES`` with
one that never returns (releasing the GIL, as a wait on a lock does, or holding it, as a
C call that never returns does), which is where the teardown was seen stuck; a node process
no longer enters that teardown (issue 48, ``uvms_common.node_main``). Times are
asserted against the launcher's escalation (5 s to SIGTERM), not against the grace period
itself, so that a machine three times slower passes too.
"""

from __future__ import annotations

import io
import os
import random
import signal
import struct
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import rclpy
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Chunk, Message
from mcap.stream_reader import StreamReader
from rclpy.context import Context
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import JointState
from uvms_bringup.processes import SIGTERM_TIMEOUT_S
from uvms_common.ros_environment import ros_environment_defaults

ros_environment_defaults()

BIN = Path(sys.executable).parent
DOMAIN_ID = random.SystemRandom().randint(101, 200)
#: Start-up of a node process or of the graph on 2 loaded cores (s).
START_TIMEOUT_S = 90.0

STUCK_TEARDOWN = '''\
"""Test only: rclpy's Node.destroy_node never returns in the nodes of UVMS_TEST_STUCK_NODES."""
import os
import sys

_stuck = [name for name in os.environ.get('UVMS_TEST_STUCK_NODES', '').split(',') if name]
if any(f'__node:={name}' in sys.argv for name in _stuck):
    import ctypes
    import threading

    import rclpy.node

    def _block_releasing_the_gil(self):
        threading.Event().wait()

    def _block_holding_the_gil(self):
        ctypes.PyDLL(None).sleep(3600)  # PyDLL keeps the GIL during the call

    holding = os.environ.get('UVMS_TEST_STUCK_HOLDS_GIL') == '1'
    rclpy.node.Node.destroy_node = (_block_holding_the_gil if holding
                                    else _block_releasing_the_gil)
'''


def stuck_environment(directory: Path, nodes: str, holds_gil: bool = False) -> dict[str, str]:
    """The children's environment: our domain, and the named nodes' teardown made to hang."""
    directory.mkdir(parents=True, exist_ok=True)
    (directory / 'sitecustomize.py').write_text(STUCK_TEARDOWN)
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([str(directory), env.get('PYTHONPATH', '')])
    env['UVMS_TEST_STUCK_NODES'] = nodes
    env['UVMS_TEST_STUCK_HOLDS_GIL'] = '1' if holds_gil else '0'
    env['ROS_DOMAIN_ID'] = str(DOMAIN_ID)
    env['PYTHONUNBUFFERED'] = '1'
    return env


@pytest.fixture
def publisher_node() -> Iterator[Node]:
    """An rclpy node of this process on the children's domain, in a Context of its own."""
    context = Context()
    rclpy.init(args=[], context=context, domain_id=DOMAIN_ID,
               signal_handler_options=SignalHandlerOptions.NO)
    node = Node('stuck_teardown_publisher', context=context)
    yield node
    node.destroy_node()
    rclpy.try_shutdown(context=context)


def wait_until(condition: Callable[[], bool], timeout_s: float, what: str,
               process: subprocess.Popen[str]) -> None:
    """Poll ``condition()`` until true; fail naming ``what`` and the process's stderr."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        if process.poll() is not None or time.monotonic() > deadline:
            if process.poll() is None:
                process.kill()
            pytest.fail(f'{what}: not within {timeout_s} s:\n{process.communicate()[1]}')
        time.sleep(0.05)


def ended_by_itself(process: subprocess.Popen[str], sig: signal.Signals,
                    ) -> tuple[float, str]:
    """Send one signal, then only wait: seconds until the process ended, and its stderr."""
    sent = time.monotonic()
    process.send_signal(sig)
    try:
        _, err = process.communicate(timeout=60.0)
    except subprocess.TimeoutExpired:
        process.kill()
        pytest.fail(f'still running 60 s after {sig.name}:\n{process.communicate()[1]}')
    return time.monotonic() - sent, err


def recorded_positions(path: Path, topic: str) -> list[float]:
    """JointState positions of a topic in a closed MCAP file (fails if it has no summary)."""
    with path.open('rb') as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None, f'{path} not closed'
        return [deserialize_message(message.data, JointState).position[0]
                for _, channel, message in reader.iter_messages() if channel.topic == topic]


@pytest.mark.parametrize('holds_gil', [False, True], ids=['gil-released', 'gil-held'])
@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_a_recorder_whose_destroy_node_would_hang_never_enters_it_and_exits_0(
    tmp_path: Path, publisher_node: Node, holds_gil: bool, sig: signal.Signals,
) -> None:
    """The MCAP is closed; the middleware's teardown, where the hang is, is never entered.

    Issue 48 (deliberate change): a node process leaves the middleware's teardown to its end
    (``uvms_common.node_main``), so a ``Node.destroy_node`` that would hang (GIL released
    or held) is not called: the stop's status 0 within the grace period, no stacks. Before,
    the deadline ended it after ``TEARDOWN_GRACE_S`` (held GIL: faulthandler, status 1).
    """
    output = tmp_path / 'stuck.mcap'
    process = subprocess.Popen(
        [str(BIN / 'recorder'), '--ros-args', '-r', '__node:=recorder', '-r', '__ns:=/stuck',
         '-p', f'output_path:={output}'],
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env=stuck_environment(tmp_path / 'site', 'recorder', holds_gil))
    publisher = publisher_node.create_publisher(
        JointState, '/stuck/joint_states',
        QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
    wait_until(lambda: publisher.get_subscription_count() > 0, START_TIMEOUT_S,
               'the recorder subscribes /stuck/joint_states', process)
    for i in range(20):
        publisher.publish(JointState(name=['joint_1'], position=[0.01 * i]))
        time.sleep(0.02)
    time.sleep(0.5)
    took_s, err = ended_by_itself(process, sig)
    assert process.returncode == 0, err
    assert took_s < SIGTERM_TIMEOUT_S, f'{took_s:.1f} s:\n{err}'
    assert 'teardown still running' not in err and 'Timeout (' not in err, err
    assert 'in _block_' not in err, err
    assert recorded_positions(output, '/stuck/joint_states') == pytest.approx(
        [0.01 * i for i in range(20)])


def holds_a_chunk(path: Path) -> bool:
    """Whether the recording being written holds a complete chunk: messages were recorded."""
    if not path.exists():
        return False
    try:
        return any(isinstance(record, Chunk) for record in
                   StreamReader(io.BytesIO(path.read_bytes()), emit_chunks=True).records)
    except (McapError, EOFError, struct.error):
        return False  # the writer's last record is not complete yet


def holds_a_message_on(path: Path, topic: str) -> bool:
    """Whether a complete chunk of the recording being written holds a message on topic.

    A chunk alone is not enough: under load the recorder may have matched the simulator's
    publishers but not yet another process's (discovery runs per pair of processes).
    """
    if not path.exists():
        return False
    channels: set[int] = set()
    try:
        for record in StreamReader(io.BytesIO(path.read_bytes())).records:
            if isinstance(record, Channel) and record.topic == topic:
                channels.add(record.id)
            elif isinstance(record, Message) and record.channel_id in channels:
                return True
    except (McapError, EOFError, struct.error):
        pass  # the writer's last record is not complete yet
    return False


def test_uvms_launch_with_stuck_teardowns_exits_130_without_sigkill(tmp_path: Path) -> None:
    """Simulator and recorder would hang in destroy_node: the launch still exits 130.

    The launcher reports no escalation (no SIGTERM, no SIGKILL), and the recording, whose
    recorder hung after closing it, is complete: summary, and messages on the graph's topics.
    """
    output = tmp_path / 'run.mcap'
    process = subprocess.Popen(
        [str(BIN / 'uvms'), 'launch', 'case1_ke1e4', '--output', str(output)],
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env=stuck_environment(tmp_path / 'site', 'simulator,recorder'))
    wait_until(lambda: holds_a_message_on(output, '/uvms/command/actuators'), START_TIMEOUT_S,
               'a recorded actuator command', process)
    time.sleep(1.0)
    took_s, err = ended_by_itself(process, signal.SIGINT)
    assert process.returncode == 130, err
    assert 'still running after' not in err, err  # the launcher escalated to nobody
    # Issue 48 (deliberate change): node processes never enter the hanging teardown.
    assert 'teardown still running' not in err, err
    assert 'Timeout (' not in err and 'in _block_' not in err, err
    assert took_s < 2 * SIGTERM_TIMEOUT_S, f'{took_s:.1f} s:\n{err}'
    with output.open('rb') as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None, 'MCAP not closed'
        counts = {summary.channels[cid].topic: n
                  for cid, n in summary.statistics.channel_message_counts.items()}
        read = sum(1 for _ in reader.iter_messages())
    assert read == summary.statistics.message_count > 0
    for topic in ('/clock', '/uvms/joint_states', '/uvms/command/actuators'):
        assert counts.get(topic, 0) > 0, counts
