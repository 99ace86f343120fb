"""The Net F/T twin streams RDT records on request and stops on command 0."""

from __future__ import annotations

import socket
import time
import urllib.request

import pytest
from uvms_twins.netft_twin import NetFtTwin

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


class ManualClock:
    """A clock the test sets (s)."""

    def __init__(self, now_s: float) -> None:
        self.now_s = now_s

    def __call__(self) -> float:
        """The time set."""
        return self.now_s


def test_records_are_the_samples_due_on_the_boxs_clock() -> None:
    """At 200 Hz, 10.5 ms after the start: samples 1 and 2, sampled 5 ms apart."""
    clock = ManualClock(100.0)
    twin = NetFtTwin(port=0, rate_hz=200.0, clock=clock)
    twin.handle(rdt.encode_request(rdt.COMMAND_START_REALTIME), ('127.0.0.1', 1))
    clock.now_s = 100.0105
    records, wait_s = twin._due()
    assert [rdt.decode_record(r).rdt_sequence for r in records] == [1, 2]
    assert (twin.sample_time_s(1), twin.sample_time_s(2)) == pytest.approx((100.005, 100.010))
    assert wait_s == pytest.approx(0.0045)


def test_a_late_twin_skips_what_it_cannot_send_and_keeps_the_sequence_on_time() -> None:
    """Woken 6 s late at 200 Hz: the newest MAX_BURST (1000) samples sent, the 200 before lost."""
    clock = ManualClock(0.0)
    twin = NetFtTwin(port=0, rate_hz=200.0, clock=clock)
    twin.handle(rdt.encode_request(rdt.COMMAND_START_REALTIME), ('127.0.0.1', 1))
    clock.now_s = 6.0
    records, _ = twin._due()
    sequences = [rdt.decode_record(r).rdt_sequence for r in records]
    assert sequences == list(range(201, 1201)) and twin.burst_lost == 200


def test_each_start_request_begins_a_new_stream_at_sequence_one() -> None:
    """A second start: rdt_sequence from 1 again, sampled from the new start."""
    clock = ManualClock(0.0)
    twin = NetFtTwin(port=0, rate_hz=100.0, clock=clock)
    start = rdt.encode_request(rdt.COMMAND_START_REALTIME)
    twin.handle(start, ('127.0.0.1', 1))
    clock.now_s = 0.05
    twin._due()
    twin.handle(start, ('127.0.0.1', 1))
    clock.now_s = 0.0605
    records, _ = twin._due()
    assert [rdt.decode_record(r).rdt_sequence for r in records] == [1]
    assert twin.sample_time_s(1) == pytest.approx(0.06)


def test_the_calibration_page_is_served_on_loopback_http() -> None:
    """GET /netftapi2.xml gives the twin's counts per N and N m and its rate."""
    with NetFtTwin(port=0, rate_hz=250.0, counts_per_force=2e6, counts_per_torque=5e5,
                   http_port=0) as twin:
        assert twin.http_port
        with urllib.request.build_opener(urllib.request.ProxyHandler({})).open(
                f'http://127.0.0.1:{twin.http_port}/netftapi2.xml?index=0', timeout=2.0) as page:
            calibration = rdt.calibration_from_netftapi2(page.read())
    assert calibration == rdt.BoxCalibration(2e6, 5e5, 250.0)
