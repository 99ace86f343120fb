"""With the shipped Fast DDS profile a participant binds only loopback, beside a routable address.

Each participant runs in a network namespace made by the test: besides ``lo`` it holds a veth
pair whose one end carries the documentation address ``TEST_ADDRESS`` (RFC 5737 TEST-NET-2; the
namespace has no route anywhere, and the veth pair's both ends are inside it, so whatever a
leaking participant sends stays there). The sockets come from the kernel's tables
(``/proc/<pid>/net/{udp,udp6,tcp,tcp6}``) joined with the participant's own descriptors
(``/proc/<pid>/fd``), so the check sees what DDS really bound, not what it was asked to.
"""

from __future__ import annotations

import os
import random
import shutil
import socket
import struct
import subprocess
import sys
import uuid
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import pytest
from uvms_common.ros_environment import (
    DISCOVERY_VARIABLES,
    PROFILE_VARIABLES,
    loopback_profile_path,
)

REPO = Path(__file__).resolve().parents[2]
LOOPBACK_NETNS = REPO / 'tools' / 'loopback-netns'
TEST_ADDRESS = '198.51.100.77'
DDS_MULTICAST_GROUP = '239.255.0.1'
ANY_ADDRESSES = frozenset({'0.0.0.0', '::'})
# A veth pair rather than a dummy device: not every kernel has the dummy module (this one has
# not). Both ends stay in the test's namespace.
NAMESPACE_SETUP = f"""set -e
ip link set lo up
ip link add uvmstest0 type veth peer name uvmstest1
ip addr add {TEST_ADDRESS}/24 dev uvmstest0
ip link set uvmstest0 up
ip link set uvmstest1 up
exec "$@"
"""
# One node with a publisher and a subscription of its own topic: prints `ready N` (N messages
# received, at most 5 s after start), then holds its sockets open until stdin closes.
PARTICIPANT = """
import sys, time
import rclpy
from std_msgs.msg import String

rclpy.init()
node = rclpy.create_node('loopback_probe')
received = []
publisher = node.create_publisher(String, sys.argv[1], 10)
node.create_subscription(String, sys.argv[1], lambda msg: received.append(msg.data), 10)
deadline = time.monotonic() + 5.0
while not received and time.monotonic() < deadline:
    publisher.publish(String(data='probe'))
    rclpy.spin_once(node, timeout_sec=0.05)
print('ready', len(received), flush=True)
sys.stdin.read()
node.destroy_node()
rclpy.try_shutdown()
"""
# Publishes `<pid> <n>` every 50 ms until SIGTERM (rclpy's handler shuts the context down).
PUBLISHER = """
import os, sys
import rclpy
from std_msgs.msg import String

rclpy.init()
node = rclpy.create_node('loopback_talker')
publisher = node.create_publisher(String, sys.argv[1], 10)
count = 0
while rclpy.ok():
    publisher.publish(String(data=f'{os.getpid()} {count}'))
    count += 1
    rclpy.spin_once(node, timeout_sec=0.05)
node.destroy_node()
rclpy.try_shutdown()
"""
# Prints `<own pid>` and then the first three messages received; exits 1 if none in 10 s.
SUBSCRIBER = """
import os, sys, time
import rclpy
from std_msgs.msg import String

rclpy.init()
node = rclpy.create_node('loopback_listener')
received = []
node.create_subscription(String, sys.argv[1], lambda msg: received.append(msg.data), 10)
deadline = time.monotonic() + 10.0
while len(received) < 3 and time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.1)
print('listener', os.getpid())
print('\\n'.join(received[:3]), flush=True)
node.destroy_node()
rclpy.try_shutdown()
sys.exit(0 if len(received) >= 3 else 1)
"""


class BoundSocket(NamedTuple):
    """One inet socket of a process: protocol table, local address and port."""

    protocol: str
    address: str
    port: int


@dataclass(frozen=True)
class Footprint:
    """What a participant left in its network namespace once it was running."""

    sockets: list[BoundSocket]
    groups: dict[str, set[str]]
    received: int


