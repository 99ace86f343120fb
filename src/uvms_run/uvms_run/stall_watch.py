"""Notice a graph whose simulated time stands still: a hang turned into an error.

In one process the simulator's own timers handle a late or lost answer (``lockstep_timeout_s``
steps on the last command; ``startup.timeout_s`` ends a start-up that never closes the loop),
so simulated time always moves on within those limits. If it does not, something below them
is stuck (an executor that stopped delivering, a timer that never fired); ``run_graph`` then
stops with an error naming the simulated time and the wall time waited, instead of spinning
forever. Pure; wall times in seconds of a monotonic clock.

Example::

    watch = StallWatch(limit_s=151.0)
    watch.check(sim_time_ns=0, wall_s=0.0)        # None: just started
    watch.check(sim_time_ns=0, wall_s=155.0)      # the message: 155 s without progress
"""

from __future__ import annotations

#: Wall time allowed beyond the simulator's own longest wait before the graph counts as stalled.
MARGIN_S = 30.0


def stall_limit_s(startup_timeout_s: float, lockstep_timeout_s: float) -> float:
    """Wall time without simulated progress after which a graph is stalled (s).

    The simulator's longest wait at one simulated time: ``startup.timeout_s`` for the
    recorder (``startup.recorder``), again for the loop to close, then a lockstep timeout.
    """
    return 2.0 * startup_timeout_s + lockstep_timeout_s + MARGIN_S


class StallWatch:
    """Wall time since simulated time last moved, against a limit."""

    def __init__(self, limit_s: float) -> None:
        """Watch with a limit (s, > 0) on the wall time without simulated progress."""
        if limit_s <= 0.0:
            raise ValueError(f'stall limit must be > 0 s, got {limit_s}')
        self.limit_s = limit_s
        self._sim_ns: int | None = None
        self._since_s = 0.0

    def check(self, sim_time_ns: int, wall_s: float) -> str | None:
        """None while simulated time moves (or has not stood still too long), else why not."""
        if sim_time_ns != self._sim_ns:
            self._sim_ns, self._since_s = sim_time_ns, wall_s
            return None
        waited_s = wall_s - self._since_s
        if waited_s <= self.limit_s:
            return None
        return (f'simulated time stood still at t = {sim_time_ns * 1e-9:.3f} s for '
                f'{waited_s:.0f} s of wall time (limit {self.limit_s:.0f} s, beyond the '
                f"simulator's own start-up and lockstep timeouts): the graph is stalled")
