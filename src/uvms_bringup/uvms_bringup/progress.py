"""Plain-text progress bar of a run on stderr, in simulated seconds."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class ProgressBar:
    """Progress of a run: bar, simulated time and real-time factor.

    On a terminal the bar redraws in place (carriage return) at most ``redraw_hz`` times
    per wall-clock second; elsewhere (a log file, CI) it writes one line per tenth of the
    run, so logs stay short.

    Args:
        total_s: Simulated duration of the run (s).
        stream: Where to write; stderr by default.
        width: Number of characters of the bar.
        redraw_hz: Redraw rate limit on a terminal (1/s).
    """

    def __init__(
        self,
        total_s: float,
        stream: TextIO | None = None,
        width: int = 30,
        redraw_hz: float = 10.0,
    ) -> None:
        self._total_s = max(total_s, 1e-9)
        self._stream = stream if stream is not None else sys.stderr
        self._width = width
        self._min_interval_s = 1.0 / redraw_hz
        self._interactive = bool(getattr(self._stream, 'isatty', lambda: False)())
        # Wall-clock time only measures the run's speed for the user; it never drives it.
        self._start = time.monotonic()
        self._last_draw = -float('inf')
        self._last_tenth = -1
        self._closed = False

    def update(self, sim_time_s: float) -> None:
        """Report the simulated time reached (s); redraws when due."""
        if self._closed:
            return
        fraction = min(max(sim_time_s / self._total_s, 0.0), 1.0)
        now = time.monotonic()
        if self._interactive:
            if now - self._last_draw >= self._min_interval_s:
                self._last_draw = now
                self._stream.write('\r' + self._line(fraction, sim_time_s, now))
                self._stream.flush()
            return
        tenth = int(fraction * 10.0 + 1e-9)
        if tenth > self._last_tenth:
            self._last_tenth = tenth
            self._stream.write(self._line(fraction, sim_time_s, now) + '\n')
            self._stream.flush()

    def close(self, sim_time_s: float) -> None:
        """Draw the final state and end the line."""
        if self._closed:
            return
        if self._interactive:
            now = time.monotonic()
            self._stream.write('\r' + self._line(min(sim_time_s / self._total_s, 1.0),
                                                 sim_time_s, now) + '\n')
            self._stream.flush()
        else:
            self.update(sim_time_s)
        self._closed = True

    def _line(self, fraction: float, sim_time_s: float, now: float) -> str:
        """One line: bar, percentage, simulated time and speed."""
        filled = round(fraction * self._width)
        bar = '#' * filled + '.' * (self._width - filled)
        wall_s = now - self._start
        factor = f'{sim_time_s / wall_s:5.2f}x real time' if wall_s > 0.0 else ''
        return (
            f'[{bar}] {100.0 * fraction:5.1f}% {sim_time_s:7.2f}/{self._total_s:.2f} s '
            f'simulated, {wall_s:6.1f} s wall, {factor}'
        )


class PointProgress:
    """Progress of a sweep: bar, points done of the total, failures, elapsed time and ETA.

    The ETA is the mean wall time per point finished in this invocation times the points
    left (points skipped on resume count as done and cost nothing). On a terminal the line
    redraws in place; elsewhere one line per tenth of the points, as ``ProgressBar``.

    Args:
        total: Points of the sweep.
        already_done: Points skipped because the table already holds them.
        stream: Where to write; stderr by default.
        width: Number of characters of the bar.
    """

    def __init__(
        self, total: int, already_done: int = 0, stream: TextIO | None = None, width: int = 30
    ) -> None:
        self._total = max(total, 1)
        self._skipped = already_done
        self._done = already_done
        self._failed = 0
        self._stream = stream if stream is not None else sys.stderr
        self._width = width
        self._interactive = bool(getattr(self._stream, 'isatty', lambda: False)())
        self._start = time.monotonic()
        self._last_tenth = -1
        self._closed = False
        self._draw()

    def update(self, failed: bool) -> None:
        """Count one finished point (failed or not) and redraw."""
        self._done += 1
        self._failed += int(failed)
        self._draw()

    def close(self) -> None:
        """End the line."""
        if not self._closed and self._interactive:
            self._stream.write('\n')
            self._stream.flush()
        self._closed = True

    def _draw(self) -> None:
        """Redraw (terminal) or write a line per tenth (log)."""
        if self._closed:
            return
        line = self._line(time.monotonic())
        if self._interactive:
            self._stream.write('\r' + line)
            self._stream.flush()
            return
        tenth = int(10.0 * self._done / self._total + 1e-9)
        if tenth > self._last_tenth:
            self._last_tenth = tenth
            self._stream.write(line + '\n')
            self._stream.flush()

    def _line(self, now: float) -> str:
        """One line: bar, points, failures, elapsed and remaining wall time."""
        fraction = min(self._done / self._total, 1.0)
        filled = round(fraction * self._width)
        bar = '#' * filled + '.' * (self._width - filled)
        elapsed = now - self._start
        ran = self._done - self._skipped
        left = self._total - self._done
        eta = f'ETA {_duration(elapsed / ran * left)}' if ran > 0 else 'ETA --'
        return (f'[{bar}] {self._done}/{self._total} points, {self._failed} failed, '
                f'{_duration(elapsed)} elapsed, {eta}')


def _duration(seconds: float) -> str:
    """Wall time as ``42 s``, ``3.5 min`` or ``1.2 h``."""
    if seconds < 90.0:
        return f'{seconds:.0f} s'
    if seconds < 5400.0:
        return f'{seconds / 60.0:.1f} min'
    return f'{seconds / 3600.0:.1f} h'
