"""Publish a topic at a lower rate than the loop that computes it, on stamps (simulated or not).

A topic no node of the control loop needs (a controller's state, the thrusters' state) may
be published less often than the loop runs, to spare the loop its messages. The gate lets
through the first stamp of every period window of the chosen rate, so a 50 Hz gate on a
500 Hz loop passes t = 0, 20, 40 ms ... in lockstep, and keeps the rate on jittery
real-time stamps without drifting.
"""

from __future__ import annotations


class RateGate:
    """Lets through the first stamp of each window of 1/rate_hz; rate 0: every message.

    Args:
        rate_hz: Rate (Hz, >= 0); 0 passes everything (a repeated stamp too: a timer on a
            paused simulated clock publishes with one stamp, as it did without a gate).
    """

    def __init__(self, rate_hz: float) -> None:
        if not rate_hz >= 0.0:
            msg = f'rate must be 0 (every stamp) or positive, got {rate_hz!r} Hz'
            raise ValueError(msg)
        self.every = rate_hz == 0.0
        self.period_ns = max(1, round(1e9 / rate_hz)) if rate_hz > 0.0 else 1
        self._window: int | None = None

    def due(self, t_ns: int) -> bool:
        """Whether a message stamped t_ns (ns) goes out: the first stamp of its window."""
        if self.every:
            return True
        window = t_ns // self.period_ns
        if window == self._window:
            return False
        self._window = window
        return True
