"""A DVL bridge beside a simulator whose ``/clock`` stands while the bridge's process starves.

Through the twin stand the DVL twin's clock is the plant's time and the bridge stamps on the
node clock, a ``/clock`` that the robot process takes on its main thread. When that thread is
starved for half a second the clock stands while the DVL's reports keep arriving: read on it,
those arrivals look earlier than their own transmission, the DVL clock's offset is taken from
them, and every later report was stamped 0.55 s early for seconds (issue 50: the locked DVL
read 0.08-0.12 m/s off the true velocity in the twin stand's surge runs). The arrivals are read
through the steady clock (`uvms_hardware.arrival_clock`): after the stall the stamps are the
reports' own times again.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from uvms_hardware.arrival_clock import ArrivalClock
from uvms_hardware.dvl_component import SPECS, DvlComponent
from uvms_twins.dvl_twin import DvlTwin

STALL_FROM_S, STALL_S = 2.0, 0.5  # the node clock stands this long, from this plant time


class TimeTellingTwin(DvlTwin):
    """A DVL twin whose reports carry their own time of validity as vx (s)."""

    def velocity_line(self, time_of_validity_s: float,
                      time_of_transmission_s: float | None = None) -> bytes:
        """The report, vx = its time of validity."""
        self.set_velocity((time_of_validity_s, 0.0, 0.0))
        return super().velocity_line(time_of_validity_s, time_of_transmission_s)


class StallingClock:
    """The plant's time as a process's ``/clock`` reads it: standing during the stall."""

    def __init__(self) -> None:
        self.start_s = time.monotonic()

    def plant_s(self) -> float:
        """The plant's time (s): the DVL twin's clock (factor 1)."""
        return time.monotonic() - self.start_s

    def node_s(self) -> float:
        """The node clock (s): the plant's time, standing at STALL_FROM_S during the stall."""
        t = self.plant_s()
        return STALL_FROM_S if STALL_FROM_S <= t < STALL_FROM_S + STALL_S else t


def test_stamps_are_the_reports_own_times_after_the_node_clock_stood() -> None:
    """Reports after a 0.5 s stall of the node clock are stamped within 20 ms of their time."""
    clock = StallingClock()
    values: dict[str, object] = {spec.name: spec.default for spec in SPECS}
    with TimeTellingTwin(rate_hz=20.0, clock=clock.plant_s) as twin:
        values.update(address=twin.url, reconnect_period_s=0.1)
        dvl = DvlComponent(values, np.eye(3), clock=time.monotonic, local_clock=clock.node_s,
                           log=lambda level, text: None)
        dvl.configure()
        dvl.activate()
        early_s = []
        try:
            while clock.plant_s() < STALL_FROM_S + STALL_S + 2.0:
                t = clock.plant_s()
                if not STALL_FROM_S <= t < STALL_FROM_S + STALL_S:  # the main thread starved
                    dvl.read(time.monotonic())
                    if t > STALL_FROM_S + STALL_S + 0.3:
                        early_s += [m.v_m_s[0] - m.stamp_s for m in dvl.state().measurements]
                time.sleep(0.01)
        finally:
            dvl.put_back()
            dvl.release()
    assert len(early_s) >= 20
    # Each report stamped with its own time (the smallest delay of its arrival aside).
    assert max(early_s) < 0.02, f'stamped up to {max(early_s):.3f} s early after the stall'
    assert min(early_s) > -0.02, f'stamped up to {-min(early_s):.3f} s late after the stall'


def test_the_arrival_clock_is_the_node_clock_while_it_runs() -> None:
    """A node clock that never stands is answered as it is (a real robot's wall clock)."""
    steady = [100.0]
    arrival = ArrivalClock(lambda: steady[0] - 90.0, lambda: steady[0])
    for _ in range(400):
        steady[0] += 0.01
        arrival.sample()
    assert arrival.now() == pytest.approx(steady[0] - 90.0, abs=1e-9)
    assert arrival.mended == 0


def test_a_standing_node_clock_is_read_forward_at_its_rate() -> None:
    """A /clock at factor 0.8 that stands 0.3 s: read as the running clock would read it."""
    steady = [0.0]
    node = [0.0]
    arrival = ArrivalClock(lambda: node[0], lambda: steady[0])
    for _ in range(400):
        steady[0] += 0.01
        node[0] += 0.008
        arrival.sample()
    stood = node[0]
    steady[0] += 0.3  # the clock stands
    assert arrival.now() == pytest.approx(stood + 0.8 * 0.3, abs=2e-3)
    # A clock that stands for good (a simulator paused) stops being read forward.
    for _ in range(300):
        steady[0] += 0.01
        arrival.sample()
    assert arrival.now() == stood


def test_reports_at_a_plant_holding_its_first_state_are_stamped_at_its_time() -> None:
    """Plant and node clock stand at 0 (a simulator holding t = 0): stamped 0, not later."""
    values: dict[str, object] = {spec.name: spec.default for spec in SPECS}
    with DvlTwin(rate_hz=20.0, clock=lambda: 0.0) as twin:
        values.update(address=twin.url, reconnect_period_s=0.1)
        dvl = DvlComponent(values, np.eye(3), clock=time.monotonic, local_clock=lambda: 0.0,
                           log=lambda level, text: None)
        dvl.configure()
        dvl.activate()
        stamps = []
        try:
            end_s = time.monotonic() + 1.5
            while time.monotonic() < end_s:
                dvl.read(time.monotonic())
                stamps += [m.stamp_s for m in dvl.state().measurements]
                time.sleep(0.01)
        finally:
            dvl.put_back()
            dvl.release()
    assert len(stamps) >= 5
    assert max(stamps) < 0.01  # the arrivals' smallest delay; not read forward to 0.5-2 s
