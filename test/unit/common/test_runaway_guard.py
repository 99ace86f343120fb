"""The runaway guard of a real-time process: RLIMIT_RTTIME set, never raised, worded.

Each case runs in a child process: a limit set on the test process would be inherited by
the real-time node processes later tests start, and end their start-up.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from uvms_common.scheduling import LOOP_RTTIME_S, fifo_refusal


def run_child(code: str) -> object:
    """Run ``code`` in a child Python on this test's path; what it printed, as JSON."""
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join(p for p in sys.path if p)}
    result = subprocess.run([sys.executable, '-c', code], env=env, capture_output=True,
                            text=True, check=True, timeout=60)
    return json.loads(result.stdout)


def test_a_granted_priority_comes_with_the_loop_guard() -> None:
    """SCHED_FIFO granted: RLIMIT_RTTIME 2 s soft, 3 s hard, and the log line says so."""
    if fifo_refusal(50):
        pytest.skip(f'SCHED_FIFO refused here: {fifo_refusal(50)}')
    code = ('import json, resource\n'
            'from uvms_common.scheduling import Scheduling, apply_scheduling\n'
            'outcome = apply_scheduling(Scheduling(priority=50))\n'
            'print(json.dumps([outcome.applied, outcome.refused,\n'
            '                  resource.getrlimit(resource.RLIMIT_RTTIME)]))\n')
    applied, refused, limit = run_child(code)  # type: ignore[misc]
    assert refused == ''
    assert applied == ['SCHED_FIFO 50', 'runaway guard 2 s (RLIMIT_RTTIME)']
    assert limit == [round(LOOP_RTTIME_S[0] * 1e6), round(LOOP_RTTIME_S[1] * 1e6)]


def test_the_guard_never_raises_a_lower_limit() -> None:
    """An administrator's 1 s / 1.5 s stays; an unlimited one becomes the loop's."""
    code = ('import json, resource\n'
            'from uvms_common.scheduling import LOOP_RTTIME_S, limit_rt_time\n'
            'resource.setrlimit(resource.RLIMIT_RTTIME, (1_000_000, 1_500_000))\n'
            'limit_rt_time(*LOOP_RTTIME_S)\n'
            'low = resource.getrlimit(resource.RLIMIT_RTTIME)\n'
            'print(json.dumps(low))\n')
    assert run_child(code) == [1_000_000, 1_500_000]


def test_a_refused_priority_sets_no_guard() -> None:
    """SCHED_FIFO refused: nothing to guard, the limit stays as it was."""
    code = ('import errno, json, os, resource\n'
            'from uvms_common import scheduling\n'
            'def refuse(*_):\n'
            '    raise PermissionError(errno.EPERM, "Operation not permitted")\n'
            'scheduling.os.sched_setscheduler = refuse\n'
            'outcome = scheduling.apply_scheduling(scheduling.Scheduling(priority=50))\n'
            'print(json.dumps([outcome.applied,\n'
            '                  resource.getrlimit(resource.RLIMIT_RTTIME)[0] ==\n'
            '                  resource.RLIM_INFINITY]))\n')
    assert run_child(code) == [[], True]
