"""Loop processes on SCHED_FIFO: granted where allowed, one warning and running on where not.

Tests run as root here, where SCHED_FIFO is granted; the refused case drops CAP_SYS_NICE
(``setpriv``) and sets RLIMIT_RTPRIO 0 (``prlimit``) for the process it starts, as an
unprivileged user's login has them.
"""

from __future__ import annotations

import io
import os
import resource
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

BIN = Path(sys.executable).parent
#: Runs a command without CAP_SYS_NICE and with RLIMIT_RTPRIO 0, even as root.
UNPRIVILEGED = ['prlimit', '--rtprio=0', 'setpriv', '--inh-caps=-sys_nice',
                '--bounding-set=-sys_nice']
#: Line of a node whose request was granted (``uvms_common.node_main.schedule_process``).
GRANTED = 'real-time scheduling: SCHED_FIFO 50'
REFUSED = 'real-time scheduling refused (SCHED_FIFO 50'

pytestmark = pytest.mark.skipif(shutil.which('setpriv') is None or shutil.which('prlimit')
                                is None, reason='needs setpriv and prlimit (util-linux)')


def child_env() -> dict[str, str]:
    """This test's sources first on the children's path, and the module's ROS domain."""
    return {**os.environ, 'PYTHONUNBUFFERED': '1',
            'PYTHONPATH': os.pathsep.join(p for p in sys.path if p)}


def fifo_allowed() -> bool:
    """Whether this test process may start SCHED_FIFO children."""
    from uvms_common.scheduling import fifo_refusal

    return fifo_refusal(50) == ''


def simulator_alone(prefix: list[str]) -> subprocess.Popen[str]:
    """The simulator's console script alone, in real time, asking for SCHED_FIFO 50."""
    command = [str(BIN / 'simulator'), '--ros-args', '-r', '__ns:=/rt_test',
               '-p', 'mode:=realtime', '-p', 'rt_priority:=50']
    return subprocess.Popen([*prefix, *command], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, env=child_env(),
                            stdin=subprocess.DEVNULL)


def read_until(process: subprocess.Popen[str], text: str, timeout_s: float) -> list[str]:
    """Lines of the process's output up to the one holding ``text``; fail after the timeout."""
    assert process.stdout is not None
    os.set_blocking(process.stdout.fileno(), False)
    lines: list[str] = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if line:
            lines.append(line)
            if text in line:
                return lines
        elif process.poll() is not None:
            break
        else:
            time.sleep(0.05)
    process.kill()
    pytest.fail(f'{text!r} not seen within {timeout_s} s:\n{"".join(lines)}')


def stop(process: subprocess.Popen[str]) -> int:
    """SIGINT, then the exit status."""
    process.send_signal(signal.SIGINT)
    try:
        return process.wait(timeout=20)
    except subprocess.TimeoutExpired:
        process.kill()
        raise


def test_a_node_given_rt_priority_runs_sched_fifo_at_that_priority() -> None:
    """``-p rt_priority:=50`` with permission: every thread of the process runs FIFO 50.

    The middleware's threads too (Fast DDS receive threads, started before the node asks):
    they deliver the messages the loop waits for.
    """
    if not fifo_allowed():
        pytest.skip('SCHED_FIFO not allowed here (uvms doctor says why)')
    process = simulator_alone([])
    try:
        read_until(process, GRANTED, 60.0)
        policy = os.sched_getscheduler(process.pid)
        priority = os.sched_getparam(process.pid).sched_priority
        # Field 41 of /proc/PID/stat is the policy too (1: SCHED_FIFO), after the comm field.
        stat_policy = int(Path(f'/proc/{process.pid}/stat').read_text()
                          .rsplit(')', 1)[1].split()[41 - 3])
        tids = [int(tid) for tid in os.listdir(f'/proc/{process.pid}/task')]
        thread_policies = {os.sched_getscheduler(tid) for tid in tids}
    finally:
        status = stop(process)
    assert (policy, priority, stat_policy) == (os.SCHED_FIFO, 50, 1)
    assert len(tids) > 1 and thread_policies == {os.SCHED_FIFO}
    assert status in (0, 130)


