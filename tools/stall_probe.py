"""A pytest plugin that names what stalled a test process: the CPU, or a thread of its own.

Issue 48's UDP device tests failed with the twin "silent" for 1-3 s. This plugin tells the
two causes apart: a sampler thread wakes every 20 ms; when it could not run for longer than
``STALL_S``, it writes one record with, per thread of the process, the CPU time it got and
the time it spent waiting on a run queue in the gap (``/proc/self/task/*/schedstat``), and
the main thread's stack before and after. Every thread waiting on the run queue for the
whole gap is CPU starvation (other tasks ran); a thread that ran through it (or slept in
I/O, neither running nor waiting) is a stall of the process' own (the GIL held, a lock).

    PYTHONPATH=tools .venv/bin/python -m pytest -p stall_probe test/integration/test_X.py

Records go to ``$UVMS_STALL_LOG`` (default ``/tmp/uvms_stall_probe.log``), with the start
and end of each test. Not loaded by the suite: the sampler's wakeups cost CPU of their own.
"""

from __future__ import annotations

import os
import sys
import threading
import time
import traceback
from collections import deque
from pathlib import Path

#: A sampler gap longer than this (s) is written down.
STALL_S = 0.25
#: The sampler's period (s).
PERIOD_S = 0.02
LOG_PATH = Path(os.environ.get('UVMS_STALL_LOG', '/tmp/uvms_stall_probe.log'))
_START_S = time.monotonic()


def _log(message: str) -> None:
    with LOG_PATH.open('a') as stream:
        stream.write(f'[{os.getpid()} {time.monotonic() - _START_S:8.3f}] {message}\n')


def thread_times() -> dict[int, tuple[str, float, float]]:
    """Each thread of this process: (name, CPU time s, run-queue wait s) so far."""
    out: dict[int, tuple[str, float, float]] = {}
    for tid in os.listdir('/proc/self/task'):
        try:
            ran_ns, waited_ns, _ = Path(f'/proc/self/task/{tid}/schedstat').read_text().split()
            name = Path(f'/proc/self/task/{tid}/comm').read_text().strip()
        except (OSError, ValueError):
            continue
        out[int(tid)] = (name, int(ran_ns) * 1e-9, int(waited_ns) * 1e-9)
    return out


def _main_stack() -> str:
    frame = sys._current_frames().get(threading.main_thread().ident or 0)
    return ''.join(traceback.format_stack(frame, limit=10)) if frame is not None else ''


def _sample() -> None:
    last_s, before, stack = time.monotonic(), thread_times(), ''
    stacks: deque[str] = deque(maxlen=2)
    while True:
        time.sleep(PERIOD_S)
        now_s, now = time.monotonic(), thread_times()
        stack = _main_stack()
        stacks.append(stack)
        if now_s - last_s > STALL_S:
            lines = [f'  {tid} {name}: ran {ran - before[tid][1]:.3f} s, run-queue wait '
                     f'{waited - before[tid][2]:.3f} s'
                     for tid, (name, ran, waited) in now.items() if tid in before]
            _log(f'STALL {now_s - last_s:.3f} s\n' + '\n'.join(lines)
                 + '\n main thread before:\n' + stacks[0] + ' main thread after:\n' + stack)
        last_s, before = now_s, now


threading.Thread(target=_sample, name='stall probe', daemon=True).start()


def pytest_runtest_logstart(nodeid: str, location: object) -> None:
    """Mark a test's start in the log."""
    _log(f'start {nodeid}')


def pytest_runtest_logfinish(nodeid: str, location: object) -> None:
    """Mark a test's end in the log."""
    _log(f'end {nodeid}')
