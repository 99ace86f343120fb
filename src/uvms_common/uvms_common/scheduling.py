"""Real-time scheduling of a loop process: SCHED_FIFO, CPU pinning and locked memory.

As ros2_control's controller manager does for its update thread, a loop process (simulator,
controller, allocator, estimator, hardware bridges) asks Linux for ``SCHED_FIFO`` at a
priority (``DEFAULT_RT_PRIORITY``, 50); a process of normal priority then cannot delay it.
Where the system refuses (no ``CAP_SYS_NICE``, an ``RLIMIT_RTPRIO`` below the priority, a
container), ``refusal_line`` is the one warning naming what to change, and the process runs
on at normal priority. The kernel's real-time throttling (``/proc/sys/kernel/
sched_rt_runtime_us``: 950 ms of every 1 s by default) leaves other processes 5 % of each
CPU, so a runaway real-time loop slows the machine instead of freezing it; and the runaway
guard ends it: a process that asks for SCHED_FIFO also gets ``RLIMIT_RTTIME``
(``LOOP_RTTIME_S``), the CPU time a real-time thread may use without one blocking call. A
healthy loop blocks every period (waiting for its timer or its input), which starts the count
again; one that spins gets SIGXCPU from the kernel after 2 s (its default action ends the
process) and SIGKILL after 3 s. The kernel does the counting in its scheduler tick, so the
guard needs no CPU of its own.

Pure standard library: no rclpy (``uvms_common.node_main`` reads the node's parameters).

Example::

    outcome = apply_scheduling(Scheduling(priority=50, cpus=(1,)))
    if outcome.refused:
        logger.warning(outcome.refused)
"""

from __future__ import annotations

import ctypes
import errno
import os
import resource
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

#: SCHED_FIFO priority of the loop processes (ros2_control's controller manager uses 50).
DEFAULT_RT_PRIORITY = 50
#: Highest SCHED_FIFO priority on Linux.
MAX_RT_PRIORITY = 99
#: mlockall flags (linux/mman.h): the pages mapped now and those mapped later.
MCL_CURRENT = 1
MCL_FUTURE = 2
#: Bit of CAP_SYS_NICE in the capability sets (linux/capability.h).
CAP_SYS_NICE = 23
#: The kernel's real-time throttling: runtime allowed to real-time tasks per period (µs).
RT_RUNTIME_FILE = Path('/proc/sys/kernel/sched_rt_runtime_us')
RT_PERIOD_FILE = Path('/proc/sys/kernel/sched_rt_period_us')
#: RLIMIT_RTTIME of a loop process once it runs its loop (soft, hard; s of CPU at SCHED_FIFO
#: without a blocking call): SIGXCPU at the soft limit, SIGKILL at the hard one.
LOOP_RTTIME_S = (2.0, 3.0)
#: RLIMIT_RTTIME while a loop process starts (set by ``uvms launch`` between fork and exec,
#: beside its SCHED_FIFO): imports and kernels ran 1-2 s without a blocking call here (a 1 s
#: limit ended the simulator's start-up, 2 s did not), and a kernel compiled at a first start
#: runs for seconds more; the process tightens it to ``LOOP_RTTIME_S`` once built.
STARTUP_RTTIME_S = (30.0, 31.0)

_HOW_TO_ALLOW = (
    'allow it with `@GROUP - rtprio 98` (and `memlock unlimited` for locked memory) in '
    '/etc/security/limits.conf and a new login, `ulimit -r 98` in the starting shell, or the '
    'CAP_SYS_NICE capability (`setcap cap_sys_nice+ep`; in a container `--cap-add SYS_NICE`); '
    '`--no-rt` (or rt_priority 0) runs without asking')


@dataclass(frozen=True)
class Scheduling:
    """What a process asks for.

    Attributes:
        priority: SCHED_FIFO priority, 1-99; 0 keeps the normal scheduler (SCHED_OTHER).
        cpus: CPUs to pin the process to; empty: every CPU.
        lock_memory: Lock every page now and later in RAM (``mlockall``), so that no page
            fault reaches the disk in a period.
    """

    priority: int = 0
    cpus: tuple[int, ...] = ()
    lock_memory: bool = False

    def __post_init__(self) -> None:
        if not 0 <= self.priority <= MAX_RT_PRIORITY:
            msg = f'rt_priority must be 0 (normal) to {MAX_RT_PRIORITY}, got {self.priority}'
            raise ValueError(msg)
        if any(cpu < 0 for cpu in self.cpus):
            msg = f'rt_cpus must be CPU numbers >= 0, got {list(self.cpus)}'
            raise ValueError(msg)

    @property
    def asks(self) -> bool:
        """Whether anything beyond the defaults is asked for."""
        return bool(self.priority or self.cpus or self.lock_memory)


