"""DvlComponent without ROS, against the DVL twin on 127.0.0.1: the component's contract."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from uvms_hardware.component import ERROR, OK, WARN
from uvms_hardware.dvl_component import SPECS, DvlBridgeError, DvlComponent, DvlMeasurement
from uvms_twins.dvl_twin import DvlTwin


def settings(address: str, **changes: object) -> dict[str, object]:
    """The node's defaults on ``address``, reconnecting quickly."""
    values: dict[str, object] = {spec.name: spec.default for spec in SPECS}
    values.update(address=address, reconnect_period_s=0.1, timeout_s=0.3)
    values.update(changes)
    return values


def read_until(dvl: DvlComponent, done: Callable[[], bool], timeout_s: float = 3.0,
               ) -> list[DvlMeasurement]:
    """Call read() every 10 ms until done(); the measurements taken meanwhile."""
    taken: list[DvlMeasurement] = []
    end = time.monotonic() + timeout_s
    while not done():
        assert time.monotonic() < end, 'timed out reading'
        dvl.read(time.monotonic())
        taken += dvl.state().measurements
        time.sleep(0.01)
    return taken


@pytest.fixture
def twin() -> Iterator[DvlTwin]:
    """A DVL twin at 20 Hz on a free port."""
    with DvlTwin(rate_hz=20.0) as running:
        yield running


@pytest.fixture
def dvl(twin: DvlTwin) -> Iterator[DvlComponent]:
    """A configured and active component on the twin (identity mounting); released after."""
    made = DvlComponent(settings(twin.url), np.eye(3), log=lambda level, text: None)
    made.configure()
    made.activate()
    yield made
    made.put_back()
    made.release()


def test_locked_reports_are_measurements_once_each(twin: DvlTwin, dvl: DvlComponent) -> None:
    """The twin's velocity with fom^2 variances, each report given once, fresh."""
    twin.set_velocity((0.4, -0.2, 0.1), valid=True, fom=0.003)
    taken = read_until(dvl, lambda: any(np.allclose(m.v_m_s, (0.4, -0.2, 0.1))
                                        for m in dvl.state().measurements))
    taken += read_until(dvl, lambda: dvl.published >= len(taken) + 2)
    m = taken[-1]
    assert m.v_m_s == pytest.approx((0.4, -0.2, 0.1))
    assert m.covariance[0, 0] == pytest.approx(0.003 ** 2)
    assert dvl.published == len(taken)
    assert len({m.stamp_s for m in taken}) == len(taken)
    assert dvl.state().fresh and dvl.state().bottom_lock is True
    assert dvl.report(time.monotonic()).level in (OK, WARN)


def test_reports_without_lock_are_no_measurement(twin: DvlTwin, dvl: DvlComponent) -> None:
    """velocity_valid false: no measurement, WARN naming the lost lock."""
    twin.set_velocity((0.0, 0.0, 0.0), valid=False)
    read_until(dvl, lambda: dvl.state().bottom_lock is False)
    taken = read_until(dvl, lambda: dvl.link is not None and dvl.link.parser.reports >= 6)
    assert taken == []
    report = dvl.report(time.monotonic())
    assert report.level == WARN and 'no bottom lock' in report.message


def test_a_silent_dvl_returns_at_once_and_is_stale(twin: DvlTwin, dvl: DvlComponent,
                                                  no_waiting: Any) -> None:
    """The DVL goes quiet: read() never waits, nothing new, not fresh, ERROR."""
    read_until(dvl, lambda: dvl.published >= 2)
    twin.silent = True
    time.sleep(0.1)
    dvl.read(time.monotonic())  # what was already on its way
    time.sleep(0.4)  # longer than timeout_s 0.3
    with no_waiting.check():  # no sleep, select or blocking receive (conftest.py)
        for _ in range(20):
            dvl.read(time.monotonic())
            assert dvl.state().measurements == ()
    assert not dvl.state().fresh
    report = dvl.report(time.monotonic())
    assert report.level == ERROR and 'DVL silent' in report.message


def test_malformed_lines_are_counted(twin: DvlTwin, dvl: DvlComponent) -> None:
    """Garbage lines: counted in the report, measurements keep coming."""
    read_until(dvl, lambda: twin.client_count() == 1)
    twin.send_raw(b'{"type": "velocity", "vx":\n\x00\x01garbage\n')
    read_until(dvl, lambda: dvl.report(time.monotonic()).values['malformed_lines'] == 2)
    count = dvl.published
    read_until(dvl, lambda: dvl.published > count + 2)


def test_put_back_stops_measurements_and_release_disconnects(twin: DvlTwin,
                                                             dvl: DvlComponent) -> None:
    """Inactive: reports still time the clock but give no measurement; release closes."""
    read_until(dvl, lambda: dvl.published >= 1)
    assert dvl.put_back() == []
    count = dvl.published
    read_until(dvl, lambda: dvl.link is not None and dvl.link.parser.reports >= 6)
    assert dvl.published == count
    dvl.release()
    end = time.monotonic() + 3.0
    while twin.client_count():
        assert time.monotonic() < end, 'the connection stays open after release'
        time.sleep(0.01)
    assert dvl.link is None and not dvl.state().fresh


def test_no_dvl_refuses_configure() -> None:
    """Nothing at the address: configure raises within connect_timeout_s."""
    with DvlTwin() as gone:
        url = gone.url
    dvl = DvlComponent(settings(url, connect_timeout_s=0.3), np.eye(3),
                       log=lambda level, text: None)
    with pytest.raises(DvlBridgeError, match='no DVL'):
        dvl.configure()
    dvl.release()
    assert dvl.link is None
