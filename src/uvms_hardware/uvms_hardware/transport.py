"""Byte links of the bridges: a UDP peer or a serial port, both read without blocking.

``udp:HOST:PORT`` sends datagrams to HOST:PORT from a socket bound to 127.0.0.1 when HOST is
loopback (nothing binds beyond it unless the user's address says so); ``serial:DEVICE[:BAUD]``
opens a serial port with pyserial, 8N1, 115200 baud unless given. ``read`` returns whatever
arrived (b'' if nothing), so a bridge polls its link once per period without threads.
``UdpLink.read_stamped`` also gives each datagram's arrival, the kernel's time of it (Linux's
``SO_TIMESTAMPNS``), which a poll that comes late does not move.
"""

from __future__ import annotations

import select
import socket
import time
from collections.abc import Callable, Collection
from typing import NamedTuple, Protocol

from uvms_hardware import latency_probe
from uvms_hardware.address import LOOPBACK, parse_host_port
from uvms_hardware.datagram_arrival import ANCILLARY_SIZE, kernel_arrival_s, stamp_arrivals
from uvms_hardware.errors import AddressError, HardwareError

DEFAULT_BAUD = 115200


class Connection(NamedTuple):
    """A parsed connection: ``kind`` 'udp' (target host, port) or 'serial' (device, baud)."""

    kind: str
    target: str
    number: int


class Link(Protocol):
    """What a bridge needs of its link."""

    def send(self, data: bytes) -> None: ...  # noqa: D102

    def read(self) -> bytes: ...  # noqa: D102

    def wait(self, timeout_s: float) -> bool: ...  # noqa: D102

    def close(self) -> None: ...  # noqa: D102


def parse_connection(text: str, default_port: int, name: str = 'connection') -> Connection:
    """``udp:HOST:PORT`` or ``serial:DEVICE[:BAUD]`` -> Connection.

    Raises:
        AddressError: Another form; the message names the parameter and the valid forms.
    """
    kind, sep, rest = text.strip().partition(':')
    if sep and kind == 'udp':
        host, port = parse_host_port(rest, default_port, name)
        return Connection('udp', host, port)
    if sep and kind == 'serial' and rest:
        device, sep_baud, baud_text = rest.rpartition(':')
        if sep_baud and device and baud_text.isdigit() and int(baud_text) > 0:
            return Connection('serial', device, int(baud_text))
        return Connection('serial', rest, DEFAULT_BAUD)
    raise AddressError(f'{name} = {text!r}: expected udp:HOST:PORT or serial:DEVICE[:BAUD], '
                       f'e.g. udp:{LOOPBACK}:{default_port}')


class UdpLink:
    """Datagrams to one peer; replies from it read without blocking."""

    def __init__(self, host: str, port: int) -> None:
        self._peer = (host, port)
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        loopback = host == LOOPBACK or host == 'localhost'
        self._socket.bind((LOOPBACK if loopback else '', 0))
        self._socket.setblocking(False)
        #: Whether the kernel stamps each datagram's arrival (Linux).
        self.stamped = stamp_arrivals(self._socket)
        #: Sends the peer refused (ICMP port unreachable: nothing listens there).
        self.refused = 0

    def send(self, data: bytes) -> None:
        """One datagram (no-op for b'')."""
        if data:
            try:
                self._socket.sendto(data, self._peer)
            except ConnectionRefusedError:
                self.refused += 1

    def read(self) -> bytes:
        """Every datagram waiting, from the peer only, concatenated."""
        return b''.join(self.read_datagrams())

    def read_datagrams(self) -> list[bytes]:
        """Every datagram waiting from the peer, one bytes each (others are dropped)."""
        return [data for data, _ in self.read_stamped()]

    def read_stamped(self) -> list[tuple[bytes, float | None]]:
        """Every datagram waiting from the peer with its arrival, in order.

        The arrival is the kernel's stamp (s since the epoch, on CLOCK_REALTIME), None where
        it gives none.
        """
        datagrams = []
        while True:
            try:
                data, ancillary, _, sender = self._socket.recvmsg(4096, ANCILLARY_SIZE)
            except (BlockingIOError, InterruptedError):
                break
            except ConnectionRefusedError:
                self.refused += 1
                continue
            if sender[1] == self._peer[1]:
                datagrams.append((data, kernel_arrival_s(ancillary)))
        if datagrams:
            latency_probe.note('rx', self._peer[1], len(datagrams))
        return datagrams

    def wait(self, timeout_s: float) -> bool:
        """True when something can be read within ``timeout_s``."""
        readable, _, _ = select.select([self._socket], [], [], max(0.0, timeout_s))
        return bool(readable)

    def close(self) -> None:
        """Close the socket."""
        self._socket.close()


class SerialLink:
    """A serial port (pyserial), 8N1, non-blocking reads."""

    def __init__(self, device: str, baud: int) -> None:
        import serial  # type: ignore[import-untyped]

        try:
            self._port = serial.Serial(device, baudrate=baud, bytesize=8, parity='N',
                                       stopbits=1, timeout=0, write_timeout=0.1)
        except (serial.SerialException, ValueError) as exc:
            raise HardwareError(f'serial port {device} at {baud} baud: {exc}') from exc

    def send(self, data: bytes) -> None:
        """Write the bytes."""
        if data:
            self._port.write(data)

    def read(self) -> bytes:
        """The bytes waiting."""
        waiting = self._port.in_waiting
        return bytes(self._port.read(waiting)) if waiting else b''

    def wait(self, timeout_s: float) -> bool:
        """True when bytes wait within ``timeout_s``."""
        readable, _, _ = select.select([self._port.fileno()], [], [], max(0.0, timeout_s))
        return bool(readable)

    def close(self) -> None:
        """Close the port."""
        self._port.close()


def open_link(connection: Connection) -> UdpLink | SerialLink:
    """The link of a parsed connection."""
    if connection.kind == 'udp':
        return UdpLink(connection.target, connection.number)
    return SerialLink(connection.target, connection.number)


def collect(link: Link, feed: Callable[[bytes], Collection[int]], wanted: Collection[int],
            timeout_s: float) -> set[int]:
    """Read until ``feed`` (bytes -> ids it recognised) has seen every wanted id, or timeout.

    Wall-clock I/O timeout at configure only (the node's period never waits). Returns the
    wanted ids seen.
    """
    seen: set[int] = set()
    deadline = time.monotonic() + timeout_s
    while not set(wanted) <= seen:
        remaining = deadline - time.monotonic()
        if remaining <= 0.0:
            break
        if link.wait(remaining):
            seen |= set(feed(link.read())) & set(wanted)
    return seen

