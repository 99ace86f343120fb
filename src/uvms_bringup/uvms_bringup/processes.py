"""Node processes of a launch: start them, copy their output, stop them in order.

Shutdown follows ``ros2 launch``: SIGINT to every node, SIGTERM after ``sigterm_timeout_s``,
SIGKILL after ``sigkill_timeout_s`` more. The recorder is stopped last, so that it records
the other nodes' last messages and then closes its file. The children run in their own
process group, so a Ctrl-C in the terminal reaches only the launcher, which decides the
order; on Linux they also receive SIGTERM if the launcher itself dies (``PR_SET_PDEATHSIG``),
so no orphaned node keeps publishing.

A loop process starts at its SCHED_FIFO priority with a start-up runaway guard
(``RLIMIT_RTTIME``, ``STARTUP_RTTIME_S``), which the node tightens to ``LOOP_RTTIME_S`` once
built (``uvms_common.scheduling``). One that spins past it is ended by the kernel (SIGXCPU,
then SIGKILL); ``end_line`` says so, and the launch stops as for any failed node.
"""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Protocol

from uvms_common.ros_environment import ros_environment_defaults
from uvms_common.scheduling import STARTUP_RTTIME_S, limit_rt_time, rt_time_limit_s
from uvms_common.stop_event import STOP_SIGNALS_BLOCKED
from uvms_tasks.mission_outcome import EXIT_MISSION_FAILED

from uvms_bringup.launch_helpers import RECORDER, SIMULATOR, NodeSpec

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_INTERRUPTED = 130

#: Seconds between SIGINT and SIGTERM, and between SIGTERM and SIGKILL (ros2 launch's).
SIGTERM_TIMEOUT_S = 5.0
SIGKILL_TIMEOUT_S = 5.0
#: Wall-clock period of the launcher's look at its children and its stop event (s).
POLL_PERIOD_S = 0.05
#: Exit statuses of a node that stopped because it was asked to (signal handled, or 0).
_STOPPED_STATUSES = (0, EXIT_INTERRUPTED, -signal.SIGINT, -signal.SIGTERM)
#: Exit statuses of a finishing node (the mission) that did its job, or whose job failed.
_FINISHED_STATUSES = (0, EXIT_MISSION_FAILED)

_PR_SET_PDEATHSIG = 1
_SIGTERM = int(signal.SIGTERM)


class LaunchError(RuntimeError):
    """A node process cannot be started; the message names the node and the command."""


class StopRequest(Protocol):
    """What the launcher polls to know that it should stop (``StopEvent``, threading.Event)."""

    def is_set(self) -> bool:
        """Whether a stop was asked for."""
        ...


@dataclass(frozen=True)
class NodeProcessSpec:
    """One node process of a launch: its label and its full command line.

    Attributes:
        spec: The node.
        label: Name in the output prefix, ``executable-N`` as ros2 launch numbers them.
        command: Executable and arguments, ``--ros-args ...`` included.
        parameters_file: The generated parameter file of the overrides, if any.
        outcome_file: Where a finishing node (the mission) writes how its job ended
            (``uvms_tasks.mission_outcome``), if anywhere.
        rt_priority: SCHED_FIFO priority the process starts with (set between fork and
            exec, so its imports and every thread it starts have it); 0: normal.
        nice: Niceness it starts with (set the same way; refused, it keeps 0): below 0 a
            normal process gets a larger share of what the SCHED_FIFO loops leave.
    """

    spec: NodeSpec
    label: str
    command: tuple[str, ...]
    parameters_file: Path | None = None
    outcome_file: Path | None = None
    rt_priority: int = 0
    nice: int = 0


