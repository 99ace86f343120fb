"""`uvms launch` and `uvms run` stop on Ctrl-C or SIGTERM and leave a complete recording."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader

REPO = Path(__file__).resolve().parents[2]
SOURCES = [REPO / 'src' / name for name in
           ('uvms_common', 'uvms_bringup', 'uvms_model', 'uvms_sim', 'uvms_control')]


def start_cli(*args: str) -> subprocess.Popen[str]:
    """Start `python -m uvms_bringup.cli ARGS` (genuine rclpy of this venv)."""
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([*map(str, SOURCES), env.get('PYTHONPATH', '')])
    return subprocess.Popen([sys.executable, '-m', 'uvms_bringup.cli', *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env, cwd=REPO)


def wait_for_chunk(path: Path, process: subprocess.Popen[str], timeout_s: float = 30.0) -> None:
    """Wait until the recording exists and then grows: the graph is running and recording."""
    deadline = time.monotonic() + timeout_s
    first_size = None
    while first_size is None or path.stat().st_size <= first_size:
        assert process.poll() is None, process.communicate()[1]
        assert time.monotonic() < deadline, 'the recording did not grow'
        if first_size is None and path.exists():
            first_size = path.stat().st_size
        time.sleep(0.05)


@pytest.mark.parametrize(
    ('command', 'sig'),
    [('launch', signal.SIGINT), ('run', signal.SIGTERM)],
)
def test_signal_stops_the_graph_with_status_130_and_a_closed_recording(
    tmp_path: Path, command: str, sig: signal.Signals
) -> None:
    """The process exits 130 and the MCAP has its summary (closed, not cut short)."""
    path = tmp_path / 'stopped.mcap'
    process = start_cli(command, 'free_motion', '--output', str(path), '--quiet')
    wait_for_chunk(path, process)
    process.send_signal(sig)
    _, err = process.communicate(timeout=30)
    assert process.returncode == 130, err
    with path.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    assert summary.statistics.message_count > 0