def decode_address(field: str) -> str:
    """Decode a /proc/net address: 32-bit words printed in hex in host byte order."""
    words = [int(field[i:i + 8], 16) for i in range(0, len(field), 8)]
    packed = b''.join(struct.pack('=I', word) for word in words)
    return socket.inet_ntop(socket.AF_INET if len(packed) == 4 else socket.AF_INET6, packed)


def socket_inodes(pid: int) -> set[str]:
    """Inodes of the sockets among the open descriptors of process ``pid``."""
    inodes = set()
    for fd in (Path(f'/proc/{pid}/fd')).iterdir():
        target = os.readlink(fd)
        if target.startswith('socket:['):
            inodes.add(target[len('socket:['):-1])
    return inodes


def bound_sockets(pid: int) -> list[BoundSocket]:
    """The inet sockets of process ``pid`` with their local addresses, UDP and TCP, v4 and v6."""
    inodes = socket_inodes(pid)
    found = []
    for protocol in ('udp', 'udp6', 'tcp', 'tcp6'):
        rows = Path(f'/proc/{pid}/net/{protocol}').read_text().splitlines()[1:]
        for fields in (row.split() for row in rows):
            if fields[9] in inodes:
                address, port = fields[1].split(':')
                found.append(BoundSocket(protocol, decode_address(address), int(port, 16)))
    return found


def joined_groups(pid: int) -> dict[str, set[str]]:
    """IPv4 multicast groups joined in the network namespace of ``pid``, by device."""
    groups: dict[str, set[str]] = {}
    device = ''
    for line in Path(f'/proc/{pid}/net/igmp').read_text().splitlines()[1:]:
        if line[:1].isdigit():
            device = line.split()[1]
            groups[device] = set()
        elif line.strip():
            groups[device].add(decode_address(line.split()[0]))
    return groups


def leaks(sockets: list[BoundSocket]) -> list[BoundSocket]:
    """The sockets bound to every interface or to the namespace's routable test address."""
    return [s for s in sockets if s.address in ANY_ADDRESSES or s.address == TEST_ADDRESS]


def dds_environment(profile: bool, discovery_range: str | None) -> dict[str, str]:
    """This environment with the DDS settings replaced: the shipped profile or none."""
    env = {name: value for name, value in os.environ.items()
           if name not in (*PROFILE_VARIABLES, *DISCOVERY_VARIABLES)}
    if profile:
        env['FASTRTPS_DEFAULT_PROFILES_FILE'] = str(loopback_profile_path())
    if discovery_range is not None:
        env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = discovery_range
    env['RMW_IMPLEMENTATION'] = 'rmw_fastrtps_cpp'
    # Another domain and topic than anything else on this machine: only our processes meet.
    env['ROS_DOMAIN_ID'] = str(random.randint(1, 100))
    return env


def run_participant_beside_test_address(env: Mapping[str, str], log: Path) -> Footprint:
    """Run PARTICIPANT in a fresh namespace holding lo and TEST_ADDRESS; measure it running."""
    topic = f'loopback_probe_{uuid.uuid4().hex[:8]}'
    command = ['unshare', '--net', 'sh', '-c', NAMESPACE_SETUP, 'sh',
               sys.executable, '-c', PARTICIPANT, topic]
    with log.open('w') as stderr:
        # unshare and sh exec: the process started here is the participant itself.
        process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                   stderr=stderr, text=True, env=dict(env))
        try:
            assert process.stdout is not None and process.stdin is not None
            line = process.stdout.readline().split()
            assert line[:1] == ['ready'], f'participant did not start: {log.read_text()}'
            footprint = Footprint(bound_sockets(process.pid), joined_groups(process.pid),
                                  int(line[1]))
            process.stdin.close()
            assert process.wait(timeout=10) == 0, log.read_text()
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
    return footprint