@dataclass
class NodeProcess:
    """A started node process and what the launcher knows of its end.

    Attributes:
        plan: How it was started.
        popen: The process.
        status: Exit status once it ended (negative: killed by that signal), else None.
        signals_sent: Signals the launcher sent it, in order.
        rt_time_limit_s: Its RLIMIT_RTTIME (soft, hard; s) when last seen running, for a
            real-time process; None where unlimited or not looked at.
        rt_time_soft_min_s: The smallest soft RLIMIT_RTTIME seen while it ran (s): the limit
            at which a SIGXCPU was sent, as the kernel raises the soft limit by 1 s as it sends
            one and the launcher may read it between the signal and the process's end.
    """

    plan: NodeProcessSpec
    popen: subprocess.Popen[bytes]
    status: int | None = None
    signals_sent: list[signal.Signals] = field(default_factory=list)
    rt_time_limit_s: tuple[float, float] | None = None
    rt_time_soft_min_s: float | None = None

    @property
    def name(self) -> str:
        """The node's name."""
        return self.plan.spec.name

    def poll(self) -> int | None:
        """The exit status if the process has ended (kept once known)."""
        if self.status is None:
            # Kept only from a process still running after it was read: the kernel raises
            # the soft limit by 1 s as it sends SIGXCPU.
            limit = rt_time_limit_s(self.popen.pid) if self.plan.rt_priority else None
            self.status = self.popen.poll()
            if self.status is None and limit is not None:
                self.rt_time_limit_s = limit
                seen = self.rt_time_soft_min_s
                self.rt_time_soft_min_s = limit[0] if seen is None else min(seen, limit[0])
        return self.status


def describe_status(status: int) -> str:
    """An exit status as a user reads it: ``status 1``, ``killed by SIGKILL``."""
    if status < 0:
        try:
            return f'killed by {signal.Signals(-status).name}'
        except ValueError:
            return f'killed by signal {-status}'
    if status == EXIT_INTERRUPTED:
        return 'status 130 (stopped by a signal)'
    return f'status {status}'


def end_line(process: NodeProcess) -> str:
    """How a node's process ended, after ``node 'NAME' ``: ``exited: status 1``, ...

    A real-time process ended by SIGXCPU ran past its runaway guard's soft limit
    (``RLIMIT_RTTIME``). One ended by a SIGKILL the launcher did not send ran past the hard
    limit only if it had survived a SIGXCPU first, which the kernel marks by raising the soft
    limit by 1 s, up to the hard one: otherwise the SIGKILL came from elsewhere (``kill -9``,
    the out-of-memory killer) and is said as it is.
    """
    status = process.status or 0
    limit = process.rt_time_limit_s
    if process.plan.rt_priority and status == -signal.SIGXCPU:
        soft = process.rt_time_soft_min_s
        ran = f'{soft:g} s ' if soft is not None else ''
        return f'stopped: real-time loop ran {ran}without blocking (RLIMIT_RTTIME)'
    if (process.plan.rt_priority and status == -signal.SIGKILL and limit is not None
            and limit[0] >= limit[1] and signal.SIGKILL not in process.signals_sent):
        return (f'stopped: killed by SIGKILL: real-time loop ran {limit[1]:g} s without '
                "blocking (RLIMIT_RTTIME's hard limit)")
    return f'exited: {describe_status(status)}'


def _die_with_parent() -> None:  # pragma: no cover - runs in the child between fork and exec
    """Ask Linux for SIGTERM when the launcher dies, so that no node outlives it."""
    if _PRCTL is not None:
        _PRCTL(_PR_SET_PDEATHSIG, _SIGTERM)


def _child_setup(rt_priority: int, nice: int = 0) -> Callable[[], None]:
    """What the child runs between fork and exec: stops held, die with the launcher, priority.

    SIGINT is blocked (the mask survives exec and the ROS wheels' re-exec) until the node
    installs its stop handlers; SIGTERM is not, so a process that never installs them still
    ends at the launcher's SIGTERM.

    A loop process that starts at its SCHED_FIFO priority loads its modules and kernels
    ahead of the machine's other work, so the first simulated step comes sooner on a busy
    machine; its start-up runaway guard (``STARTUP_RTTIME_S``) comes with it. Refused (the
    launcher checked before), it starts at normal priority: the node asks again and warns.
    """
    def setup() -> None:  # pragma: no cover - runs in the child
        # Held (not lost) until the node's StopEvent is installed and unblocks them: a stop
        # during the interpreter's start then ends the node cleanly (uvms_common.stop_event).
        signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS_BLOCKED)
        _die_with_parent()
        if rt_priority:
            try:
                limit_rt_time(*STARTUP_RTTIME_S)
            except OSError:
                pass
            try:
                os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(rt_priority))
            except OSError:
                pass
        if nice:
            try:
                os.setpriority(os.PRIO_PROCESS, 0, nice)
            except OSError:
                pass
    return setup


def _load_prctl() -> Callable[..., int] | None:
    """The prctl function of libc, resolved before any fork (a child must not load it)."""
    if not sys.platform.startswith('linux'):
        return None
    try:
        return ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None


_PRCTL = _load_prctl()


