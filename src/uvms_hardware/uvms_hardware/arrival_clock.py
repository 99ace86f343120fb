"""The node clock at an arrival, read through the steady clock: a stale ``/clock`` mended. Pure.

A bridge's reader thread stamps each arrival on the node clock, which `uvms_hardware.device_time`
then pairs with the device's own time. Under ``use_sim_time`` the node clock is the last
``/clock`` the process took, and the process takes it on its main thread: while that thread is
starved (a loaded machine, a long callback) the clock stands, and an arrival read on it is
*earlier* than it was by as long as the stall. A device-clock estimate by the minimum delay
(the lower envelope of arrival - device) takes that as the smallest delay yet and maps every
later report that much too early (a 0.5 s stall: 0.55 s early for seconds after it, until the
late buckets restart the estimate; `issue 50`, the DVL through the twin stand).

The steady clock never stands. Each reading of the node clock L at a steady time S satisfies
``S - L = c + stale`` with ``stale >= 0`` (a node clock only ever lags its own time), so the
lower envelope of ``S - L`` is the fresh relation, however the readings lag, and
``now`` answers the node clock at the steady time of the call through it: the time a fresh
``/clock`` would have read. The same `DeviceClockEstimator` finds it (the node clock as the
"device", the steady clock as "ours"), with its skew: a simulator at another real-time factor
(0.53-1.9x) is followed; beyond that the node clock is read as it is, and so is a clock that
stood longer than `MAX_STAND_S` (a simulator paused). On a wall clock (a real robot) the node
clock never stands and ``now`` is it within microseconds::

    arrival = ArrivalClock(node_now_s, time.monotonic)
    arrival.sample()          # as often as convenient (each drain of the reports)
    arrival_s = arrival.now() # at an arrival, from any thread
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from uvms_hardware.device_time import DeviceClockEstimator

#: The node clock's rate against the steady clock may differ from 1 by this (the estimator's
#: skew bound): simulators at real-time factors 0.53-1.9 are followed.
MAX_RATE_ERROR = 0.9
#: A node clock standing longer than this (s of node time) stands for good (a simulator
#: paused, or holding its first state): read as it is, not forward.
MAX_STAND_S = 2.0
#: `ArrivalClock.sample` adds a pair at most this often (s of the steady clock): two or so per
#: bucket; each new bucket refits the envelope (about 0.1 ms on this machine).
SAMPLE_PERIOD_S = 0.05


class ArrivalClock:
    """The node clock read through the steady clock (thread-safe)."""

    def __init__(self, node_clock: Callable[[], float], steady_clock: Callable[[], float],
                 window_s: float = 1.0, bucket_s: float = 0.1, reset_s: float = 0.05) -> None:
        """Read ``node_clock`` (s) through ``steady_clock`` (s).

        Args:
            node_clock: The clock stamps are in (the node's, possibly a ``/clock``).
            steady_clock: A clock that never stands (``time.monotonic``).
            window_s: Node-clock time the fresh relation is estimated over (s).
            bucket_s: Node-clock time per bucket of the estimate (s).
            reset_s: A reading this far below the relation: the node clock jumped (s).
        """
        self.node_clock = node_clock
        self.steady_clock = steady_clock
        self._estimate = DeviceClockEstimator(window_s, bucket_s, reset_s, MAX_RATE_ERROR)
        self._lock = threading.Lock()
        self._sampled_s = -float('inf')
        #: Readings answered later than the node clock read (it stood).
        self.mended = 0

    def sample(self) -> None:
        """Read both clocks and add the pair, at most every `SAMPLE_PERIOD_S` (call at will)."""
        with self._lock:
            steady_s = self.steady_clock()
            if steady_s - self._sampled_s < SAMPLE_PERIOD_S:
                return
            self._sampled_s = steady_s
            self._estimate.add(self.node_clock(), steady_s)

    def now(self) -> float:
        """The node clock now as a fresh ``/clock`` would read it (s); never before its reading."""
        with self._lock:
            node_s = self.node_clock()
            steady_s = self.steady_clock()
            estimate = self._estimate
            estimate.add(node_s, steady_s)
            at_reading = estimate.to_local(node_s)  # steady time of a fresh reading node_s
            if at_reading is None or not estimate.rates_agree:
                return node_s
            rate = estimate.to_local(node_s + 1.0)
            assert rate is not None
            steady_per_node = rate - at_reading
            late_s = (steady_s - at_reading) / steady_per_node
            if not 0.0 < late_s <= MAX_STAND_S:
                return node_s
            self.mended += 1
            return node_s + late_s
