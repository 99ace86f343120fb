"""The run's progress bar (tqdm): one line per tenth of the run off a terminal, redraws on one."""

import io
import os
import pty
import re
import select
import sys

import pytest
from uvms_run.bars import RunBar


def eta_s(line: str) -> int:
    """The ETA of a bar line, ``[elapsed<MM:SS, ...]``, in seconds."""
    match = re.search(r'<(\d+):(\d\d)[,\]]', line)
    assert match is not None, line
    return 60 * int(match[1]) + int(match[2])


def test_progress_off_a_terminal_writes_one_line_per_tenth() -> None:
    """Updated every 10 ms of a 1 s run, a log gets eleven whole lines, 0 % to 100 %."""
    stream = io.StringIO()
    bar = RunBar(1.0, file=stream)
    for k in range(101):
        bar.update_to(k * 0.01)
    bar.close()
    lines = stream.getvalue().splitlines()
    assert len(lines) == 11
    assert '  0%' in lines[0] and '0.00/1.00 s simulated' in lines[0]
    assert '100%' in lines[-1] and '1.00/1.00 s simulated' in lines[-1]
    assert all('x real time' in line for line in lines)
    assert '\r' not in stream.getvalue()


def test_progress_shows_real_time_factor_and_eta() -> None:
    """500 of 2000 simulated seconds in 1000 s of wall time: 0.5x real time, 3000 s to go."""
    stream = io.StringIO()
    bar = RunBar(2000.0, file=stream)
    bar.start_t -= 1000.0  # the run started 1000 s of wall time ago
    bar.update_to(500.0)
    line = stream.getvalue().splitlines()[-1]
    assert '500.00/2000.00 s simulated' in line
    assert '0.50x real time' in line
    assert 2990 <= eta_s(line) <= 3030


class _Terminal(io.StringIO):
    """A stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def test_progress_on_a_terminal_redraws_in_place() -> None:
    """On a terminal the bar is redrawn with carriage returns and ends with one newline."""
    stream = _Terminal()
    bar = RunBar(2.0, file=stream, mininterval=0.0)
    bar.update_to(1.0)
    bar.update_to(2.0)
    bar.close()
    text = stream.getvalue()
    assert text.count('\r') >= 3
    assert text.endswith('\n') and text.count('\n') == 1
    assert '2.00/2.00 s simulated' in text.split('\r')[-1]


def test_progress_on_a_terminal_without_a_size_still_draws(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A pseudo-terminal that reports 0 x 0 (``script``, some CI runners) still gets the bar."""
    master, slave = pty.openpty()  # a new pseudo-terminal has no size until one is set
    with os.fdopen(slave, 'w') as stream:
        assert os.get_terminal_size(slave).columns == 0
        monkeypatch.setattr(sys, 'stderr', stream)  # tqdm asks the size of stderr's terminal
        bar = RunBar(2.0)
        bar.update_to(2.0)
        bar.close()
    chunks = []
    try:
        while select.select([master], [], [], 0.5)[0]:
            chunks.append(os.read(master, 65536))
    except OSError:  # EIO: drained, and the terminal side is closed
        pass
    os.close(master)
    text = b''.join(chunks).decode()
    assert '2.00/2.00 s simulated' in text
