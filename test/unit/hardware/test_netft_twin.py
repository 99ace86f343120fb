"""The Net F/T twin streams RDT records on request and stops on command 0."""

from __future__ import annotations

import socket
import time

import pytest
from uvms_hardware.twins.netft_twin import NetFtTwin

from uvms_hardware import rdt_protocol as rdt


def receive(sock: socket.socket, count: int) -> list[rdt.Record]:
    """``count`` records from the socket."""
    return [rdt.decode_record(sock.recvfrom(64)[0]) for _ in range(count)]


def test_streams_the_plants_wrench_after_a_start_request() -> None:
    """Start: records with the set wrench's counts, consecutive sequences."""
    with NetFtTwin(port=0, rate_hz=200.0) as twin, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        twin.set_wrench((1.0, -2.0, 3.5), (0.1, 0.0, -0.25))
        sock.settimeout(2.0)
        sock.sendto(rdt.encode_request(rdt.COMMAND_START_REALTIME), ('127.0.0.1', twin.port))
        records = receive(sock, 5)
    assert records[-1].counts == (1_000_000, -2_000_000, 3_500_000, 100_000, 0, -250_000)
    sequences = [r.rdt_sequence for r in records]
    assert sequences == list(range(sequences[0], sequences[0] + 5))


def test_stop_command_ends_the_stream() -> None:
    """After command 0 no record arrives."""
    with NetFtTwin(port=0, rate_hz=200.0) as twin, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(2.0)
        sock.sendto(rdt.encode_request(rdt.COMMAND_START_REALTIME), ('127.0.0.1', twin.port))
        receive(sock, 2)
        sock.sendto(rdt.encode_request(rdt.COMMAND_STOP), ('127.0.0.1', twin.port))
        deadline = time.monotonic() + 1.0
        while twin.streaming and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.05)
        sock.setblocking(False)
        while True:  # drain what was in flight
            try:
                sock.recvfrom(64)
            except BlockingIOError:
                break
        time.sleep(0.1)
        with pytest.raises(BlockingIOError):
            sock.recvfrom(64)


def test_sample_count_limits_the_stream() -> None:
    """A start for 3 samples sends 3 records."""
    twin = NetFtTwin(port=0, rate_hz=500.0)
    with twin, socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(2.0)
        sock.sendto(rdt.encode_request(rdt.COMMAND_START_REALTIME, 3), ('127.0.0.1', twin.port))
        receive(sock, 3)
        sock.settimeout(0.2)
        with pytest.raises(TimeoutError):
            sock.recvfrom(64)


def test_bad_request_is_counted() -> None:
    """A 5-byte request is ignored and counted."""
    twin = NetFtTwin(port=0)
    twin.handle(b'\x12\x34\x00\x02\x00', ('127.0.0.1', 1))
    assert twin.bad_requests == 1 and not twin.streaming