@pytest.fixture(scope='module', autouse=True)
def network_namespaces() -> None:
    """Fail (not skip) where this machine cannot make network namespaces: CI runs as root."""
    if os.geteuid() != 0 or shutil.which('ip') is None:
        pytest.fail('the network loopback tests need root and iproute2 (ip) to build a '
                    f'namespace holding {TEST_ADDRESS}; run them as root')
    probe = subprocess.run(['unshare', '--net', 'true'], capture_output=True, text=True)
    if probe.returncode != 0:
        pytest.fail(f'`unshare --net` failed, no namespace for the network tests: {probe.stderr}')


@pytest.fixture(scope='module')
def profiled(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Footprint]:
    """A participant with the project's defaults (shipped profile, SYSTEM_DEFAULT discovery)."""
    log = tmp_path_factory.mktemp('profiled') / 'participant.log'
    yield run_participant_beside_test_address(dds_environment(True, 'SYSTEM_DEFAULT'), log)


def test_profiled_participant_binds_no_wildcard_or_routable_address(profiled: Footprint) -> None:
    """No socket on 0.0.0.0, :: or TEST_ADDRESS, yet 127.0.0.1 ones: DDS ran, on loopback."""
    assert profiled.received > 0, 'the participant did not even receive its own messages'
    assert leaks(profiled.sockets) == []
    assert any(s.address == '127.0.0.1' for s in profiled.sockets), profiled.sockets
    assert {s.address for s in profiled.sockets} <= {'127.0.0.1', DDS_MULTICAST_GROUP}


def test_profiled_participant_joins_the_dds_group_on_loopback_only(profiled: Footprint) -> None:
    """The discovery group 239.255.0.1 is joined on lo alone: no other interface hears it."""
    assert DDS_MULTICAST_GROUP in profiled.groups['lo']
    elsewhere = {device for device, groups in profiled.groups.items()
                 if device != 'lo' and DDS_MULTICAST_GROUP in groups}
    assert elsewhere == set()


@pytest.mark.parametrize(
    ('profile', 'discovery_range'),
    [(False, None), (True, 'LOCALHOST')],
    ids=['builtin-transports', 'profile-with-LOCALHOST'],
)
def test_participant_leaks_without_the_project_settings(
    tmp_path: Path, profile: bool, discovery_range: str | None
) -> None:
    """The control: builtin transports, or LOCALHOST on top of the profile, bind 0.0.0.0.

    rmw_fastrtps_cpp adds an unrestricted UDPv4 transport for LOCALHOST (hence SYSTEM_DEFAULT
    in ros_environment_defaults); this shows the check above does catch a leak.
    """
    footprint = run_participant_beside_test_address(
        dds_environment(profile, discovery_range), tmp_path / 'participant.log')
    leaked = {s.address for s in leaks(footprint.sockets)}
    assert '0.0.0.0' in leaked, footprint.sockets
    assert TEST_ADDRESS in leaked, footprint.sockets


def test_two_processes_exchange_messages_in_the_loopback_namespace(tmp_path: Path) -> None:
    """In tools/loopback-netns' namespace a listener process receives a talker process."""
    topic = f'loopback_chatter_{uuid.uuid4().hex[:8]}'
    env = dds_environment(True, 'SYSTEM_DEFAULT')
    env.update(TALKER=PUBLISHER, LISTENER=SUBSCRIBER, PYTHON=sys.executable, TOPIC=topic)
    script = ('echo "netns=$UVMS_NETNS addresses on:" $(ip -o address show | '
              "awk '{print $2}' | sort -u)\n"
              '"$PYTHON" -c "$TALKER" "$TOPIC" & talker=$!\n'
              '"$PYTHON" -c "$LISTENER" "$TOPIC"; status=$?\n'
              'kill -TERM $talker; wait $talker\n'
              'exit $status\n')
    result = subprocess.run([str(LOOPBACK_NETNS), 'sh', '-c', script], capture_output=True,
                            text=True, env=env, timeout=30)
    assert result.returncode == 0, result.stdout + result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == 'netns=private addresses on: lo', result.stdout
    listener_pid = lines[1].split()[1]
    messages = [line.split() for line in lines[2:]]
    assert len(messages) == 3
    assert all(talker_pid != listener_pid for talker_pid, _ in messages)
