"""A command watchdog: no command for ``timeout_s`` and the bridge's actuators go neutral.

Pure (no clock of its own): the caller passes its node's time in seconds, so lockstep,
real time and tests all drive it the same way. A bridge feeds it on each accepted command
and asks `expired` on each of its send periods; while expired it sends neutral, and it
stays expired until a new command arrives (never resumes on an old one)::

    watchdog = CommandWatchdog(timeout_s=0.1)
    watchdog.feed(t_s)          # a command arrived
    if watchdog.expired(t_s):   # send neutral instead of the last command
        ...
"""

from __future__ import annotations

import math


class CommandWatchdog:
    """Times out when no command has been fed for ``timeout_s`` seconds.

    Before the first command it counts as expired: nothing is sent but neutral until a
    command arrives.
    """

    def __init__(self, timeout_s: float) -> None:
        if not (math.isfinite(timeout_s) and timeout_s > 0.0):
            raise ValueError(f'watchdog timeout_s = {timeout_s!r}: expected seconds > 0')
        self.timeout_s = timeout_s
        self._last_s: float | None = None
        #: How many times it has gone from fed to expired (for /diagnostics).
        self.trips = 0
        self._tripped = True

    def feed(self, t_s: float) -> None:
        """A command arrived at time ``t_s`` (s)."""
        self._last_s = t_s
        self._tripped = False

    def expired(self, t_s: float) -> bool:
        """True when the last command is older than the timeout at ``t_s`` (or none came)."""
        stale = self._last_s is None or t_s - self._last_s > self.timeout_s
        if stale and not self._tripped:
            self._tripped = True
            self.trips += 1
        return stale

    def age_s(self, t_s: float) -> float:
        """Seconds since the last command (inf before the first)."""
        return math.inf if self._last_s is None else t_s - self._last_s
