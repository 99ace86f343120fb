"""The live view: ``uvms run --foxglove`` serves the running graph to a Foxglove client.

The client speaks Foxglove's WebSocket protocol as the app does (``foxglove_client``);
what it receives is decoded with rosbags' typestore, an oracle independent of rclpy, and
compared with the recording the same run wrote.
"""

from __future__ import annotations

import itertools
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pinocchio as pin
import pytest
from foxglove_client import FoxgloveClient, connect_when_up
from rosbags.highlevel import AnyReader
from uvms_recording.typestore import uvms_typestore

REPO = Path(__file__).resolve().parents[2]
WRENCH = '/uvms/wrench'
ADVERTISED = {
    '/tf': 'tf2_msgs/msg/TFMessage',
    '/robot_description': 'std_msgs/msg/String',
    WRENCH: 'geometry_msgs/msg/WrenchStamped',
    '/uvms/controller/state': 'uvms_msgs/msg/ControllerState',
    '/uvms/markers': 'visualization_msgs/msg/MarkerArray',
}
WRENCHES = 100


def free_port() -> int:
    """A TCP port of 127.0.0.1 that nothing listens on now."""
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return int(probe.getsockname()[1])


def own_domain() -> str:
    """A ROS domain of the run's own: the module's moved 35 along its lane's range.

    Never above 100: those domains' ports are in Linux's ephemeral range, where a participant
    can take the datagrams of a UDP twin of a test running beside (tools/run_suite.py).
    """
    low, high = (int(x) for x in os.environ.get('UVMS_TEST_DOMAINS', '1-100').split('-'))
    module = int(os.environ.get('ROS_DOMAIN_ID', str(low)))
    return str(low + (module - low + 35) % (high - low + 1))


def start_run(*args: str) -> subprocess.Popen[str]:
    """``uvms run`` in a child process on a DDS domain of its own."""
    env = dict(os.environ, ROS_DOMAIN_ID=own_domain(),
               PYTHONUNBUFFERED='1')
    return subprocess.Popen([sys.executable, '-m', 'uvms_cli.cli', 'run', *args],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=env, cwd=REPO)


@dataclass
class LiveRun:
    """What a client received from a run, and what the run recorded and printed."""

    client: FoxgloveClient
    received: dict[str, list[tuple[int, bytes]]]
    recording: Path
    status: int
    output: str


@pytest.fixture(scope='module')
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveRun]:
    """A lockstep run watched live: a client takes WRENCHES wrenches, leaves, the run goes on.

    Then SIGINT ends the run (it would run 60 s simulated), closing the recording.
    """
    recording = tmp_path_factory.mktemp('live') / 'live.mcap'
    port = free_port()
    process = start_run('case1_ke1e4', '--duration', '60', '--output', str(recording),
                        '--foxglove', str(port))
    try:
        client = connect_when_up(f'ws://127.0.0.1:{port}')
        client.read_advertisements(set(ADVERTISED))
        client.subscribe(WRENCH, '/robot_description')
        received = client.messages({WRENCH: WRENCHES, '/robot_description': 1})
        client.close()
        # The run goes on after the client left: more wrenches reach the recording.
        more = connect_when_up(f'ws://127.0.0.1:{port}')
        more.read_advertisements({WRENCH})
        more.subscribe(WRENCH)
        later = more.messages({WRENCH: 1})[WRENCH]
        more.close()
        received[f'{WRENCH} (second client)'] = later
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=120.0)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    yield LiveRun(client, received, recording, process.returncode, output)


def recorded(path: Path, topic: str) -> dict[int, object]:
    """Messages of a recorded topic by header stamp (ns), decoded with rosbags."""
    result = {}
    with AnyReader([path], default_typestore=uvms_typestore()) as reader:
        connections = [c for c in reader.connections if c.topic == topic]
        for connection, _, raw in reader.messages(connections=connections):
            msg = reader.deserialize(raw, connection.msgtype)
            result[msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec] = msg
    return result


def test_server_advertises_the_graph_topics_with_ros2msg_schemas(live: LiveRun) -> None:
    """/tf, /robot_description, the wrench and the controller state, CDR with ros2msg text."""
    for topic, type_name in ADVERTISED.items():
        channel = live.client.channels[topic]
        assert channel['encoding'] == 'cdr', topic
        assert channel['schemaEncoding'] == 'ros2msg', topic
        assert channel['schemaName'] == type_name, topic
    # The schema text carries the dependencies, as Foxglove's ros2msg parser wants them.
    assert 'MSG: geometry_msgs/Wrench' in live.client.channels[WRENCH]['schema']
    assert 'time' in live.client.server_info['capabilities']


