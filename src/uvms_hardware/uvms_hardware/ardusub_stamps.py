"""ArduSub telemetry stamped on the autopilot's own clock, mapped into the node clock. Pure.

ArduPilot times the messages the bridge publishes on its boot clock: ATTITUDE_QUATERNION and
SCALED_PRESSURE2 carry ``time_boot_ms``, RAW_IMU ``time_usec`` (``AP_HAL::micros64()``, the
same clock in µs; ``GCS_Common.cpp``). Each arrival on the node clock is that time plus the
clock offset plus a delay that is never negative, so the minimum-delay envelope of
``uvms_hardware.device_time`` maps the autopilot's time into ours, and a message the bridge
read late (its socket is drained once per override period) is stamped when the autopilot sent
it, not when it was read::

    stamper = TelemetryStamper()
    stamp_s = stamper.stamp_s('RAW_IMU', msg, arrival_s)   # node clock (s)

SYS_STATUS has no time: stamped at arrival. A stamp is never later than the arrival (nothing
is sent after it arrived). While the two clocks visibly run at different rates (a twin on wall
time beside a simulator's ``/clock``), every message is stamped at arrival and counted, never
with a wrong device time; a node on a simulated clock (``use_sim_time``) asks for that from the
start (``device_time=False``): the autopilot's clock never runs on it. TIMESYNC is not used:
the envelope gives the offset plus the link's smallest one-way delay (sub-millisecond on a
companion computer's loopback or Ethernet), which is the time the data left the autopilot.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from uvms_hardware.device_time import DeviceClockEstimator

#: The autopilot's time of each timed message (s since its boot).
DEVICE_TIME_S: dict[str, Callable[[Any], float]] = {
    'ATTITUDE_QUATERNION': lambda msg: msg.time_boot_ms * 1e-3,
    'SCALED_PRESSURE2': lambda msg: msg.time_boot_ms * 1e-3,
    'RAW_IMU': lambda msg: msg.time_usec * 1e-6,
}
#: Estimator window and bucket (s): 1 s buckets hold ~50 IMU messages each, so their earliest
#: arrival is read within a fraction of a millisecond of the poll that read it.
WINDOW_S, BUCKET_S, RESET_S = 20.0, 1.0, 0.1


class TelemetryStamper:
    """Stamps of ArduSub's telemetry on the node clock, from the autopilot's boot clock."""

    def __init__(self, window_s: float = WINDOW_S, bucket_s: float = BUCKET_S,
                 reset_s: float = RESET_S, device_time: bool = True) -> None:
        self.clock = DeviceClockEstimator(window_s, bucket_s, reset_s)
        #: False: every message at its arrival (a node on a simulated clock).
        self.device_time = device_time
        #: Timed messages stamped at their arrival (the clocks' rates differ).
        self.stamped_at_arrival = 0

    def stamp_s(self, kind: str, msg: Any, arrival_s: float) -> float:
        """When the autopilot sent ``msg`` (of type ``kind``), on the node clock (s)."""
        device_time = DEVICE_TIME_S.get(kind)
        if device_time is None:
            return arrival_s  # no time in the message (SYS_STATUS)
        device_s = device_time(msg)
        self.clock.add(device_s, arrival_s)
        local_s = self.clock.to_local(device_s) if self.clock.rates_agree else None
        if local_s is None or not self.device_time:
            self.stamped_at_arrival += 1
            return arrival_s
        return min(local_s, arrival_s)

    def report(self) -> dict[str, object]:
        """The clock estimate and the count stamped at arrival, for /diagnostics."""
        return {'stamped_at_arrival': self.stamped_at_arrival, **self.clock.report()}
