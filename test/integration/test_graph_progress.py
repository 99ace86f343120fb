"""The run's progress bar: plain text, one line per tenth of the run off a terminal."""

import io

from uvms_bringup.progress import ProgressBar


def test_progress_off_a_terminal_writes_one_line_per_tenth() -> None:
    """Updated every 10 ms of a 1 s run, a log gets eleven lines, 0 % to 100 %."""
    stream = io.StringIO()
    bar = ProgressBar(1.0, stream=stream)
    for k in range(101):
        bar.update(k * 0.01)
    bar.close(1.0)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 11
    assert '  0.0%' in lines[0] and '100.0%' in lines[-1]
    assert '1.00/1.00 s simulated' in lines[-1]
    assert '\r' not in stream.getvalue()


class _Terminal(io.StringIO):
    """A stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def test_progress_on_a_terminal_redraws_in_place() -> None:
    """On a terminal the bar is redrawn with carriage returns and ends with one newline."""
    stream = _Terminal()
    bar = ProgressBar(2.0, stream=stream, redraw_hz=1e9)
    bar.update(1.0)
    bar.close(2.0)
    text = stream.getvalue()
    assert text.count('\r') == 2
    assert text.endswith('\n') and text.count('\n') == 1
    assert '#' * 30 in text