def test_received_wrenches_decode_as_cdr_to_the_recorded_values(live: LiveRun) -> None:
    """Each wrench the client received is, by stamp, the one the recorder wrote."""
    store = uvms_typestore()
    recorded_wrenches = recorded(live.recording, WRENCH)
    frames = live.received[WRENCH]
    assert len(frames) == WRENCHES
    stamps = []
    for _, payload in frames:
        msg = store.deserialize_cdr(payload, 'geometry_msgs/msg/WrenchStamped')
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        stamps.append(stamp)
        expected = recorded_wrenches[stamp]
        assert msg.header.frame_id == expected.header.frame_id == 'ft_sensor_link'
        for part in ('force', 'torque'):
            got, want = getattr(msg.wrench, part), getattr(expected.wrench, part)
            assert (got.x, got.y, got.z) == (want.x, want.y, want.z), (stamp, part)
    # In order, one per control step (2 ms), none lost while the client was subscribed.
    assert stamps == sorted(stamps)
    assert all(b - a == 2_000_000 for a, b in itertools.pairwise(stamps))


def test_a_late_client_receives_the_latched_robot_description(live: LiveRun) -> None:
    """/robot_description, published once at start, still reaches a client joining later."""
    ((_, payload),) = live.received['/robot_description']
    text = uvms_typestore().deserialize_cdr(payload, 'std_msgs/msg/String').data
    assert ET.fromstring(text).get('name') == 'uvms'
    model = pin.buildModelFromXML(text)
    assert [name for name in model.names if name.startswith('joint_')] == [
        'joint_1', 'joint_2', 'joint_3']


def test_a_client_leaving_changes_nothing_in_the_run(live: LiveRun) -> None:
    """After the first client left, a second one still got wrenches; SIGINT ends it with 130."""
    assert live.received[f'{WRENCH} (second client)']
    first_last = max(stamp for stamp, _ in live.received[WRENCH])
    assert max(recorded(live.recording, WRENCH)) > first_last
    assert live.status == 130, live.output
    assert 'Traceback' not in live.output
    assert 'left; the run goes on' in live.output


def test_port_in_use_leaves_the_run_unchanged_with_one_log_line(tmp_path: Path) -> None:
    """With the port taken, the run completes and says so once; the recording is complete."""
    with socket.socket() as taken:
        taken.bind(('127.0.0.1', 0))
        taken.listen()
        port = taken.getsockname()[1]
        process = start_run('case1_ke1e4', '--duration', '0.2', '--output',
                            str(tmp_path / 'run.mcap'), '--foxglove', str(port))
        output, _ = process.communicate(timeout=300.0)
    assert process.returncode == 0, output
    assert output.count(f'no Foxglove live view: cannot serve ws://127.0.0.1:{port}') == 1
    assert 'Address already in use' in output
    assert 'Traceback' not in output
    assert len(recorded(tmp_path / 'run.mcap', WRENCH)) == 101


def test_foxglove_host_without_foxglove_is_a_usage_error() -> None:
    """--foxglove-host alone names the missing flag and exits 2."""
    process = start_run('case1_ke1e4', '--foxglove-host', '192.0.2.1')
    output, _ = process.communicate(timeout=120.0)
    assert process.returncode == 2
    assert '--foxglove-host needs --foxglove' in output


def test_launch_with_foxglove_serves_the_process_graph(tmp_path: Path) -> None:
    """``uvms launch --foxglove``: a foxglove_server process serves the real-time graph."""
    port = free_port()
    env = dict(os.environ, ROS_DOMAIN_ID=own_domain(),
               PYTHONUNBUFFERED='1')
    process = subprocess.Popen(
        [sys.executable, '-m', 'uvms_cli.cli', 'launch', 'free_motion', '--duration', '0',
         '--foxglove', str(port)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env=env, cwd=REPO)
    try:
        client = connect_when_up(f'ws://127.0.0.1:{port}')
        client.read_advertisements(set(ADVERTISED))
        client.subscribe(WRENCH, '/tf_static')
        received = client.messages({WRENCH: 5, '/tf_static': 1})
        client.close()
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=120.0)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    store = uvms_typestore()
    for _, payload in received[WRENCH]:
        msg = store.deserialize_cdr(payload, 'geometry_msgs/msg/WrenchStamped')
        assert msg.header.frame_id == 'ft_sensor_link'
    ((_, payload),) = received['/tf_static']
    static = store.deserialize_cdr(payload, 'tf2_msgs/msg/TFMessage')
    assert {'map', 'map_ned'} <= {t.header.frame_id for t in static.transforms} | {
        t.child_frame_id for t in static.transforms}
    assert process.returncode == 130, output
    assert re.search(r'\[foxglove_server-\d+\]', output), output  # its own process's lines
    assert 'Traceback' not in output