def test_a_node_refused_the_priority_warns_once_and_runs_on() -> None:
    """Without CAP_SYS_NICE: one warning naming limits.conf, ulimit -r and CAP_SYS_NICE."""
    process = simulator_alone(UNPRIVILEGED)
    try:
        lines = read_until(process, REFUSED, 60.0)
        time.sleep(1.0)
        running = process.poll() is None
        policy = os.sched_getscheduler(process.pid)
    finally:
        status = stop(process)
    assert process.stdout is not None
    lines += process.stdout.readlines()
    warnings = [line for line in lines if REFUSED in line]
    assert len(warnings) == 1, lines
    assert '[WARN]' in warnings[0]
    for hint in ('limits.conf', 'ulimit -r', 'CAP_SYS_NICE'):
        assert hint in warnings[0]
    assert running and policy == os.SCHED_OTHER
    assert status in (0, 130)


def test_uvms_launch_refused_the_priority_warns_once_and_the_run_succeeds() -> None:
    """``uvms launch`` without the capability: one launcher warning, nodes normal, exit 0."""
    # No scenario, so no mission: without priorities on a busy machine a mission may abort
    # (the reason for the priorities), which is not what this test is about.
    result = subprocess.run([*UNPRIVILEGED, str(BIN / 'uvms'), 'launch', '--duration', '1'],
                            capture_output=True, text=True,
                            env=child_env(), timeout=180, stdin=subprocess.DEVNULL)
    warnings = [line for line in result.stderr.splitlines() if REFUSED in line]
    assert result.returncode == 0, result.stderr
    assert len(warnings) == 1, result.stderr
    assert warnings[0].startswith('uvms launch: warning: real-time scheduling refused')
    assert GRANTED not in result.stderr
    assert 'normal priority; running until' in result.stderr


def test_a_loop_node_launched_at_fifo_runs_on_under_its_runaway_guard() -> None:
    """Started as ``uvms launch`` starts it: the start-up passes, the loop gets 2 s / 3 s.

    The start-up (imports, model, kernels: 1-2 s without a blocking call) runs under the
    30 s start-up guard; the running loop blocks every period, so its 2 s guard never fires.
    """
    from uvms_bringup.launch_helpers import SIMULATOR
    from uvms_bringup.processes import Launcher, NodeProcessSpec
    from uvms_common.scheduling import LOOP_RTTIME_S

    if not fifo_allowed():
        pytest.skip('SCHED_FIFO not allowed here (uvms doctor says why)')
    command = (str(BIN / 'simulator'), '--ros-args', '-r', '__ns:=/rt_test', '-p',
               'mode:=realtime', '-p', 'rt_priority:=50')
    output = _Lines()
    launcher = Launcher([NodeProcessSpec(SIMULATOR, 'simulator-1', command, rt_priority=50)],
                        env=child_env(), stdout=output, stderr=output)
    launcher.start()
    try:
        deadline = time.monotonic() + 60.0
        while GRANTED not in output.text() and time.monotonic() < deadline:
            assert launcher.running(), output.text()
            time.sleep(0.1)
        assert 'runaway guard 2 s (RLIMIT_RTTIME)' in output.text()
        pid = launcher.processes[0].popen.pid
        limit = resource.prlimit(pid, resource.RLIMIT_RTTIME)
        time.sleep(2 * LOOP_RTTIME_S[1])
        alive = bool(launcher.running())
    finally:
        launcher.stop()
    assert limit == (round(LOOP_RTTIME_S[0] * 1e6), round(LOOP_RTTIME_S[1] * 1e6))
    assert alive, output.text()
    assert launcher.processes[0].status in (0, 130), output.text()


class _Lines(io.StringIO):
    """The launcher's and the node's output, kept."""

    def text(self) -> str:
        """Everything written so far."""
        return self.getvalue()
