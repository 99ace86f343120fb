"""`uvms launch` and `uvms run` stop on Ctrl-C or SIGTERM and leave a complete recording."""

from __future__ import annotations

import io
import os
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Chunk
from mcap.stream_reader import StreamReader

REPO = Path(__file__).resolve().parents[2]
SOURCES = [REPO / 'src' / name for name in
           ('uvms_common', 'uvms_bringup', 'uvms_model', 'uvms_sim', 'uvms_control',
            'uvms_thrusters')]


def start_cli(*args: str) -> subprocess.Popen[str]:
    """Start `python -m uvms_cli.cli ARGS` (genuine rclpy of this venv)."""
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([*map(str, SOURCES), env.get('PYTHONPATH', '')])
    return subprocess.Popen([sys.executable, '-m', 'uvms_cli.cli', *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env, cwd=REPO)


def written_chunks(path: Path) -> int:
    """Complete chunks in a recording being written (0 while it has none, or no file)."""
    if not path.exists():
        return 0
    chunks = 0
    try:
        for record in StreamReader(io.BytesIO(path.read_bytes()), emit_chunks=True).records:
            chunks += isinstance(record, Chunk)
    except (McapError, EOFError, struct.error):
        pass  # the writer's last record is not complete yet
    return chunks


def wait_for_chunk(path: Path, process: subprocess.Popen[str], timeout_s: float = 60.0) -> None:
    """Wait until the recording holds a complete chunk: the graph runs and its messages land.

    The file grows before any message is written (header, schemas, channels), so its size
    alone does not say that the graph runs; on a slow machine a signal sent then finds no
    message recorded yet.
    """
    deadline = time.monotonic() + timeout_s
    while not written_chunks(path):
        assert process.poll() is None, process.communicate()[1]
        assert time.monotonic() < deadline, 'no chunk was recorded'
        time.sleep(0.1)


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
