"""The Water Linked DVL A50/A125 (TCP JSON) as a hardware component: velocities in dvl_link.

No ROS (``dvl_bridge_node`` wraps it in a managed node). configure connects to ``address``
(`uvms_hardware.dvl_link`: a reader thread that reconnects every ``reconnect_period_s``) and
waits ``connect_timeout_s`` for it, refusing when nothing answers; `read` takes the reports
that arrived (never waits) and turns each valid (bottom-locked) one while active into a
velocity in ``dvl_link`` (the DVL's frame, ``mounting_rpy_rad``, turned into dvl_link) with
its covariance (the report's, else fom^2), stamped with the report's own
``time_of_validity`` (µs on the DVL's clock) mapped into the local clock through the offset
`uvms_hardware.device_time` estimates from each report's ``time_of_transmission`` against its
arrival (read on the local clock through the steady one, `uvms_hardware.arrival_clock`: a
``/clock`` that stood while the process was starved would map later reports early); a report
without a time of validity, or while the clocks visibly run at different rates, is stamped
at its arrival and counted. Each report is given once, when it arrives: a silent DVL gives
nothing and is not fresh after ``timeout_s``. A sensor: nothing on the DVL is changed, so
`put_back` only says so::

    dvl = DvlComponent(values, rot_link_from_dvl(mounting, link_rpy))
    dvl.configure(); dvl.activate()
    dvl.read(now_s); for m in dvl.state().measurements: m.stamp_s, m.v_m_s, m.covariance
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from uvms_hardware.address import LOOPBACK, HostPort, parse_host_port
from uvms_hardware.arrival_clock import ArrivalClock
from uvms_hardware.component import (
    ERROR,
    OK,
    WARN,
    ComponentReport,
    HardwareComponent,
    LogFn,
    python_log,
)
from uvms_hardware.device_time import DeviceClockEstimator
from uvms_hardware.dvl_link import DvlLink
from uvms_hardware.dvl_protocol import VelocityReport, report_in_link
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_config import Spec
from uvms_hardware.stop_report import write_stop_report

DEFAULT_PORT = 16171
_US = 1e-6

#: The settings (the bridge node's parameters).
SPECS = (
    Spec('address', LOOPBACK, 'The DVL: HOST[:PORT] (TCP; port 16171 when not given)'),
    Spec('connect_timeout_s', 10.0, 'Wait for the connection at configure (s): the DVL may '
         'come up after the bridge (launch order)', 0.1, 120.0),
    Spec('reconnect_period_s', 1.0, 'Between connection attempts (s)', 0.05, 60.0),
    Spec('timeout_s', 1.0, 'No report this long: the DVL is silent, ERROR (s)', 0.1, 30.0),
    Spec('mounting_rpy_rad', [0.0, 0.0, 0.0], "The DVL's own frame in base_link_frd (rad)"),
    Spec('clock_window_s', 30.0, "Reports the DVL clock's offset is estimated over (s)",
         2.0, 600.0),
    Spec('clock_reset_s', 0.2, "The DVL clock's offset jumps by more than this: estimated "
         'again from the next report (s; an NTP step on the DVL)', 0.01, 10.0),
)


class DvlBridgeError(HardwareError, ValueError):
    """A parameter of the DVL bridge is invalid, or no DVL answers at configure."""


@dataclass(frozen=True)
class DvlMeasurement:
    """One bottom-locked velocity report in dvl_link.

    Attributes:
        stamp_s: When the velocity was measured, on the local clock (s).
        v_m_s: Velocity of dvl_link (m/s), shape (3,).
        covariance: Its covariance ((m/s)^2), shape (3, 3).
    """

    stamp_s: float
    v_m_s: npt.NDArray[np.float64]
    covariance: npt.NDArray[np.float64]


@dataclass(frozen=True)
class DvlState:
    """What the DVL gave at the last `DvlComponent.read`.

    Attributes:
        measurements: The valid reports that read took while active, oldest first (each once).
        fresh: False while no report came for ``timeout_s`` or the link is down.
        bottom_lock: The newest report's validity (None before the first).
    """

    measurements: tuple[DvlMeasurement, ...]
    fresh: bool
    bottom_lock: bool | None


class DvlComponent(HardwareComponent):
    """Water Linked DVL over TCP: a sensor component."""

    def __init__(self, values: Mapping[str, Any], rot: npt.NDArray[np.float64],
                 default_port: int = DEFAULT_PORT, name: str = 'dvl_bridge',
                 clock: Callable[[], float] = time.monotonic,
                 local_clock: Callable[[], float] | None = None,
                 log: LogFn = python_log) -> None:
        """A component over the DVL at ``values['address']`` (not contacted until configure).

        Args:
            values: Every setting of `SPECS` by name.
            rot: Rotation dvl_link <- the DVL's own frame (3x3).
            default_port: The port when the address names none.
            name: The node's name (stop report).
            clock: The steady clock (s): the reports' age, the watchdog.
            local_clock: The clock stamps are in (s; default ``clock``), read at each arrival.
            log: Where messages go.
        """
        super().__init__()
        self.values = dict(values)
        self.rot = rot
        self.default_port = default_port
        self.name = name
        self.clock, self.local_clock = clock, local_clock or clock
        #: Arrivals on the local clock read through the steady one: a local clock that is a
        #: ``/clock`` stands while its process is starved, and an arrival read on it would
        #: map every later report too early (`uvms_hardware.arrival_clock`).
        self.arrival_clock: ArrivalClock | None = (
            None if local_clock is None or local_clock is clock
            else ArrivalClock(local_clock, clock))
        self.log = log
        self.link: DvlLink | None = None
        self.estimator: DeviceClockEstimator | None = None
        self.address: HostPort | None = None
        #: Valid reports handed out by `state` while active (each once).
        self.published = 0
        #: Reports stamped at their arrival (no time of validity, or clocks' rates differ).
        self.stamped_at_arrival = 0
        self._measurements: tuple[DvlMeasurement, ...] = ()

    # -- lifecycle ---------------------------------------------------------------------------
    def configure(self) -> None:
        """Connect to the DVL.

        Raises:
            DvlBridgeError: No DVL answers within ``connect_timeout_s``.
            AddressError: An address that does not parse.
        """
        v = self.values
        self.address = address = parse_host_port(str(v['address']), self.default_port,
                                                 'address')
        window_s = float(v['clock_window_s'])
        self.estimator = DeviceClockEstimator(window_s, window_s / 30.0,
                                              float(v['clock_reset_s']))
        self.configured = True
        arrival = self.local_clock if self.arrival_clock is None else self.arrival_clock.now
        self.link = link = DvlLink(address, float(v['reconnect_period_s']), clock=self.clock,
                                   arrival_clock=arrival).start()
        if not link.wait_connected(float(v['connect_timeout_s'])):
            raise DvlBridgeError(f'no DVL at {address.host}:{address.port} ({link.last_error})')

    def put_back(self) -> list[str]:
        """Nothing to put back (the DVL is only listened to); said, for the launcher."""
        self.active = False
        self._measurements = ()
        done = 'nothing to put back: the DVL was only listened to'
        self.log('info', f'put back: {done}')
        write_stop_report(self.name, done, [])
        return []

    def release(self) -> None:
        """Disconnect (the reader thread stops, the connection closes)."""
        if self.link is not None:
            self.link.stop()
        self.link, self.estimator = None, None
        self._measurements = ()
        super().release()

    # -- the loop ----------------------------------------------------------------------------
    def stamp_s(self, report: VelocityReport, arrival_s: float) -> float:
        """When the report's velocity was measured, on the local clock (s)."""
        clock = self.estimator
        sent_us = report.time_of_transmission_us or report.time_of_validity_us
        if clock is None or sent_us is None or report.time_of_validity_us is None:
            self.stamped_at_arrival += 1
            return arrival_s
        clock.add(sent_us * _US, arrival_s)
        if not clock.rates_agree:
            self.stamped_at_arrival += 1
            return arrival_s
        stamp_s = clock.to_local(report.time_of_validity_us * _US)
        return arrival_s if stamp_s is None else stamp_s  # 0.0 is a time (a plant's first)

    def read(self, now_s: float) -> None:
        """The reports queued since the last read (never waits); each one times the clock.

        While configured every report feeds the DVL clock's estimate; only valid ones while
        active become measurements.
        """
        link = self.link
        measurements = []
        if self.arrival_clock is not None:
            self.arrival_clock.sample()
        if link is not None:
            for arrival_s, report in link.take():
                stamp_s = self.stamp_s(report, arrival_s)
                if not (self.active and report.valid):
                    continue
                v, cov = report_in_link(report, self.rot)
                measurements.append(DvlMeasurement(stamp_s, v, cov))
        self._measurements = tuple(measurements)
        self.published += len(measurements)

    def age_s(self, now_s: float) -> float:
        """Seconds since the last report arrived (inf before the first, or unconfigured)."""
        return math.inf if self.link is None else now_s - self.link.last_report_s

    def state(self) -> DvlState:
        """The measurements of the last read; fresh while connected and not silent."""
        link = self.link
        fresh = (link is not None and link.connected
                 and self.age_s(self.clock()) <= float(self.values['timeout_s']))
        return DvlState(self._measurements, fresh,
                        None if link is None else link.last_valid)

    def report(self, now_s: float) -> ComponentReport:
        """Connection, lock, silence, counters, the DVL clock's offset."""
        link = self.link
        if link is None:
            return ComponentReport(WARN, 'not connected', {})
        age_s = self.age_s(now_s)
        p = link.parser
        values = {'connected': link.connected,
                  'report_age_s': age_s, 'bottom_lock': link.last_valid,
                  'reports': p.reports, 'published': self.published,
                  'malformed_lines': p.malformed, 'ignored_reports': p.ignored,
                  'connects': link.connects, 'last_error': link.last_error or p.last_error,
                  'stamped_at_arrival': self.stamped_at_arrival,
                  **(self.estimator.report() if self.estimator is not None else {})}
        if not link.connected:
            return ComponentReport(ERROR, f'DVL disconnected: {link.last_error}', values)
        if age_s > float(self.values['timeout_s']):
            return ComponentReport(ERROR, f'DVL silent for {age_s:.1f} s', values)
        if link.last_valid is False:
            return ComponentReport(WARN, 'no bottom lock: velocity not published', values)
        if self.estimator is not None and not self.estimator.rates_agree:
            return ComponentReport(
                WARN, "the DVL's clock does not run at the node clock's rate (beside a "
                "simulator, the twin must run on the plant's time): stamped at arrival", values)
        return ComponentReport(OK, 'bottom lock', values)
