"""The sweep's progress bar (tqdm): points done of the total, failures, ETA; a log gets lines."""

from __future__ import annotations

import io
import re

from uvms_run.bars import PointBar


def eta_s(line: str) -> int:
    """The ETA of a bar line, ``[elapsed<MM:SS]``, in seconds."""
    match = re.search(r'<(\d+):(\d\d)\]', line)
    assert match is not None, line
    return 60 * int(match[1]) + int(match[2])


def test_progress_line_counts_points_and_estimates_the_rest() -> None:
    """The bar says points done of the total, the failures and an ETA (a log: one line each)."""
    stream = io.StringIO()
    bar = PointBar(10, already_done=5, file=stream)
    bar.point_done(failed=True)
    bar.close()
    lines = stream.getvalue().splitlines()
    assert '5/10 points, 0 failed' in lines[0] and lines[0].endswith('<?]')
    assert '6/10 points, 1 failed' in lines[-1] and eta_s(lines[-1]) >= 0
    assert '\r' not in stream.getvalue()


def test_eta_is_the_mean_time_of_the_points_run_here_times_the_points_left() -> None:
    """6 points skipped, 2 run in 100 s: 50 s each, so the 2 left take 100 s."""
    stream = io.StringIO()
    bar = PointBar(10, already_done=6, file=stream)
    bar.start_t -= 100.0  # this invocation started 100 s of wall time ago
    bar.point_done(failed=False)
    bar.point_done(failed=False)
    line = stream.getvalue().splitlines()[-1]
    assert '8/10 points, 0 failed' in line
    assert 99 <= eta_s(line) <= 105


def test_progress_off_a_terminal_writes_one_line_per_tenth() -> None:
    """A 100-point sweep writes eleven lines to a log, 0 to 100 points."""
    stream = io.StringIO()
    bar = PointBar(100, file=stream)
    for _ in range(100):
        bar.point_done(failed=False)
    bar.close()
    lines = stream.getvalue().splitlines()
    assert len(lines) == 11
    assert '| 0/100 points' in lines[0] and '| 100/100 points' in lines[-1]
