"""The robot process (``--compose robot``): devices, estimator, controller, allocator in one loop.

A device's reading reaches the controller, and the command the device, by function calls in
the loop's period (its own counters say so, and no node of the process subscribes on DDS to
a topic the loop delivers); the device topics still reach the recorder; each device is put
back on SIGINT and SIGTERM of the robot process, as by its bridge's own process.
"""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import pytest
from mcap.reader import make_reader
from uvms_hardware.hardware_config import load_alpha5
from uvms_hardware.reach_protocol import Mode, PacketId, encode_current
from uvms_twins.alpha5_twin import Alpha5Twin
from uvms_twins.netft_twin import NetFtTwin

#: Edges the loop must serve by function calls: (topic, the node it reaches).
DIRECT_EDGES = (
    ('/uvms/joint_states', 'controller'), ('/uvms/wrench', 'controller'),
    ('/uvms/imu', 'estimator'), ('/uvms/depth', 'estimator'),
    ('/uvms/odometry/filtered', 'controller'),
    ('/uvms/command/generalized_force', 'thruster_allocator'),
    ('/uvms/command/actuators', 'alpha5_bridge'), ('/uvms/command/actuators', 'ardusub_bridge'))
#: Device topics the recorder still gets on DDS.
RECORDED = ('/uvms/joint_states', '/uvms/wrench', '/uvms/imu', '/uvms/depth', '/uvms/dvl',
            '/uvms/command/actuators', '/uvms/thrusters/state')


def child_env() -> dict[str, str]:
    """This interpreter's import path for the child processes."""
    return dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p),
                PYTHONUNBUFFERED='1')


def direct_counts(log: str) -> Counter[tuple[str, str]]:
    """The loop's deliveries per (topic, node) from its closing line."""
    [line] = [ln for ln in log.splitlines() if 'robot loop:' in ln]
    edges = line.split('direct: ', 1)[1].split(';', 1)[0]
    return Counter({(m[1], m[2]): int(m[3])
                    for m in re.finditer(r'(\S+)->(\S+) (\d+)', edges)})


def test_the_twin_stand_runs_in_one_robot_loop(tmp_path: Path) -> None:
    """Commands reach the twins and states come back through the loop, none through DDS."""
    output = tmp_path / 'loop.mcap'
    process = subprocess.run(
        [sys.executable, '-m', 'uvms_cli.cli', 'launch', 'idle_wall', '--robot',
         'bluerov2_alpha5', '--hardware', 'twin', '--compose', 'robot', '--duration', '5',
         '--real-time-factor', '0.25', '--output', str(output)],
        env=child_env(), capture_output=True, text=True, timeout=240, stdin=subprocess.DEVNULL)
    assert process.returncode == 0, process.stderr[-3000:]
    log = process.stderr
    counts = direct_counts(log)
    missing = [edge for edge in DIRECT_EDGES if counts[edge] == 0]
    assert not missing, (missing, counts)
    assert 'DDS inputs on direct topics: none' in log, log[-3000:]
    # One process for the robot side: no bridge, estimator or controller process of its own.
    assert not re.search(r'\[(alpha5_bridge|controller|estimator)-\d+\]', log)
    recorded: Counter[str] = Counter()
    with output.open('rb') as stream:
        for _, channel, _ in make_reader(stream).iter_messages():
            recorded[channel.topic] += 1
    assert not [t for t in RECORDED if recorded[t] == 0], dict(recorded)
    # (The vehicle's disarm is confirmed once the launcher stops the robot process before
    # the twins, as it stops the bridge processes: launch_layout.holds_bridge.)
    for words in ('alpha5_bridge: every joint VELOCITY 0', 'netft_bridge: RDT stream stopped',
                  'ardusub_bridge: thrusters neutral (1500 us)', 'RC overrides released'):
        assert words in log, log[-3000:]


def start_robot_process(alpha5_port: int, netft_port: int) -> subprocess.Popen[str]:
    """The robot process with the arm and wrist-sensor bridges, run by the loop."""
    def group(name: str, *parameters: str) -> list[str]:
        values = [a for p in ('robot_name:=bluerov2_alpha5', *parameters) for a in ('-p', p)]
        return [name, '--ros-args', '-r', '__ns:=/uvms', *values]

    return subprocess.Popen(
        [sys.executable, '-m', 'uvms_bringup.composed', '--loop',
         *group('alpha5_bridge', f'connection:=udp:127.0.0.1:{alpha5_port}'), '--and',
         *group('netft_bridge', f'address:=127.0.0.1:{netft_port}')],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=child_env())


def wait_for(done: object, timeout_s: float = 30.0) -> None:
    """Poll ``done()`` until true, or fail."""
    deadline = time.monotonic() + timeout_s
    while not done():  # type: ignore[operator]
        assert time.monotonic() < deadline, 'timed out'
        time.sleep(0.05)


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_the_robot_process_puts_every_device_back_on_a_signal(signum: int) -> None:
    """A driven arm and a streaming sensor in the loop: Standby and stream stopped; exit 0."""
    with (Alpha5Twin(load_alpha5('bluerov2_alpha5'), port=0) as arm,
          NetFtTwin(port=0, rate_hz=100.0) as sensor):
        robot = start_robot_process(arm.port, sensor.port)
        try:
            wait_for(lambda: any(p.packet_id == PacketId.MODE
                                 for _, p in arm.received(0x02)))  # activated: Standby sent
            wait_for(lambda: sensor.streaming)
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
                sock.sendto(encode_current(0x05, 200.0), ('127.0.0.1', arm.port))
            wait_for(lambda: arm.joint_commands()['joint_1'][0] == Mode.CURRENT)
            time.sleep(0.3)
            robot.send_signal(signum)
            output, _ = robot.communicate(timeout=20)
        finally:
            if robot.poll() is None:
                robot.kill()
        assert robot.returncode == 0, output
        assert 'robot loop at' in output and '2 device timers' in output, output
        assert {mode for mode, _ in arm.joint_commands().values()} == {Mode.STANDBY}
        for device_id in (5, 4, 3, 2):  # each change is read back: REQUESTs left out
            changes = [p.packet_id for _, p in arm.received(device_id)
                       if p.packet_id != PacketId.REQUEST]
            assert changes[-2:] == [PacketId.VELOCITY, PacketId.MODE]
        assert not sensor.streaming
