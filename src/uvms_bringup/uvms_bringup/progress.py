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
