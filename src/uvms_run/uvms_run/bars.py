"""tqdm bars of a run (simulated seconds) and of a sweep (points), on a terminal or in a log."""

from __future__ import annotations

import os
import sys
from typing import Any, TextIO

from tqdm import tqdm

#: Run: simulated seconds done of the total, wall time elapsed < ETA, real-time factor.
RUN_FORMAT = ('{l_bar}{bar}| {n:.2f}/{total_s:.2f} s simulated '
              '[{elapsed}<{remaining}, {real_time_factor}]')
#: Sweep: points done of the total (skipped ones included), failures, wall time elapsed < ETA.
POINT_FORMAT = '{l_bar}{bar}| {n}/{total_points} points, {failed} failed [{elapsed}<{remaining}]'


class LineBar(tqdm):
    """tqdm on a terminal; elsewhere (a log file, CI) one whole line per tenth of the total.

    On a terminal the bar redraws in place, at most every ``mininterval`` (0.1 s). A log keeps
    every redraw, so off a terminal the bar writes a line ending in a newline only when the
    progress reaches the next tenth, and has nothing to clear at the end. Rates and the ETA
    are averages over the whole run (``smoothing=0``), not recent speeds.

    Args:
        args: tqdm's positional arguments.
        file: Where to write; stderr by default.
        kwargs: tqdm's keyword arguments.
    """

    #: No monitor thread: with ``miniters=0`` every update looks at the clock anyway.
    monitor_interval = 0

    def __init__(self, *args: Any, file: TextIO | None = None, **kwargs: Any) -> None:
        stream = file if file is not None else sys.stderr
        self.on_terminal = bool(getattr(stream, 'isatty', lambda: False)())
        self.logged_tenth = -1
        if not self.on_terminal:
            kwargs.update(mininterval=0.0, leave=False)
        elif not _has_size(stream):
            # A pseudo-terminal without a size (``script``, some CI runners) says 0 x 0, which
            # tqdm takes as no room for the bar: it would draw nothing.
            kwargs.setdefault('ncols', 80)
            kwargs.setdefault('nrows', 24)
        kwargs.setdefault('smoothing', 0.0)
        super().__init__(*args, file=stream, miniters=0, **kwargs)

    def display(self, msg: str | None = None, pos: int | None = None) -> bool:
        """Redraw on a terminal; elsewhere write a line when a new tenth is reached."""
        if self.on_terminal:
            return bool(super().display(msg, pos))
        if msg is not None or not self.total:
            return False  # clearing the line: a log keeps it
        tenth = int(10.0 * self.n / self.total + 1e-9)
        if tenth <= self.logged_tenth:
            return False
        self.logged_tenth = tenth
        self.fp.write(f'{self}\n')
        self.fp.flush()
        return True


class RunBar(LineBar):
    """Progress of a run: simulated seconds done of the total, ETA, real-time factor.

    Example:
        >>> import io
        >>> log = io.StringIO()
        >>> bar = RunBar(2.0, file=log)
        >>> bar.update_to(2.0)
        >>> bar.close()
        >>> '2.00/2.00 s simulated' in log.getvalue().splitlines()[-1]
        True

    Args:
        total_s: Simulated duration of the run (s).
        file: Where to write; stderr by default.
        kwargs: Further tqdm keyword arguments.
    """

    def __init__(self, total_s: float, file: TextIO | None = None, **kwargs: Any) -> None:
        super().__init__(total=max(total_s, 1e-9), file=file, bar_format=RUN_FORMAT, **kwargs)

    def update_to(self, sim_time_s: float) -> None:
        """Report the simulated time reached (s); redraws when due."""
        self.update(sim_time_s - self.n)

    @property
    def format_dict(self) -> dict[str, Any]:
        """The fields of tqdm plus ``total_s`` and ``real_time_factor`` (simulated over wall)."""
        fields: dict[str, Any] = super().format_dict
        elapsed_s = fields['elapsed']
        factor = f'{self.n / elapsed_s:.2f}x' if elapsed_s > 0.0 else '?x'
        return {**fields, 'total_s': self.total, 'real_time_factor': f'{factor} real time'}


class PointBar(LineBar):
    """Progress of a sweep: points done of the total, failures, ETA.

    The ETA is the mean wall time per point finished in this invocation times the points left:
    points skipped on resume count as done (tqdm's ``initial``) and cost nothing.

    Args:
        total: Points of the sweep.
        already_done: Points skipped because the table already holds them.
        file: Where to write; stderr by default.
        kwargs: Further tqdm keyword arguments.
    """

    def __init__(self, total: int, already_done: int = 0, file: TextIO | None = None,
                 **kwargs: Any) -> None:
        self.failed = 0
        super().__init__(total=max(total, 1), initial=already_done, file=file, unit='point',
                         bar_format=POINT_FORMAT, **kwargs)

    def point_done(self, failed: bool) -> None:
        """Count one finished point (failed or not); redraws when due."""
        self.failed += int(failed)
        self.update()

    @property
    def format_dict(self) -> dict[str, Any]:
        """The fields of tqdm plus ``total_points`` and ``failed``."""
        fields: dict[str, Any] = super().format_dict
        return {**fields, 'total_points': self.total, 'failed': self.failed}


def _has_size(stream: TextIO) -> bool:
    """Whether the terminal behind ``stream`` reports a width (True if it cannot be asked)."""
    try:
        return os.get_terminal_size(stream.fileno()).columns > 0
    except (AttributeError, OSError, ValueError):
        return True
