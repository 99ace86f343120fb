"""uvms_common.scheduling: what a loop process asks for, and the one line when refused."""

from __future__ import annotations

import errno
import os
import shutil
import subprocess
import sys

import pytest
from uvms_common.scheduling import Scheduling, apply_scheduling, parse_cpus

from uvms_common import scheduling

#: Runs a command without CAP_SYS_NICE and with RLIMIT_RTPRIO 0, even as root.
UNPRIVILEGED = ['prlimit', '--rtprio=0', 'setpriv', '--inh-caps=-sys_nice',
                '--bounding-set=-sys_nice']


@pytest.mark.parametrize(('text', 'cpus'), [('', ()), ('1', (1,)), ('0,2-3', (0, 2, 3)),
                                            (1, (1,)), ([0, 1], (0, 1))])
def test_cpus_parse_as_taskset_lists(text: object, cpus: tuple[int, ...]) -> None:
    """CPU lists read as taskset writes them; an empty one is every CPU."""
    assert parse_cpus(text) == cpus


@pytest.mark.parametrize('priority', [-1, 100])
def test_priority_out_of_range_is_refused_by_name(priority: int) -> None:
    """A SCHED_FIFO priority outside 0-99 names the parameter."""
    with pytest.raises(ValueError, match='rt_priority'):
        Scheduling(priority)


def test_nothing_asked_changes_nothing() -> None:
    """The default request applies nothing and warns of nothing."""
    outcome = apply_scheduling(Scheduling())
    assert outcome.applied == [] and outcome.refused == ''


def test_pinning_to_an_allowed_cpu_takes_effect() -> None:
    """A process pinned to one of its CPUs runs only there; restored afterwards."""
    before = {tid: os.sched_getaffinity(tid) for tid in scheduling.threads()}
    cpu = min(before[os.getpid()])
    try:
        outcome = apply_scheduling(Scheduling(cpus=(cpu,)))
        assert all(os.sched_getaffinity(tid) == {cpu} for tid in before)
    finally:
        for tid, cpus in before.items():
            os.sched_setaffinity(tid, cpus)
    assert outcome.applied == [f'CPUs {cpu}']


def test_a_refused_priority_gives_one_line_naming_what_to_change(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """EPERM from sched_setscheduler: one line with limits.conf, ulimit -r, CAP_SYS_NICE."""
    def refuse(*_: object) -> None:
        raise PermissionError(errno.EPERM, 'Operation not permitted')

    monkeypatch.setattr(scheduling.os, 'sched_setscheduler', refuse)
    outcome = apply_scheduling(Scheduling(priority=50))
    assert outcome.applied == []
    assert '\n' not in outcome.refused
    for hint in ('SCHED_FIFO 50', 'limits.conf', 'rtprio', 'ulimit -r', 'CAP_SYS_NICE',
                 'running on at normal priority'):
        assert hint in outcome.refused


@pytest.mark.skipif(shutil.which('setpriv') is None or shutil.which('prlimit') is None,
                    reason='needs setpriv and prlimit (util-linux)')
def test_fifo_probe_tells_a_process_without_the_capability_it_is_refused() -> None:
    """Without CAP_SYS_NICE and RLIMIT_RTPRIO 0 the probe returns the warning line."""
    code = 'from uvms_common.scheduling import fifo_refusal; print(fifo_refusal(50))'
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join(p for p in sys.path if p)}
    result = subprocess.run([*UNPRIVILEGED, sys.executable, '-c', code], env=env,
                            capture_output=True, text=True, check=True, timeout=60)
    assert result.stdout.startswith('real-time scheduling refused (SCHED_FIFO 50')
    assert 'RLIMIT_RTPRIO 0, no CAP_SYS_NICE' in result.stdout


def test_throttling_is_worded_from_the_kernel_files() -> None:
    """The kernel's real-time throttling is read, not assumed."""
    assert scheduling.throttling() != ''
