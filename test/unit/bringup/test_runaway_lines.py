"""How the launcher words a node's end: the runaway guard named, other ends as before."""

from __future__ import annotations

import signal
import subprocess
from typing import cast

import pytest
from uvms_bringup.launch_helpers import CONTROLLER, RECORDER
from uvms_bringup.processes import NodeProcess, NodeProcessSpec, end_line


def ended(status: int, rt_priority: int = 50, sent: tuple[signal.Signals, ...] = (),
          limit: tuple[float, float] | None = (2.0, 3.0),
          soft_min: float | None = None) -> NodeProcess:
    """A node process that ended with ``status``, last seen with ``limit``."""
    spec = CONTROLLER if rt_priority else RECORDER
    plan = NodeProcessSpec(spec, f'{spec.executable}-1', ('x',), rt_priority=rt_priority)
    if soft_min is None and limit is not None:
        soft_min = limit[0]
    return NodeProcess(plan, cast(subprocess.Popen[bytes], None), status, list(sent), limit,
                       soft_min)


def test_sigxcpu_names_the_loop_that_ran_without_blocking() -> None:
    """SIGXCPU: the soft limit it ran past, and RLIMIT_RTTIME."""
    assert end_line(ended(-signal.SIGXCPU)) == (
        'stopped: real-time loop ran 2 s without blocking (RLIMIT_RTTIME)')


def test_sigxcpu_seen_after_the_kernel_raised_the_soft_limit_names_the_first_limit() -> None:
    """The limit last read as (3, 3), between the SIGXCPU and the end: still 2 s (CI, py3.12)."""
    assert end_line(ended(-signal.SIGXCPU, limit=(3.0, 3.0), soft_min=2.0)) == (
        'stopped: real-time loop ran 2 s without blocking (RLIMIT_RTTIME)')


def test_a_sigkill_after_a_survived_sigxcpu_names_the_hard_limit() -> None:
    """SIGKILL once the kernel raised the soft limit to the hard one: the hard limit."""
    assert end_line(ended(-signal.SIGKILL, limit=(31.0, 31.0))) == (
        "stopped: killed by SIGKILL: real-time loop ran 31 s without blocking (RLIMIT_RTTIME's "
        'hard limit)')


@pytest.mark.parametrize(('process', 'line'), [
    (ended(-signal.SIGKILL, sent=(signal.SIGINT, signal.SIGTERM, signal.SIGKILL)),
     'exited: killed by SIGKILL'),
    (ended(-signal.SIGKILL, rt_priority=0, limit=None), 'exited: killed by SIGKILL'),
    (ended(-signal.SIGKILL), 'exited: killed by SIGKILL'),  # kill -9: no SIGXCPU before
    (ended(1), 'exited: status 1'),
    (ended(-signal.SIGXCPU, limit=None),
     'stopped: real-time loop ran without blocking (RLIMIT_RTTIME)'),
])
def test_other_ends_are_worded_as_before(process: NodeProcess, line: str) -> None:
    """The launcher's own SIGKILL, kill -9, a normal process, an error status: as before."""
    assert end_line(process) == line
