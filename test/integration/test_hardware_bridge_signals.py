"""The bridge processes leave their devices at rest on SIGINT and SIGTERM."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from uvms_hardware.hardware_config import load_alpha5
from uvms_hardware.reach_protocol import Mode, PacketId, encode_current
from uvms_twins.alpha5_twin import Alpha5Twin
from uvms_twins.netft_twin import NetFtTwin

REPO = Path(__file__).resolve().parents[2]
SOURCES = [REPO / 'src' / name for name in
           ('uvms_common', 'uvms_description', 'uvms_model', 'uvms_hardware')]


def start_bridge(entry: str, *parameters: str) -> subprocess.Popen[str]:
    """Start a bridge's console-script entry with ``-p`` parameters, in /uvms."""
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([*map(str, SOURCES), env.get('PYTHONPATH', '')])
    args = [arg for p in ('robot_name:=bluerov2_alpha5', *parameters) for arg in ('-p', p)]
    code = f'from uvms_hardware.entry_points import {entry}; {entry}()'
    return subprocess.Popen([sys.executable, '-c', code, '--ros-args', '-r', '__ns:=/uvms',
                             *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env=env, cwd=REPO)


def wait_for(done: object, timeout_s: float = 30.0) -> None:
    """Poll ``done()`` until true, or fail."""
    deadline = time.monotonic() + timeout_s
    while not done():  # type: ignore[operator]
        assert time.monotonic() < deadline, 'timed out'
        time.sleep(0.05)


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_alpha5_bridge_leaves_every_device_in_standby(signum: int) -> None:
    """A driven arm: on the signal, VELOCITY 0 then MODE Standby to every joint; exit 0."""
    with Alpha5Twin(load_alpha5('bluerov2_alpha5'), port=0) as twin:
        bridge = start_bridge('alpha5_bridge', f'connection:=udp:127.0.0.1:{twin.port}')
        try:
            wait_for(lambda: any(p.packet_id == PacketId.MODE
                                 for _, p in twin.received(0x02)))  # activated: Standby sent
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
                sock.sendto(encode_current(0x05, 200.0), ('127.0.0.1', twin.port))
            wait_for(lambda: twin.joint_commands()['joint_1'][0] == Mode.CURRENT)
            bridge.send_signal(signum)
            output, _ = bridge.communicate(timeout=15)
        finally:
            if bridge.poll() is None:
                bridge.kill()
        assert bridge.returncode == 0, output
        assert {mode for mode, _ in twin.joint_commands().values()} == {Mode.STANDBY}
        for device_id in (5, 4, 3, 2):  # each change is read back: REQUESTs left out
            changes = [p.packet_id for _, p in twin.received(device_id)
                       if p.packet_id != PacketId.REQUEST]
            assert changes[-2:] == [PacketId.VELOCITY, PacketId.MODE]


def test_netft_bridge_stops_the_stream_on_sigterm() -> None:
    """On SIGTERM the bridge sends the stop command: the twin stops streaming; exit 0."""
    with NetFtTwin(port=0, rate_hz=100.0) as twin:
        bridge = start_bridge('netft_bridge', f'address:=127.0.0.1:{twin.port}')
        try:
            wait_for(lambda: twin.streaming)
            time.sleep(0.3)
            bridge.send_signal(signal.SIGTERM)
            output, _ = bridge.communicate(timeout=15)
        finally:
            if bridge.poll() is None:
                bridge.kill()
        assert bridge.returncode == 0, output
        assert not twin.streaming
