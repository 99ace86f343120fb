"""Connection strings of the bridges and the UDP link on loopback."""

from __future__ import annotations

import socket
import time

import pytest
from uvms_hardware.errors import AddressError
from uvms_hardware.transport import Connection, UdpLink, parse_connection


@pytest.mark.parametrize(('text', 'expected'), [
    ('udp:127.0.0.1:6789', Connection('udp', '127.0.0.1', 6789)),
    ('udp:192.168.2.4', Connection('udp', '192.168.2.4', 6789)),
    ('serial:/dev/ttyUSB0', Connection('serial', '/dev/ttyUSB0', 115200)),
    ('serial:/dev/ttyUSB0:57600', Connection('serial', '/dev/ttyUSB0', 57600)),
])
def test_connection_forms(text: str, expected: Connection) -> None:
    """udp:HOST[:PORT] and serial:DEVICE[:BAUD], with the protocol's defaults."""
    assert parse_connection(text, 6789) == expected


@pytest.mark.parametrize('text', ['tcp:1.2.3.4:5', 'udp:host:99999', 'serial:', '127.0.0.1'])
def test_bad_connection_names_the_forms(text: str) -> None:
    """Anything else is an AddressError naming both valid forms or the bad port."""
    with pytest.raises(AddressError, match='connection'):
        parse_connection(text, 6789)


def test_udp_link_binds_loopback_and_reads_only_its_peer() -> None:
    """A loopback link binds 127.0.0.1; datagrams from its peer are read, others dropped."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as peer, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as stranger:
        peer.bind(('127.0.0.1', 0))
        stranger.bind(('127.0.0.1', 0))
        link = UdpLink('127.0.0.1', peer.getsockname()[1])
        try:
            address = link._socket.getsockname()
            assert address[0] == '127.0.0.1'
            link.send(b'hello')
            assert peer.recvfrom(16)[0] == b'hello'
            stranger.sendto(b'noise', address)
            peer.sendto(b'answer', address)
            assert link.wait(1.0)
            time.sleep(0.05)  # both datagrams are in the socket's queue
            assert link.read() == b'answer'
        finally:
            link.close()


def test_udp_link_gives_each_datagram_the_kernels_arrival_not_the_read() -> None:
    """Read 50 ms after they came, two datagrams carry the times they were sent, in order."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as peer:
        peer.bind(('127.0.0.1', 0))
        link = UdpLink('127.0.0.1', peer.getsockname()[1])
        try:
            assert link.stamped  # Linux, which the project runs on
            address = link._socket.getsockname()
            sent = []
            for payload in (b'first', b'second'):
                before_s = time.time()
                peer.sendto(payload, address)
                sent.append((before_s, time.time()))
                time.sleep(0.01)
            time.sleep(0.05)
            read_s = time.time()
            stamped = link.read_stamped()
        finally:
            link.close()
    assert [data for data, _ in stamped] == [b'first', b'second']
    for (_, arrival_s), (before_s, after_s) in zip(stamped, sent, strict=True):
        assert arrival_s is not None and before_s <= arrival_s <= after_s < read_s - 0.04
