"""Tests of uvms_hardware.dvl_link against the DVL twin (TCP on 127.0.0.1, no ROS)."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

import pytest
from uvms_hardware.address import parse_host_port
from uvms_hardware.dvl_link import DvlLink
from uvms_twins.dvl_twin import DvlTwin


def wait(condition: Callable[[], bool], timeout_s: float, what: str) -> None:
    """Poll until condition() or fail naming what."""
    end = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < end, f'timed out waiting for {what}'
        time.sleep(0.01)


@pytest.fixture
def twin() -> Iterator[DvlTwin]:
    """A DVL twin at 20 Hz on a free port."""
    with DvlTwin(rate_hz=20.0) as running:
        yield running


def test_reports_arrive_with_and_without_lock(twin: DvlTwin) -> None:
    """Locked reports carry the plant's velocity; unlocked ones are marked invalid."""
    link = DvlLink(parse_host_port(twin.url, 16171), reconnect_period_s=0.1).start()
    try:
        assert link.wait_connected(2.0)
        twin.set_velocity((0.3, -0.1, 0.05), valid=True, fom=0.004, altitude_m=3.0)
        wait(lambda: any(r.valid and r.v_m_s == (0.3, -0.1, 0.05) for _, r in link.take()),
             2.0, 'a locked report')
        twin.set_velocity((0.0, 0.0, 0.0), valid=False)
        wait(lambda: any(not r.valid for _, r in link.take()), 2.0, 'an unlocked report')
        wait(lambda: link.parser.ignored >= 1, 2.0, 'a dead-reckoning report ignored')
    finally:
        link.stop()


def test_a_plant_reading_is_reported_once_and_at_once() -> None:
    """One reading, one report, sent now: the slow idle stream does not repeat it."""
    with DvlTwin(rate_hz=1.0) as twin:
        link = DvlLink(parse_host_port(twin.url, 16171)).start()
        try:
            assert link.wait_connected(2.0)
            wait(lambda: twin.client_count() == 1, 2.0, 'the twin to accept')
            wait(lambda: bool(link.take()), 2.0, 'the first idle report')
            sent_s = time.monotonic()
            twin.report((0.2, 0.0, 0.0), valid=True)
            wait(lambda: any(r.v_m_s == (0.2, 0.0, 0.0) for _, r in link.take()), 2.0,
                 'the reading')
            assert time.monotonic() - sent_s < 0.5  # not the idle stream's next report (1 s)
            time.sleep(0.3)
            assert link.take() == []  # nothing repeated within the idle period
        finally:
            link.stop()


def test_malformed_lines_are_survived_and_counted(twin: DvlTwin) -> None:
    """Garbage between reports: counted, and reports keep coming."""
    link = DvlLink(parse_host_port(twin.url, 16171)).start()
    try:
        assert link.wait_connected(2.0)
        wait(lambda: twin.client_count() == 1, 2.0, 'the twin to accept')
        twin.send_raw(b'{"type": "velocity", "vx": \nnot json at all\n')
        wait(lambda: link.parser.malformed == 2, 2.0, 'two malformed lines counted')
        link.take()
        wait(lambda: bool(link.take()), 2.0, 'reports after the garbage')
    finally:
        link.stop()


def test_the_link_reconnects_after_the_dvl_drops_it(twin: DvlTwin) -> None:
    """The twin closes the connection: the link connects again and reports resume."""
    link = DvlLink(parse_host_port(twin.url, 16171), reconnect_period_s=0.1).start()
    try:
        assert link.wait_connected(2.0)
        wait(lambda: twin.client_count() == 1, 2.0, 'the twin to accept')
        twin.drop_clients()
        wait(lambda: link.connects >= 2 and link.connected, 3.0, 'a second connection')
        link.take()
        wait(lambda: bool(link.take()), 2.0, 'reports after reconnecting')
    finally:
        link.stop()


def test_no_dvl_means_no_connection() -> None:
    """Nothing listening: not connected, the error names the address."""
    with DvlTwin() as gone:
        url = gone.url
    link = DvlLink(parse_host_port(url, 16171), reconnect_period_s=0.1).start()
    try:
        assert not link.wait_connected(0.3)
        wait(lambda: url in link.last_error, 1.0, 'the error')
    finally:
        link.stop()


def test_arrivals_are_read_on_the_arrival_clock_when_they_arrive(twin: DvlTwin) -> None:
    """The stamp clock is read by the reader thread at recv, not when the node drains."""
    ticks: list[float] = []

    def arrival_clock() -> float:
        ticks.append(time.monotonic())
        return 1e6 + len(ticks)

    link = DvlLink(parse_host_port(twin.url, 16171), arrival_clock=arrival_clock).start()
    try:
        assert link.wait_connected(2.0)
        wait(lambda: len(ticks) >= 2, 2.0, 'two arrivals')
        time.sleep(0.2)  # drained late: the arrival times do not change
        taken = link.take()
        assert taken and all(t_s > 1e6 for t_s, _ in taken)
    finally:
        link.stop()