@dataclass
class Outcome:
    """What the system granted.

    Attributes:
        applied: What took effect, worded for a log line (``SCHED_FIFO 50``, ``CPUs 1``).
        refused: The one warning line when something was refused, else ''.
    """

    applied: list[str] = field(default_factory=list)
    refused: str = ''


def parse_cpus(value: object) -> tuple[int, ...]:
    """CPUs from ``'0,2-3'``, ``1``, ``[0, 1]`` or ``''`` (every CPU: empty)."""
    if isinstance(value, bool):
        raise ValueError(f'CPUs: expected numbers, got {value!r}')
    if isinstance(value, int):
        return (value,)
    if isinstance(value, (list, tuple)):
        return tuple(int(v) for v in value)
    cpus: list[int] = []
    for part in str(value).replace(' ', '').split(','):
        if not part:
            continue
        first, _, last = part.partition('-')
        try:
            cpus += range(int(first), int(last or first) + 1)
        except ValueError:
            msg = f'CPUs: expected a list such as 0,2-3, got {value!r}'
            raise ValueError(msg) from None
    return tuple(cpus)


def _mlockall() -> None:
    """Lock the process's pages in RAM; OSError with the errno when refused."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.mlockall(MCL_CURRENT | MCL_FUTURE) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code))


def has_sys_nice() -> bool | None:
    """Whether this process holds CAP_SYS_NICE (effective set); None where unknown."""
    try:
        for line in Path('/proc/self/status').read_text().splitlines():
            if line.startswith('CapEff:'):
                return bool(int(line.split()[1], 16) >> CAP_SYS_NICE & 1)
    except (OSError, ValueError):
        pass
    return None


def may_lower_niceness(nice: int) -> bool:
    """Whether a process of this user may start at niceness ``nice`` (below 0).

    CAP_SYS_NICE, or a soft RLIMIT_NICE of at least 20 - nice (setrlimit(2)).
    """
    if has_sys_nice():
        return True
    limit = resource.getrlimit(resource.RLIMIT_NICE)[0]
    return limit == resource.RLIM_INFINITY or limit >= 20 - nice


def rtprio_limit() -> str:
    """This process's soft RLIMIT_RTPRIO, worded (``0``, ``98``, ``unlimited``)."""
    rtprio = resource.getrlimit(resource.RLIMIT_RTPRIO)[0]
    return 'unlimited' if rtprio == resource.RLIM_INFINITY else str(rtprio)


def refusal_line(what: str, exc: OSError) -> str:
    """The one warning line of a refused request, naming what to change."""
    capability = {True: 'CAP_SYS_NICE held', False: 'no CAP_SYS_NICE',
                  None: 'CAP_SYS_NICE unknown'}[has_sys_nice()]
    return (f'real-time scheduling refused ({what}: {exc.strerror or exc}; RLIMIT_RTPRIO '
            f'{rtprio_limit()}, {capability}): running on at normal priority; '
            f'{_HOW_TO_ALLOW}')


def limit_rt_time(soft_s: float, hard_s: float, pid: int = 0) -> None:
    """Set RLIMIT_RTTIME of a process, never raising what is already lower.

    Lowering a limit needs no privilege; a limit set lower by the administrator or the
    launcher stays.

    Args:
        soft_s: CPU time without a blocking call after which the kernel sends SIGXCPU (s).
        hard_s: CPU time without a blocking call after which it sends SIGKILL (s).
        pid: The process (0: this one).

    Raises:
        OSError: The system refused (another user's process).
    """
    wanted = (round(soft_s * 1e6), round(hard_s * 1e6))
    current = resource.prlimit(pid, resource.RLIMIT_RTTIME)
    soft, hard = (w if c == resource.RLIM_INFINITY else min(c, w)
                  for c, w in zip(current, wanted, strict=True))
    resource.prlimit(pid, resource.RLIMIT_RTTIME, (min(soft, hard), hard))


def rt_time_limit_s(pid: int = 0) -> tuple[float, float] | None:
    """RLIMIT_RTTIME of a process (soft, hard; s); None where unlimited or unreadable."""
    try:
        soft, hard = resource.prlimit(pid, resource.RLIMIT_RTTIME)
    except OSError:
        return None
    if soft == resource.RLIM_INFINITY:
        return None
    return soft * 1e-6, (float('inf') if hard == resource.RLIM_INFINITY else hard * 1e-6)


