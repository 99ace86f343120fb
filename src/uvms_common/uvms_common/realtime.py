"""Start-up-aware staleness alarms and counted real-time misses of a periodic node (pure).

A real-time launch starts its nodes one after the other, loads their compiled kernels and
waits for the first ``/clock``: for a moment every node sees old inputs or falls behind,
which is no fault. `StalenessMonitor` logs such a start-up state at INFO and alarms (WARN)
only after a start-up grace; `MissCounter` counts the periods a timer did not run on time
and says when their share in a window passes a threshold. Times are nanoseconds of the
node's clock (the epoch does not matter, only differences); nothing here reads a clock.

Example::

    staleness = StalenessMonitor(grace_ns=2_000_000_000)
    staleness.observe(0, stale=True)              # Event('info', 'waiting'): at start-up
    staleness.observe(10_000_000, stale=False)    # Event('info', 'fresh')
    staleness.observe(3_000_000_000, stale=True)  # Event('warn', 'stale'): a real alarm
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any, Literal

#: Start-up time during which a node reports stale inputs or lateness at INFO only (s).
STARTUP_GRACE_S = 2.0
#: Share of missed periods in a window above which a node warns (fraction).
MISS_WARN_SHARE = 0.01
#: Length of the window over which a node checks its share of missed periods (s).
MISS_WINDOW_S = 10.0


@dataclass(frozen=True)
class Event:
    """A change the node logs.

    Attributes:
        level: 'info' or 'warn'.
        kind: 'waiting' (stale during start-up), 'fresh' (first fresh input), 'stale'
            (stale after start-up), 'resumed' (fresh again after 'stale'), or 'never_fresh'
            (the grace passed without one fresh input).
    """

    level: Literal['info', 'warn']
    kind: Literal['waiting', 'fresh', 'stale', 'resumed', 'never_fresh']


class StalenessMonitor:
    """Staleness that alarms only after a start-up grace; INFO while the node waits."""

    def __init__(self, grace_ns: int = round(STARTUP_GRACE_S * 1e9)) -> None:
        """Monitor with ``grace_ns`` of start-up, counted from the first observation."""
        self.grace_ns = grace_ns
        self._start_ns: int | None = None
        self._been_fresh = False
        self._alarmed = False
        self.stale = False

    @property
    def alarmed(self) -> bool:
        """True while a stale state is reported as a fault (after the start-up grace)."""
        return self._alarmed

    def observe(self, now_ns: int, stale: bool) -> Event | None:
        """Take one observation; the event to log, if the state changed."""
        if self._start_ns is None:
            self._start_ns = now_ns
        started = now_ns - self._start_ns >= self.grace_ns
        was_stale, self.stale = self.stale, stale
        if not stale:
            first = not self._been_fresh
            self._been_fresh = True
            resumed = self._alarmed
            self._alarmed = False
            if resumed:
                return Event('info', 'resumed')
            return Event('info', 'fresh') if first else None
        if self._alarmed:
            return None
        if started:
            self._alarmed = True
            return Event('warn', 'stale' if self._been_fresh else 'never_fresh')
        return None if was_stale else Event('info', 'waiting')


class MissCounter:
    """Periods of a timer that did not run, counted from the times its callback ran.

    A callback that runs ``k`` periods after the previous one missed ``k - 1`` periods
    (rounded to the nearest period); a callback that ran but could not do its work (``ran``
    False: e.g. no new simulated time to control) misses its own period too. Periods before
    the start-up grace are not counted.
    """

    def __init__(
        self,
        period_ns: int,
        grace_ns: int = round(STARTUP_GRACE_S * 1e9),
        window_ns: int = round(MISS_WINDOW_S * 1e9),
        warn_share: float = MISS_WARN_SHARE,
    ) -> None:
        """Counter of a timer of period ``period_ns``; warns above ``warn_share`` per window."""
        if period_ns <= 0:
            raise ValueError(f'period must be > 0 ns, got {period_ns}')
        self.period_ns = period_ns
        self.grace_ns = grace_ns
        self.window_ns = window_ns
        self.warn_share = warn_share
        self.periods = 0
        self.missed = 0
        self._start_ns: int | None = None
        self._last_ns: int | None = None
        self._window_start_ns: int | None = None
        self._window = [0, 0]  # periods, missed
        #: Largest delay of a callback beyond its period, after the grace (ns).
        self.worst_late_ns = 0
        _COUNTERS.add(self)

    @property
    def share(self) -> float | None:
        """Missed share of all counted periods (None before any)."""
        return self.missed / self.periods if self.periods else None

    def tick(self, now_ns: int, ran: bool = True, on_time: bool = False) -> float | None:
        """Count one run of the callback; the window's missed share when it is due and high.

        Args:
            now_ns: When the callback ran.
            ran: Whether it did its work (False: its period counts as missed).
            on_time: Count exactly one period, however late the callback ran (a callback
                that catches up by itself, as the real-time simulator's does).

        Returns:
            The missed share of the window that just ended if it exceeds ``warn_share``
            (the node warns with it), else None.
        """
        if self._start_ns is None:
            self._start_ns = now_ns
        last, self._last_ns = self._last_ns, now_ns
        if now_ns - self._start_ns < self.grace_ns:
            return None
        if self._window_start_ns is None:  # the first tick after the grace: counting starts
            self._window_start_ns = now_ns
            return None
        assert last is not None
        elapsed = 1
        self.worst_late_ns = max(self.worst_late_ns, now_ns - last - self.period_ns)
        if not on_time and now_ns > last:
            elapsed = max(1, round((now_ns - last) / self.period_ns))
        missed = elapsed - 1 + (not ran)
        self.periods += elapsed
        self.missed += missed
        self._window[0] += elapsed
        self._window[1] += missed
        if now_ns - self._window_start_ns < self.window_ns:
            return None
        periods, missed = self._window
        self._window_start_ns, self._window = now_ns, [0, 0]
        share = missed / periods
        return share if share > self.warn_share else None


#: Every MissCounter of this process (a node's figures for diagnostics and its launcher).
_COUNTERS: weakref.WeakSet[MissCounter] = weakref.WeakSet()


def process_periods() -> dict[str, Any]:
    """The periods of every MissCounter of this process, summed: what its launcher prints.

    Returns:
        ``periods``, ``missed``, ``missed_share`` (None before any period) and
        ``worst_late_ms`` (largest delay of a callback beyond its period, ms; None without
        a counter).
    """
    counters = list(_COUNTERS)
    periods = sum(c.periods for c in counters)
    missed = sum(c.missed for c in counters)
    return {'periods': periods, 'missed': missed,
            'missed_share': missed / periods if periods else None,
            'worst_late_ms': (max(c.worst_late_ns for c in counters) * 1e-6
                              if counters else None)}


class EventLogger:
    """The INFO and WARN lines of a node's `StalenessMonitor` events, worded by the node."""

    def __init__(self, logger: Any, lines: dict[str, str]) -> None:
        """Lines by event kind ('waiting', 'fresh', 'stale', 'resumed', 'never_fresh').

        Args:
            logger: The node's logger (``info`` and ``warning`` methods, as rclpy's).
            lines: What to say for each kind; a kind without a line is not logged.
        """
        self._logger = logger
        self._lines = lines

    def log(self, event: Event | None) -> None:
        """Log an event at its level (nothing for None)."""
        if event is None or event.kind not in self._lines:
            return
        line = self._lines[event.kind]
        if event.level == 'warn':
            self._logger.warning(line)
        else:
            self._logger.info(line)