class _Prefixer(threading.Thread):
    """Copies a child's output line by line to a stream, each line prefixed ``[label] ``."""

    def __init__(self, source: IO[bytes], target: IO[str], label: str,
                 lock: threading.Lock) -> None:
        super().__init__(name=f'output of {label}', daemon=True)
        self._source = source
        self._target = target
        self._prefix = f'[{label}] '
        self._lock = lock

    def run(self) -> None:
        for raw in iter(self._source.readline, b''):
            line = raw.decode('utf-8', errors='replace').rstrip('\r\n')
            with self._lock:
                try:
                    self._target.write(f'{self._prefix}{line}\n')
                    self._target.flush()
                except (OSError, ValueError):
                    pass  # the launcher's own output is gone (closed pipe): keep draining
        self._source.close()


class Launcher:
    """Starts node processes, watches them, and stops them in order with escalation."""

    def __init__(
        self,
        plans: Sequence[NodeProcessSpec],
        *,
        env: Mapping[str, str] | None = None,
        stdout: IO[str] | None = None,
        stderr: IO[str] | None = None,
        capture: bool = True,
        sigterm_timeout_s: float = SIGTERM_TIMEOUT_S,
        sigkill_timeout_s: float = SIGKILL_TIMEOUT_S,
    ) -> None:
        """Prepare the launch; nothing starts before ``start``.

        Args:
            plans: The node processes, in start order.
            env: Environment of the children (``os.environ`` with the project's ROS
                defaults if None).
            stdout: Where the children's prefixed stdout goes (``sys.stdout`` if None).
            stderr: Where the children's prefixed stderr (their logs) and the launcher's
                reports go (``sys.stderr`` if None).
            capture: Prefix the children's output; False lets it through unchanged.
            sigterm_timeout_s: Wait after SIGINT before SIGTERM (s).
            sigkill_timeout_s: Wait after SIGTERM before SIGKILL (s).
        """
        self.plans = list(plans)
        self.processes: list[NodeProcess] = []
        self._stdout = stdout if stdout is not None else sys.stdout
        self._stderr = stderr if stderr is not None else sys.stderr
        self._capture = capture
        self._sigterm_timeout_s = sigterm_timeout_s
        self._sigkill_timeout_s = sigkill_timeout_s
        self._lock = threading.Lock()
        self._threads: list[threading.Thread] = []
        if env is None:
            ros_environment_defaults()
            env = os.environ
        self._env = dict(env)
        self._env.setdefault('PYTHONUNBUFFERED', '1')
        if capture and self._stderr.isatty():
            self._env.setdefault('RCUTILS_COLORIZED_OUTPUT', '1')

    def report(self, line: str) -> None:
        """One line of the launcher's own on its stderr, between the children's lines."""
        with self._lock:
            self._stderr.write(line + '\n')
            self._stderr.flush()

    def start(self) -> None:
        """Start every node process; the output copiers start after the last one.

        The copier threads start only once every child is forked: the child runs
        ``_die_with_parent`` between fork and exec, which must not meet other threads.

        Raises:
            LaunchError: An executable cannot be started; the ones started are stopped.
        """
        pipe = subprocess.PIPE if self._capture else None
        for plan in self.plans:
            try:
                popen = subprocess.Popen(
                    plan.command, env=self._env, stdin=subprocess.DEVNULL, stdout=pipe,
                    stderr=pipe, process_group=0,
                    preexec_fn=_child_setup(plan.rt_priority, plan.nice),
                )
            except OSError as exc:
                self.stop()
                msg = f'node {plan.spec.name!r}: cannot start {plan.command[0]}: {exc}'
                raise LaunchError(msg) from exc
            self.processes.append(NodeProcess(plan, popen))
        if self._capture:
            for process in self.processes:
                popen = process.popen
                assert popen.stdout is not None and popen.stderr is not None
                self._threads += [
                    _Prefixer(popen.stdout, self._stdout, process.plan.label, self._lock),
                    _Prefixer(popen.stderr, self._stderr, process.plan.label, self._lock),
                ]
            for thread in self._threads:
                thread.start()

    def running(self) -> list[NodeProcess]:
        """The processes that have not ended."""
        return [process for process in self.processes if process.poll() is None]

    def wait_for_exit(
        self, stop: StopRequest, end_node: str | None = SIMULATOR.name,
        on_finished: Callable[[NodeProcess], None] | None = None,
        on_poll: Callable[[], None] | None = None,
        end_reached: Callable[[], bool] | None = None,
    ) -> tuple[str, NodeProcess | None]:
        """Watch the children until a stop request or the first one that ends.

        A node that finishes by itself (``NodeSpec.finishes``: the mission) ends the watch
        only when it crashed: its job done (0) or failed (``EXIT_MISSION_FAILED``), the run
        goes on and ``on_finished`` is called once with it.

        Args:
            stop: Polled every ``POLL_PERIOD_S``.
            end_node: The node whose exit with status 0 is the run's normal end.
            on_finished: Called once per finishing node that ended with 0 or
                ``EXIT_MISSION_FAILED``.
            on_poll: Called every ``POLL_PERIOD_S`` while the children run.
            end_reached: True once ``end_node`` reached the run's end while it keeps
                running (the simulator serving the twins in its process: the bridges put
                their devices back through them before it is stopped).

        Returns:
            ``('stopped', None)`` after a stop request, ``('finished', node)`` when
            ``end_node`` exited 0 or reached its end, ``('failed', node)`` when another one
            ended.
        """
        seen: set[int] = set()
        while True:
            if stop.is_set():
                return 'stopped', None
            for process in self.processes:
                status = process.poll()
                if status is None:
                    continue
                if self.finished_its_job(process):
                    if id(process) not in seen and on_finished is not None:
                        on_finished(process)
                    seen.add(id(process))
                    continue
                if process.name == end_node and status == 0:
                    return 'finished', process
                return 'failed', process
            if end_reached is not None and end_reached():
                ends = [p for p in self.processes if p.name == end_node]
                if ends:
                    return 'finished', ends[0]
            if on_poll is not None:
                on_poll()
            time.sleep(POLL_PERIOD_S)

    @staticmethod
    def finished_its_job(process: NodeProcess) -> bool:
        """A finishing node (the mission) that ended by itself, its job done or failed."""
        return process.plan.spec.finishes and process.status in _FINISHED_STATUSES

    def failed_jobs(self) -> list[NodeProcess]:
        """Finishing nodes whose job failed (exit ``EXIT_MISSION_FAILED``: the mission)."""
        return [p for p in self.processes
                if p.plan.spec.finishes and p.status == EXIT_MISSION_FAILED]

    def stop(self) -> None:
        """Stop every running node; escalate SIGINT, SIGTERM, SIGKILL.

        The processes holding a hardware bridge first (a bridge alone, or the robot process
        that composes them), while their devices (or twins) still answer as they put back
        what they changed; the recorder last, so that it records the others' last messages
        and then closes its file.
        """
        from uvms_bringup.launch_layout import holds_bridge  # launch_layout imports this

        bridges = [p for p in self.processes if holds_bridge(p.plan)]
        recorders = [p for p in self.processes if p.plan.spec is RECORDER]
        others = [p for p in self.processes if p not in bridges and p not in recorders]
        for group in (bridges, others, recorders):
            self._stop_group(group)
        for thread in self._threads:
            thread.join(timeout=1.0)

    def _stop_group(self, group: Sequence[NodeProcess]) -> None:
        """SIGINT to the group, then SIGTERM and SIGKILL to those still running."""
        steps = ((signal.SIGINT, self._sigterm_timeout_s),
                 (signal.SIGTERM, self._sigkill_timeout_s),
                 (signal.SIGKILL, 5.0))
        for sig, timeout_s in steps:
            alive = [p for p in group if p.poll() is None]
            if not alive:
                return
            if sig is not signal.SIGINT:
                names = ', '.join(p.name for p in alive)
                self.report(f'uvms launch: {names} still running after '
                            f'{alive[0].signals_sent[-1].name}: sending {sig.name}')
            for process in alive:
                try:
                    process.popen.send_signal(sig)
                except ProcessLookupError:
                    pass
                process.signals_sent.append(sig)
            deadline = time.monotonic() + timeout_s
            for process in alive:
                try:
                    process.popen.wait(timeout=max(deadline - time.monotonic(), 0.0))
                except subprocess.TimeoutExpired:
                    continue
                process.poll()

    def unclean_stops(self) -> list[NodeProcess]:
        """Processes that ended with an error (not 0/130/by signal, nor a failed mission)."""
        return [p for p in self.processes
                if p.status is not None and p.status not in _STOPPED_STATUSES
                and not self.finished_its_job(p)]
