"""A real-time loop that spins is ended by the kernel within 5 s, named, and the launch stops.

The loop processes of ``uvms launch`` run SCHED_FIFO; one that never blocks would hold its
CPU (issue 47: two such processes starved the launcher for 10 minutes). Here a stand-in loop
process asks for its scheduling as a node does (``apply_scheduling``) and spins, pinned to
CPU 0 beside a stand-in recorder that writes a line every 50 ms; both are started by the
launcher's own process API (``Launcher``, ``run_launch``). The tests run as root here and in
CI; where SCHED_FIFO is refused they skip, naming why.
"""

from __future__ import annotations

import io
import os
import sys
import threading
import time
from pathlib import Path

import pytest
from uvms_bringup.launch_helpers import RECORDER, NodeSpec
from uvms_bringup.launcher import run_launch
from uvms_bringup.processes import EXIT_FAILURE, Launcher, NodeProcessSpec
from uvms_common.process_costs import CostWatch
from uvms_common.scheduling import LOOP_RTTIME_S, fifo_refusal

#: The guard must end a spinning loop within this long after it starts spinning (s).
STOPPED_WITHIN_S = 5.0
#: The hard limit's SIGKILL: 3 s of CPU, which a FIFO task gets at most 95 % of
#: (sched_rt_runtime_us), then the launcher's report; 5.15 s seen in a suite run.
KILLED_WITHIN_S = 8.0
#: The test gives up (a stop request) after this long: the old code never stops the spinner.
GIVE_UP_S = 20.0

SPINNER = NodeSpec('spinner', 'test', 'spinner', 'spinner', '', ())
#: A loop process that asks for SCHED_FIFO 50 on CPU 0 as a node does, then spins.
SPIN = """
import signal, sys
from uvms_common.scheduling import Scheduling, apply_scheduling
if 'ignore-sigxcpu' in sys.argv:
    signal.signal(signal.SIGXCPU, signal.SIG_IGN)
print(', '.join(apply_scheduling(Scheduling(priority=50, cpus=(0,))).applied), flush=True)
print('spinning', flush=True)
while True:
    pass
"""
#: The recorder's stand-in, on the spinner's CPU: a line every 50 ms, 'closed' on SIGINT.
BEAT = """
import os, signal, time
signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # as a node's StopEvent does
# Its own handler, as StopEvent installs one: started from a background job, SIGINT comes
# ignored (bash's asynchronous commands), and the stand-in then never closed.
signal.signal(signal.SIGINT, signal.default_int_handler)
os.sched_setaffinity(0, {0})
try:
    while True:
        print('beat', flush=True)
        time.sleep(0.05)
except KeyboardInterrupt:
    print('closed', flush=True)
"""

pytestmark = pytest.mark.skipif(bool(fifo_refusal(50)),
                                reason=f'SCHED_FIFO refused here: {fifo_refusal(50)}')


class TimedLines(io.TextIOBase):
    """A text stream that keeps each line with the monotonic time it was written."""

    def __init__(self) -> None:
        self.lines: list[tuple[float, str]] = []
        self._lock = threading.Lock()

    def write(self, text: str) -> int:
        """Keep the text's lines, stamped now."""
        with self._lock:
            now = time.monotonic()
            self.lines += [(now, line) for line in text.splitlines() if line]
        return len(text)

    def first(self, text: str) -> float | None:
        """When the first line holding ``text`` came, None if none did."""
        return next((t for t, line in self.lines if text in line), None)

    def text(self) -> str:
        """Every line, for a failure's message."""
        return '\n'.join(line for _, line in self.lines)


class GiveUp:
    """A stop request set ``GIVE_UP_S`` after it was made."""

    def __init__(self) -> None:
        self._end = time.monotonic() + GIVE_UP_S

    def is_set(self) -> bool:
        """Whether the time is up."""
        return time.monotonic() >= self._end


def launch_spinner(tmp_path: Path, *spinner_args: str) -> tuple[int, TimedLines, TimedLines,
                                                                 Launcher]:
    """Launch the spinner and the recorder's stand-in; exit status, stdout, stderr, launcher."""
    env = {**os.environ, 'PYTHONUNBUFFERED': '1',
           'PYTHONPATH': os.pathsep.join(p for p in sys.path if p)}
    # The recorder first, and without site (-I -S), so that it is in its loop before the
    # spinner takes CPU 0 (a SIGINT during Python's start-up ends it with status 1).
    plans = [NodeProcessSpec(RECORDER, 'recorder-1', (sys.executable, '-I', '-S', '-c', BEAT)),
             NodeProcessSpec(SPINNER, 'spinner-2',
                             (sys.executable, '-c', SPIN, *spinner_args), rt_priority=50)]
    out, err = TimedLines(), TimedLines()
    launcher = Launcher(plans, env=env, stdout=out, stderr=err, sigterm_timeout_s=2.0,
                        sigkill_timeout_s=2.0)
    status = run_launch(launcher, GiveUp(), 'realtime', None, False, '',
                        CostWatch(tmp_path / 'stats'))
    return status, out, err, launcher


def test_a_spinning_loop_is_stopped_within_5_s_named_and_the_launch_stops(
        tmp_path: Path) -> None:
    """SIGXCPU at 2 s without blocking: one line naming it; the recorder closes cleanly."""
    status, out, err, launcher = launch_spinner(tmp_path)
    spinning = out.first('[spinner-2] spinning')
    line = (f"uvms launch: error: node 'spinner' (spinner-2) stopped: real-time loop ran "
            f'{LOOP_RTTIME_S[0]:g} s without blocking (RLIMIT_RTTIME); stopped the other nodes')
    reported = err.first(line)
    assert spinning is not None, out.text() + err.text()
    assert 'SCHED_FIFO 50, runaway guard 2 s (RLIMIT_RTTIME)' in out.text()
    assert reported is not None, err.text()
    assert reported - spinning < STOPPED_WITHIN_S
    assert status == EXIT_FAILURE
    recorder = launcher.processes[0]
    assert recorder.status == 0 and '[recorder-1] closed' in out.text(), out.text()
    assert 'still running' not in err.text()


def test_a_spinning_loop_that_ignores_sigxcpu_is_killed_at_the_hard_limit(
        tmp_path: Path) -> None:
    """SIGXCPU ignored: SIGKILL at 3 s, still within 5 s, the line names the hard limit."""
    status, out, err, launcher = launch_spinner(tmp_path, 'ignore-sigxcpu')
    spinning = out.first('[spinner-2] spinning')
    reported = err.first("node 'spinner' (spinner-2) stopped: killed by SIGKILL: real-time "
                         f'loop ran {LOOP_RTTIME_S[1]:g} s without blocking '
                         "(RLIMIT_RTTIME's hard limit); stopped the other nodes")
    assert spinning is not None and reported is not None, out.text() + err.text()
    assert reported - spinning < KILLED_WITHIN_S
    assert status == EXIT_FAILURE
    assert launcher.processes[0].status == 0
