"""ArduSub telemetry stamps (ardusub_stamps): the autopilot's time on the node clock."""

from __future__ import annotations

import random
from types import SimpleNamespace

import pytest
from uvms_hardware.ardusub_stamps import TelemetryStamper

#: Node clock minus the autopilot's boot clock (s), and the link's smallest delay (s).
OFFSET_S, DELAY_S = 1000.0, 0.0005


def raw_imu(device_s: float) -> SimpleNamespace:
    """A RAW_IMU as pymavlink decodes it: only its time matters here."""
    return SimpleNamespace(time_usec=round(device_s * 1e6))


def test_delayed_arrivals_do_not_delay_the_stamps() -> None:
    """50 Hz arrivals late by 0-20 ms (a busy link or host): stamps within 1 ms of the send."""
    rng = random.Random(7)
    stamper, errors = TelemetryStamper(), []
    for k in range(1000):
        device_s = 0.02 * k
        arrival_s = device_s + OFFSET_S + DELAY_S + rng.expovariate(1.0 / 0.005) % 0.02
        errors.append(stamper.stamp_s('RAW_IMU', raw_imu(device_s), arrival_s)
                      - (device_s + OFFSET_S))
    assert max(abs(e) for e in errors[100:]) < 0.001
    assert stamper.stamped_at_arrival == 0


def test_a_stamp_is_never_later_than_its_arrival() -> None:
    """Whatever the estimate, nothing is stamped after it arrived."""
    stamper = TelemetryStamper()
    for k in range(100):
        stamper.stamp_s('RAW_IMU', raw_imu(0.02 * k), OFFSET_S + 0.02 * k + 0.05)
    arrival_s = OFFSET_S + 0.02 * 100 + 0.001  # earlier than the estimate says
    assert stamper.stamp_s('RAW_IMU', raw_imu(0.02 * 100), arrival_s) == arrival_s


@pytest.mark.parametrize('kind', ['SYS_STATUS'])
def test_a_message_without_time_is_stamped_at_arrival(kind: str) -> None:
    """SYS_STATUS carries no time: its arrival, not counted as a fallback."""
    stamper = TelemetryStamper()
    assert stamper.stamp_s(kind, SimpleNamespace(), 12.5) == 12.5
    assert stamper.stamped_at_arrival == 0


def test_on_a_simulated_clock_every_message_is_stamped_at_arrival() -> None:
    """device_time False (use_sim_time): arrival stamps, counted."""
    stamper = TelemetryStamper(device_time=False)
    for k in range(10):
        assert stamper.stamp_s('RAW_IMU', raw_imu(0.02 * k), 5.0 + 0.01 * k) == 5.0 + 0.01 * k
    assert stamper.stamped_at_arrival == 10
