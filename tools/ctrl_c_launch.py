#!/usr/bin/env python3
"""Stop ``uvms launch SCENARIO --output F`` with Ctrl-C N times; count the clean, quick ends.

Each run starts the launch, waits until the recording holds its first message (a complete
chunk: the graph runs), sends SIGINT as a terminal's Ctrl-C would, and counts the run clean
when the launcher exited 130 within ``--within`` seconds, escalated to no SIGTERM or SIGKILL,
and left an MCAP file with its summary and messages. Loopback only: run it inside
``tools/loopback-netns``; each run gets a ROS domain of its own.

    tools/loopback-netns .venv/bin/python tools/ctrl_c_launch.py --runs 20
"""

from __future__ import annotations

import argparse
import io
import os
import signal
import struct
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Chunk
from mcap.stream_reader import StreamReader

#: Longest wait for the first recorded message of a run (s), on a loaded 2-core machine.
START_TIMEOUT_S = 120.0
#: Longest wait for the launcher after SIGINT before it is killed (s): above its own
#: SIGINT -> SIGTERM -> SIGKILL escalation of two node groups.
STOP_TIMEOUT_S = 40.0


@dataclass(frozen=True)
class Run:
    """One stopped launch: status, seconds from SIGINT to exit, what was wrong, and notes."""

    status: int | None
    stop_s: float
    problems: tuple[str, ...]
    notes: tuple[str, ...] = ()

    def clean(self, within_s: float) -> bool:
        """Exit 130 within the time, a readable recording, no escalation."""
        return not self.problems and self.status == 130 and self.stop_s <= within_s


def holds_a_chunk(path: Path) -> bool:
    """Whether the file being written holds a complete chunk (the first messages landed)."""
    if not path.exists():
        return False
    try:
        return any(isinstance(record, Chunk) for record in
                   StreamReader(io.BytesIO(path.read_bytes()), emit_chunks=True).records)
    except (McapError, EOFError, struct.error):
        return False  # the writer's last record is not complete yet


def recording_problem(path: Path) -> str | None:
    """Why the recording is not a closed MCAP file with messages, or None."""
    try:
        with path.open('rb') as stream:
            reader = make_reader(stream)
            summary = reader.get_summary()
            if summary is None or summary.statistics is None:
                return 'recording not closed (no summary)'
            read = sum(1 for _ in reader.iter_messages())
    except (OSError, McapError, EOFError, struct.error) as exc:
        return f'recording unreadable: {exc}'
    if read == 0 or read != summary.statistics.message_count:
        return f'recording: {read} messages read, summary says {summary.statistics.message_count}'
    return None


def run_once(index: int, scenario: str, directory: Path, uvms: str) -> Run:
    """Start one launch, stop it with SIGINT once it records, and judge its end."""
    output = directory / f'run{index:02d}.mcap'
    log = directory / f'run{index:02d}.stderr'
    env = dict(os.environ)
    env['ROS_DOMAIN_ID'] = str(1 + (os.getpid() + index) % 100)
    with log.open('w') as stderr:
        process = subprocess.Popen([uvms, 'launch', scenario, '--output', str(output)],
                                   stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                   stderr=stderr, env=env)
        deadline = time.monotonic() + START_TIMEOUT_S
        while not holds_a_chunk(output):
            if process.poll() is not None or time.monotonic() > deadline:
                process.kill()
                process.wait()
                return Run(process.returncode, 0.0, ('no message recorded: did not start',))
            time.sleep(0.1)
        sent = time.monotonic()
        process.send_signal(signal.SIGINT)
        try:
            status: int | None = process.wait(timeout=STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
            status = None
        stop_s = time.monotonic() - sent
    lines = log.read_text(errors='replace').splitlines()
    problems = [line for line in lines if 'still running after' in line
                or 'Traceback' in line or line.startswith('uvms launch: error')]
    problem = recording_problem(output)
    if problem is not None:
        problems.append(problem)
    # A teardown that the grace period ended is clean (nothing was lost), but worth a look.
    notes = tuple(line.split(' [')[0] + ' teardown ended by its deadline'
                  for line in lines if 'teardown still running' in line)
    return Run(status, stop_s, tuple(problems), notes)


def main(argv: list[str] | None = None) -> int:
    """Run the launches and print one line per run and the count; 0 when all were clean."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--runs', type=int, default=20, help='launches to stop (default 20)')
    parser.add_argument('--scenario', default='case1_ke1e4', help='scenario to launch')
    parser.add_argument('--within', type=float, default=3.0,
                        help='seconds from SIGINT to exit that count as quick (default 3)')
    parser.add_argument('--keep', type=Path, default=None,
                        help='directory for the recordings and logs (a temporary one if unset)')
    args = parser.parse_args(argv)
    if os.environ.get('UVMS_NETNS') != 'private':
        print('ctrl_c_launch: not inside tools/loopback-netns; the DDS profile is the only '
              'guard of the network', file=sys.stderr)
    uvms = str(Path(sys.executable).parent / 'uvms')
    with tempfile.TemporaryDirectory(prefix='ctrl_c_launch_') as temporary:
        directory = args.keep or Path(temporary)
        directory.mkdir(parents=True, exist_ok=True)
        clean = 0
        for index in range(1, args.runs + 1):
            run = run_once(index, args.scenario, directory, uvms)
            clean += run.clean(args.within)
            verdict = 'clean' if run.clean(args.within) else 'NOT clean'
            detail = '; '.join(run.problems + run.notes)
            print(f'run {index:2d}: exit {run.status}, stopped in {run.stop_s:.2f} s, {verdict}'
                  + (f': {detail}' if detail else ''), flush=True)
    print(f'{clean} of {args.runs} launches ended cleanly within {args.within:g} s of Ctrl-C '
          '(exit 130, recording closed and readable, no SIGTERM or SIGKILL)')
    return 0 if clean == args.runs else 1


if __name__ == '__main__':
    sys.exit(main())