def threads(pid: int = 0) -> list[int]:
    """Thread ids of a process (0: this one), from /proc; ``[pid]`` where unreadable.

    Linux schedules threads: ``sched_setscheduler`` and ``sched_setaffinity`` of a pid set
    that one thread only. A node process has threads before it asks (Fast DDS's receive and
    event threads, the EventsExecutor's): left at normal priority, a busy machine delays the
    messages its loop waits for (measured: 340 ms gaps, a run aborted, beside other work).
    Threads started later inherit from the thread that starts them.
    """
    try:
        return sorted(int(t) for t in os.listdir(f'/proc/{pid or "self"}/task'))
    except OSError:
        return [pid]


def apply_scheduling(request: Scheduling, pid: int = 0) -> Outcome:
    """Ask for what ``request`` names, for every thread; refusals in ``Outcome.refused``.

    Pinning comes first (it needs no privilege), then locked memory, then the priority with
    its runaway guard (``LOOP_RTTIME_S``). The guard's count starts at this call: a start-up
    that ran at SCHED_FIFO without blocking (imports, kernels) does not count against it.

    Args:
        request: What to ask for.
        pid: The process (0: this one).
    """
    outcome = Outcome()
    refused: list[tuple[str, OSError]] = []
    tids = threads(pid)
    if request.cpus:
        try:
            for tid in tids:
                os.sched_setaffinity(tid, request.cpus)
            outcome.applied.append('CPUs ' + ','.join(map(str, request.cpus)))
        except OSError as exc:  # a CPU that does not exist or is not allowed (cpuset)
            refused.append((f'CPUs {list(request.cpus)}', exc))
    if request.lock_memory:
        try:
            _mlockall()
            outcome.applied.append('memory locked')
        except OSError as exc:
            refused.append(('mlockall', exc))
    if request.priority:
        try:
            for tid in tids:
                os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(request.priority))
            outcome.applied.append(f'SCHED_FIFO {request.priority}')
        except OSError as exc:
            refused.append((f'SCHED_FIFO {request.priority}', exc))
        else:
            try:
                outcome.applied.append(_guard_runaway(pid))
            except OSError as exc:
                refused.append(('RLIMIT_RTTIME', exc))
    if refused:
        what = ', '.join(name for name, _ in refused)
        first = refused[0][1]
        if first.errno in (errno.EPERM, errno.ENOMEM, errno.EAGAIN):
            outcome.refused = refusal_line(what, first)
        else:
            outcome.refused = f'{what} refused: {first}: running on without it'
    return outcome


def _guard_runaway(pid: int) -> str:
    """Set the loop's RLIMIT_RTTIME (``LOOP_RTTIME_S``), counted from now; the guard, worded."""
    limit_rt_time(*LOOP_RTTIME_S, pid)
    if not pid:
        time.sleep(0.001)  # one blocking call: this thread's count starts again
    limit = rt_time_limit_s(pid)
    return f'runaway guard {limit[0]:g} s (RLIMIT_RTTIME)' if limit else 'no runaway guard'


def fifo_refusal(priority: int = DEFAULT_RT_PRIORITY) -> str:
    """'' when a new process of this user may run SCHED_FIFO at ``priority``, else the line.

    Tried in a child (``python -I -S``, about 20 ms), so this process keeps its scheduler.
    """
    code = ('import os, sys\ntry:\n'
            f'    os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param({priority:d}))\n'
            'except OSError as exc:\n    sys.exit(exc.errno)\n')
    result = subprocess.run([sys.executable, '-I', '-S', '-c', code], check=False,
                            capture_output=True)
    if result.returncode == 0:
        return ''
    return refusal_line(f'SCHED_FIFO {priority}',
                        OSError(result.returncode, os.strerror(result.returncode)))


def throttling() -> str:
    """The kernel's real-time throttling, worded: ``950 ms of every 1000 ms`` or ``off``."""
    try:
        runtime_us = int(RT_RUNTIME_FILE.read_text())
        period_us = int(RT_PERIOD_FILE.read_text())
    except (OSError, ValueError):
        return 'unknown'
    if runtime_us < 0:
        return 'off (sched_rt_runtime_us -1: a runaway real-time loop can freeze the machine)'
    return (f'{runtime_us / 1000:g} ms of every {period_us / 1000:g} ms for real-time tasks '
            '(sched_rt_runtime_us)')