@dataclass
class ServerLog:
    """The log of a foxglove_server node that two clients joined and left, by client address."""

    dropped: str
    quiet: str
    status: int
    output: str

    def lines_of(self, address: str) -> list[str]:
        """The output lines that name a client address."""
        return [line for line in self.output.splitlines() if address in line]


def wait_for(lines: list[str], text: str, timeout_s: float = 60.0) -> None:
    """Wait until a line holding ``text`` has been read."""
    deadline = time.monotonic() + timeout_s
    while not any(text in line for line in list(lines)):
        assert time.monotonic() < deadline, f'no line with {text!r} in:\n' + ''.join(lines)
        time.sleep(0.05)


@pytest.fixture(scope='module')
def server_log() -> Iterator[ServerLog]:
    """A foxglove_server node alone, two clients in turn, then SIGINT.

    The first subscribes and drops without a closing handshake (as a killed tab does); the
    second connects and closes without subscribing.
    """
    port = free_port()
    env = dict(os.environ, ROS_DOMAIN_ID=own_domain(),
               PYTHONUNBUFFERED='1')
    process = subprocess.Popen(
        [sys.executable, '-m', 'uvms_viz.foxglove_server_node', '--ros-args',
         '-r', '__ns:=/uvms', '-p', f'port:={port}'],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd=REPO)
    lines: list[str] = []
    assert process.stdout is not None
    reader = threading.Thread(target=lambda: lines.extend(process.stdout or ()), daemon=True)
    reader.start()
    try:
        url = f'ws://127.0.0.1:{port}'
        client = connect_when_up(url)
        client.read_advertisements({WRENCH})
        client.subscribe(WRENCH)
        host, client_port = client.connection.socket.getsockname()[:2]
        dropped = f'{host}:{client_port}'
        wait_for(lines, f'{dropped} joined')
        # A killed tab: the kernel ends the TCP connection, no WebSocket close frame is sent.
        client.connection.socket.shutdown(socket.SHUT_RDWR)
        client.connection.socket.close()
        wait_for(lines, f'{dropped} left')
        quiet_client = connect_when_up(url)
        quiet_client.read_advertisements({WRENCH})
        host, client_port = quiet_client.connection.socket.getsockname()[:2]
        quiet = f'{host}:{client_port}'
        quiet_client.close()
        wait_for(lines, f'{quiet} left')
        process.send_signal(signal.SIGINT)
        process.wait(timeout=60.0)
        reader.join(timeout=10.0)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    yield ServerLog(dropped, quiet, process.returncode, ''.join(lines))


#: A node log line as rclpy formats it: [LEVEL] [time] [logger]: message.
NODE_LINE = re.compile(r'^\[(INFO|WARN|ERROR|DEBUG)\] \[[0-9.]+\] \[uvms\.foxglove_server\]: ')


def test_a_dropped_connection_is_one_formatted_line(server_log: ServerLog) -> None:
    """A client gone without a closing handshake: joined, then one 'left: connection dropped'."""
    joined, left = server_log.lines_of(server_log.dropped)
    assert NODE_LINE.match(joined) and joined.endswith(f'Foxglove client {server_log.dropped} '
                                                       'joined')
    assert NODE_LINE.match(left), left
    assert f'Foxglove client {server_log.dropped} left: connection dropped (' in left
    assert left.endswith('; the run goes on')
    unformatted = [line for line in server_log.output.splitlines()
                   if line.strip() and not NODE_LINE.match(line)]
    assert not unformatted, server_log.output
    assert server_log.status == 0, server_log.output


def test_a_client_that_never_subscribed_joins_and_leaves(server_log: ServerLog) -> None:
    """A client that only connected and closed: one join line and one leave line."""
    lines = [NODE_LINE.sub('', line) for line in server_log.lines_of(server_log.quiet)]
    assert lines == [f'Foxglove client {server_log.quiet} joined',
                     f'Foxglove client {server_log.quiet} left; the run goes on']
