"""The lockstep timeout's clock: wall time waited while the simulator's process ran on time.

``lockstep_timeout_s`` exists to notice an answer that will not come (a node process died,
a message was lost), not a busy machine. Measured as plain wall time it also fires when the
simulator's own executor could not run: on a loaded machine (issue 29: a CI runner, a flood
of foreign inputs queued ahead of the exchange's own messages) an exchange waited 1.8-9.8 s
of wall time while the answer was on its way, and the run stepped on an old command. So the
wait is counted from the checks of a periodic timer: each check adds the wall time since
the previous one if that is at most two timer periods, else nothing. A process that runs its
timer on time counts wall time as it passes; a starved or backlogged one (its timer late, or
run back to back from a queue) counts nothing for the intervals it missed. An answer that
will not come leaves the exchange idle, the process then runs its timer on time, and the
timeout still fires. Pure; times in nanoseconds of any clock.

Example::

    wait = AttentiveWait(check_period_ns=250_000_000)
    wait.start(0)
    wait.check(250_000_000)    # 250 ms: on time, counted in full
    wait.check(5_250_000_000)  # 5 s late (the process starved): counts nothing
"""

from __future__ import annotations


class AttentiveWait:
    """Wall time waited for an answer, counted only while the waiting process ran on time."""

    def __init__(self, check_period_ns: int) -> None:
        """Counter checked by a timer of period ``check_period_ns`` (> 0)."""
        if check_period_ns <= 0:
            raise ValueError(f'check period must be > 0 ns, got {check_period_ns}')
        self.cap_ns = 2 * check_period_ns
        self.counted_ns = 0
        self.wall_ns = 0
        self._start_ns = 0
        self._last_ns = 0

    def start(self, now_ns: int) -> None:
        """A new wait begins (the state was published)."""
        self._start_ns = self._last_ns = now_ns
        self.counted_ns = self.wall_ns = 0

    def check(self, now_ns: int) -> int:
        """One timer check; the counted wait so far (ns)."""
        step = max(0, now_ns - self._last_ns)
        self._last_ns = max(self._last_ns, now_ns)
        if step <= self.cap_ns:  # a late check: the process was not there to wait
            self.counted_ns += step
        self.wall_ns = max(0, now_ns - self._start_ns)
        return self.counted_ns
