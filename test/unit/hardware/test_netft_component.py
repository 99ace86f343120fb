"""NetFtComponent without ROS, against the Net F/T twin on 127.0.0.1: the component's contract."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from uvms_hardware.component import ERROR, OK
from uvms_hardware.netft_component import PARAMETERS, NetFtBridgeError, NetFtComponent
from uvms_twins.netft_twin import NetFtTwin

from uvms_hardware import rdt_protocol as rdt

IDENTITY = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]


def settings(port: int, **changes: object) -> dict[str, object]:
    """The node's defaults, the twin's calibration given, no page asked for."""
    values: dict[str, object] = {name: default for name, default, _ in PARAMETERS}
    values.update(address=f'127.0.0.1:{port}', http_port=0,
                  counts_per_force=rdt.DEFAULT_COUNTS_PER_FORCE,
                  counts_per_torque=rdt.DEFAULT_COUNTS_PER_TORQUE, rdt_rate_hz=200.0,
                  rot_link_from_sensor=IDENTITY, startup_wait_s=0.0)
    values.update(changes)
    return values


def read_until(netft: NetFtComponent, done: Callable[[], bool], timeout_s: float = 3.0,
               ) -> list[tuple[float, object]]:
    """Call read() every 5 ms until done(); the records taken meanwhile."""
    records: list[tuple[float, object]] = []
    end = time.monotonic() + timeout_s
    while not done():
        assert time.monotonic() < end, 'timed out reading'
        netft.read(time.monotonic())
        records += netft.state().records
        time.sleep(0.005)
    return records


@pytest.fixture
def twin() -> Iterator[NetFtTwin]:
    """A twin streaming at 200 Hz on a free port."""
    with NetFtTwin(port=0, rate_hz=200.0) as running:
        yield running


@pytest.fixture
def netft(twin: NetFtTwin) -> Iterator[NetFtComponent]:
    """A configured and active component on the twin; put back and released after."""
    made = NetFtComponent(settings(twin.port), log=lambda level, text: None)
    made.configure()
    made.activate()
    yield made
    made.put_back()
    made.release()


def test_read_gives_each_record_once_in_ft_sensor_link(twin: NetFtTwin,
                                                       netft: NetFtComponent) -> None:
    """The twin's wrench comes out of read()/state(), every record decoded exactly once."""
    twin.set_wrench((1.5, -2.0, 3.0), (0.1, 0.2, -0.3))

    def newest_is_set() -> bool:
        wrench = netft.state().wrench
        return wrench is not None and wrench[0][0] == pytest.approx(1.5)

    seen = read_until(netft, newest_is_set)
    seen += read_until(netft, lambda: netft.core is not None and netft.core.records >= 10)
    assert netft.core is not None and len(seen) == netft.core.records
    state = netft.state()
    assert state.fresh and state.wrench is not None
    assert state.wrench[0] == pytest.approx((1.5, -2.0, 3.0))
    assert state.wrench[1] == pytest.approx((0.1, 0.2, -0.3))


def test_a_silent_box_returns_at_once_and_is_stale(twin: NetFtTwin, netft: NetFtComponent,
                                                  no_waiting: Any) -> None:
    """The box stops: read() never waits, state() is not fresh, the report is ERROR."""
    read_until(netft, lambda: netft.state().fresh and netft.state().wrench is not None)
    twin.stop()
    netft.read(time.monotonic())  # what was already on its way
    time.sleep(0.15)  # longer than watchdog_timeout_s 0.1
    with no_waiting.check():  # no sleep, select or blocking receive (conftest.py)
        for _ in range(20):
            netft.read(time.monotonic())
    state = netft.state()
    assert not state.fresh and state.records == () and state.wrench is None
    report = netft.report(time.monotonic())
    assert report.level == ERROR and 'no record' in report.message


def test_lost_and_malformed_are_counted(twin: NetFtTwin, netft: NetFtComponent) -> None:
    """Five skipped sequence numbers: 5 lost; a datagram of the wrong size: one bad."""
    read_until(netft, lambda: netft.core is not None and netft.core.records >= 3)
    twin.drop_records(5)
    read_until(netft, lambda: netft.core is not None and netft.core.lost >= 5)
    assert netft.core is not None
    bad = netft.core.bad_datagrams
    netft.core.receive_all([b'\x00' * 7], time.monotonic(), time.monotonic())
    assert netft.core.bad_datagrams == bad + 1
    values = netft.report(time.monotonic()).values
    assert values['lost_records'] == 5 and values['bad_datagrams'] == bad + 1


def test_put_back_stops_the_stream(twin: NetFtTwin, netft: NetFtComponent) -> None:
    """put_back sends command 0: the twin stops streaming; the report says not streaming."""
    read_until(netft, lambda: twin.streaming)
    assert netft.put_back() == []
    end = time.monotonic() + 2.0
    while twin.streaming:
        assert time.monotonic() < end, 'the twin still streams after put_back'
        time.sleep(0.01)
    assert netft.report(time.monotonic()).level == OK
    assert not netft.state().fresh


def test_no_box_refuses_configure() -> None:
    """Nothing answers: configure raises naming the address; release closes what it opened."""
    with NetFtTwin(port=0) as gone:
        port = gone.port
    netft = NetFtComponent(settings(port, answer_timeout_s=0.1), log=lambda level, text: None)
    with pytest.raises(NetFtBridgeError, match=f'127.0.0.1:{port}'):
        netft.configure()
    netft.release()
    assert netft.link is None


def test_no_calibration_refuses_configure(twin: NetFtTwin) -> None:
    """No counts per N anywhere: refused, never assumed."""
    netft = NetFtComponent(settings(twin.port, counts_per_force=0.0),
                           log=lambda level, text: None)
    with pytest.raises(NetFtBridgeError, match='never assumed'):
        netft.configure()


class CountingTwin(NetFtTwin):
    """A twin on the wall clock whose Fx counts are the record's sample number."""

    def _record(self) -> bytes:
        self._counts = (self._sample, 0, 0, 0, 0, 0)
        return super()._record()


def test_a_pause_between_the_clock_reads_never_stamps_a_record_before_its_sample() -> None:
    """The local clock paused 5 ms around its reading (a preempted thread): stamps not early.

    The kernel's arrival is moved onto the local clock by the two clocks' readings; a pause
    between them must make an arrival late (which the minimum-delay fit passes over), never
    early (which it would take, stamping every later record before its sample).
    """
    def paused_clock() -> float:
        time.sleep(0.005)
        now_s = time.time()
        time.sleep(0.005)
        return now_s

    with CountingTwin(port=0, rate_hz=200.0, clock=time.time) as twin:
        netft = NetFtComponent(settings(twin.port), local_clock=paused_clock,
                               log=lambda level, text: None)
        netft.configure()
        netft.activate()
        try:
            records = read_until(netft, lambda: netft.core is not None
                                 and netft.core.records >= 60)
            early_s = [twin.sample_time_s(round(force[0] * rdt.DEFAULT_COUNTS_PER_FORCE))
                       - stamp_s for stamp_s, (force, _) in records]
        finally:
            netft.put_back()
            netft.release()
    assert len(early_s) >= 50 and max(early_s) < 0.0005, max(early_s)
