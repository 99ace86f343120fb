"""Starts and stops under load: N ``uvms launch`` cycles, each stopped at a random moment.

Issue 48's soak. Beside ``--loads`` busy loops (``while True: pass`` at normal priority), it
runs ``--cycles`` launches in turn over the scenarios (both shipped robots by default; with
``--twin`` also through ``--hardware twin``), each recording to an MCAP file, and stops each
at a moment drawn from four, as a user's Ctrl-C would (SIGINT to the launch's process group):

- ``startup``: 0.2-2 s after the launcher started its node processes (its first line),
  while they import and build;
- ``before_step``: once every node is up but before the first simulated step;
- ``mid_task``: 0.5-5 s after the mission sent its goal;
- ``end``: not at all: the launch runs to the scenario's duration.

Each cycle is judged as issue 48 asks: the documented exit status (130 after a signal; 0, or
3 with ``mission failed:`` said, at the end), no core dump and no node ended by a signal, no
error line after the stop (``[ERROR]``, ``Fatal Python error``, ``Traceback``, ``uvms launch:
error``), the recording readable by rosbags (its summary and every message), the stop within
``--stop-limit`` seconds (2 s) of the signal, and, where the mission ran, its goal sent within
``--discovery-limit`` seconds (3 s) of the mission's first line (the action server found and
settled: the discovery time). One row per cycle, then the counts; exit status 1 when a cycle
failed, so the bench can stand in a loop.

``--test NODEID --runs N`` instead runs one test N times under the same load, each in its own
``tools/run_suite.py`` process (the suite's own limits), and counts the passes (``--logs DIR``
keeps each failed run's output).

Usage::

    .venv/bin/python bench/bench_soak.py --cycles 100 [--twin] [--loads 2] [--seed 1]
    .venv/bin/python bench/bench_soak.py --test test/integration/test_mission.py --runs 30
"""

from __future__ import annotations

import argparse
import os
import random
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DEFAULT_SCENARIOS = ('case1_ke1e4', 'bluerov2_alpha5_contact')
#: Robots whose scenarios can also run through the protocol twins.
TWIN_SCENARIOS = ('bluerov2_alpha5_contact',)
MOMENTS = ('startup', 'before_step', 'mid_task', 'end')
#: The launcher's first line, once its node processes are started.
LAUNCHER_UP = 'uvms launch: '
BUSY_LOOP = 'while True:\n    pass\n'
#: Lines that a clean stop never prints.
ERROR_LINE = re.compile(r'\[ERROR\]|Fatal Python error|Traceback|uvms launch: error|'
                        r'core dumped|Segmentation fault')
#: What only a stop that went wrong prints (a run's own [ERROR] lines are its outcome).
TEARDOWN_ERROR = re.compile(r'Fatal Python error|Traceback|uvms launch: error|core dumped|'
                            r'Segmentation fault')
#: A ROS log line's stamp: ``[INFO] [1796539428.692050634] [uvms.mission]: ...``.
STAMPED = re.compile(r'\[(?:INFO|WARN|ERROR|DEBUG|FATAL)\] \[(\d+\.\d+)\] \[([\w.]+)\]: (.*)')
SIGNAL_DEATH = re.compile(r'signal (\d+)|killed by|SIGSEGV|SIGABRT|SIGKILL')


@dataclass
class Cycle:
    """One launch: how it was stopped and what it showed."""

    scenario: str
    twin: bool
    moment: str
    status: int | None = None
    stop_s: float | None = None
    discovery_s: float | None = None
    problems: list[str] = field(default_factory=list)
    #: The launch's console lines with their arrival (monotonic s).
    lines: list[tuple[float, str]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """Whether the cycle met every criterion."""
        return not self.problems


def source_path() -> str:
    """PYTHONPATH of this tree's packages (uvms_msgs is the venv's built one)."""
    return os.pathsep.join(str(p) for p in sorted((REPO / 'src').glob('uvms_*'))
                           if p.name != 'uvms_msgs')


def busy_loops(count: int) -> list[subprocess.Popen[bytes]]:
    """``count`` processes spinning at normal priority (other work on the machine)."""
    return [subprocess.Popen([sys.executable, '-c', BUSY_LOOP]) for _ in range(count)]


class Launch:
    """``uvms launch`` in a process group of its own, its output read line by line."""

    def __init__(self, scenario: str, twin: bool, output: Path) -> None:
        env = dict(os.environ, PYTHONPATH=source_path(),
                   ROS_DOMAIN_ID=str(random.randint(1, 100)))
        command = [str(Path(sys.executable).parent / 'uvms'), 'launch', scenario, '--output',
                   str(output), *(['--hardware', 'twin'] if twin else [])]
        self.started = time.monotonic()
        self.process = subprocess.Popen(command, env=env, stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, text=True,
                                        start_new_session=True)
        self.lines: list[tuple[float, str]] = []
        self.ended = float('nan')
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append((time.monotonic(), line.rstrip('\n')))

    def seen(self, text: str) -> float | None:
        """When a line containing ``text`` was read (monotonic s), or None."""
        return next((t for t, line in self.lines if text in line), None)

    def wait_for(self, text: str, timeout_s: float) -> float | None:
        """Wait until a line containing ``text`` or the process ends; when it came."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end and self.process.poll() is None:
            if (t := self.seen(text)) is not None:
                return t
            time.sleep(0.02)
        return self.seen(text)

    def interrupt(self) -> float:
        """SIGINT to the whole group, as a terminal's Ctrl-C; the moment it was sent."""
        sent = time.monotonic()
        try:
            os.killpg(self.process.pid, signal.SIGINT)
        except ProcessLookupError:
            pass
        return sent

    def finish(self, timeout_s: float) -> int | None:
        """The exit status, or None after SIGKILL of the group at the timeout."""
        try:
            status: int | None = self.process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()
            status = None
        self.ended = time.monotonic()
        self._reader.join(timeout=5.0)
        return status


#: The mission's line when it found the controller's action server (mission_node).
FOUND = re.compile(r'found the action server (\S+) (\d+\.\d+) s after the node started')


def discovery_s(lines: list[tuple[float, str]]) -> float | None:
    """The mission's time to find the action server, as its own line says it (s).

    Missions older than that line: from the mission's first line to its goal sent, on the
    log's own stamps (which also counts the wait for the first controller state).
    """
    first = sent = None
    for _, line in lines:
        match = STAMPED.search(line)
        if not match or match.group(2) != 'uvms.mission':
            continue
        stamp, text = float(match.group(1)), match.group(3)
        found = FOUND.search(text)
        if found is not None:
            return float(found.group(2))
        if first is None:
            first = stamp
        if text.startswith('sending') and sent is None:
            sent = stamp
    return None if first is None or sent is None else sent - first


def recording_problems(path: Path) -> list[str]:
    """What keeps rosbags from reading the recording whole (empty: it reads)."""
    if not path.is_file():
        return [f'no recording {path.name}']
    try:
        from mcap.reader import make_reader
        from rosbags.highlevel import AnyReader

        with path.open('rb') as stream:
            if make_reader(stream).get_summary() is None:
                return ['recording without a summary']
        with AnyReader([path]) as reader:
            for connection, _, raw in reader.messages():
                reader.deserialize(raw, connection.msgtype)
    except Exception as exc:  # any failure to read is the finding
        return [f'recording unreadable: {type(exc).__name__}: {exc}']
    return []


def run_cycle(cycle: Cycle, directory: Path, stop_limit_s: float,
              discovery_limit_s: float) -> Cycle:
    """Launch, stop at the cycle's moment, judge."""
    output = directory / f'{cycle.scenario}-{random.randrange(1 << 30)}.mcap'
    launch = Launch(cycle.scenario, cycle.twin, output)
    try:
        sent: float | None = None
        if cycle.moment == 'startup':
            # Counted from the launcher's first line (its node processes started): before it,
            # the stop would land in the launcher's own interpreter start-up (the ROS wheels'
            # .pth re-executes it), where no code of ours runs yet and Python itself prints
            # `Fatal Python error: init_import_site` for any console script.
            if launch.wait_for(LAUNCHER_UP, 60.0) is not None:
                time.sleep(random.uniform(0.2, 2.0))
                sent = launch.interrupt()
        elif cycle.moment == 'before_step':
            if launch.wait_for('holding the initial state', 60.0) is not None:
                sent = launch.interrupt()
        elif cycle.moment == 'mid_task':
            if launch.wait_for('sending mission', 90.0) is not None:
                time.sleep(random.uniform(0.5, 5.0))
                sent = launch.interrupt()
        cycle.status = launch.finish(600.0 if sent is None else 30.0)
    except BaseException:  # the soak itself stopped (Ctrl-C, SIGTERM): so is the launch
        launch.interrupt()
        launch.finish(10.0)
        raise
    lines = launch.lines
    cycle.lines = lines
    if sent is not None and cycle.status is not None:
        cycle.stop_s = launch.ended - sent
    judge(cycle, lines, sent, output, stop_limit_s, discovery_limit_s)
    return cycle


def judge(cycle: Cycle, lines: list[tuple[float, str]], sent: float | None, output: Path,
          stop_limit_s: float, discovery_limit_s: float) -> None:
    """Fill ``cycle.problems`` from the status, the lines, the timing and the recording."""
    text = [line for _, line in lines]
    mission_failed = any(line.startswith('mission failed:') for line in text)
    if cycle.status is None:
        cycle.problems.append('did not end: group SIGKILLed')
    elif sent is not None and cycle.status != 130:
        cycle.problems.append(f'status {cycle.status} after a stop (documented: 130)')
    elif sent is None and cycle.status not in (0, 3):
        cycle.problems.append(f'status {cycle.status} at the end (documented: 0, or 3)')
    elif sent is None and (cycle.status == 3) != mission_failed:
        cycle.problems.append('status 3 without "mission failed:" (or the reverse)')
    after = [line for t, line in lines if sent is None or t >= sent]
    errors = [line for line in after if ERROR_LINE.search(line)]
    if sent is None:  # a run to its end: a node's [ERROR] is the run's, not the stop's
        errors = [line for line in errors if TEARDOWN_ERROR.search(line)]
    if errors:
        cycle.problems.append(f'{len(errors)} error line(s) at stop: {errors[0][:160]}')
    deaths = [line for line in text if 'exited' in line and SIGNAL_DEATH.search(line)]
    if deaths:
        cycle.problems.append(f'a node ended by a signal: {deaths[0][:160]}')
    if cycle.stop_s is not None and cycle.stop_s > stop_limit_s:
        cycle.problems.append(f'stop took {cycle.stop_s:.2f} s (limit {stop_limit_s:g} s)')
    cycle.discovery_s = discovery_s(lines)
    if cycle.discovery_s is not None and cycle.discovery_s > discovery_limit_s:
        cycle.problems.append(f'action server found {cycle.discovery_s:.2f} s after the '
                              f'mission started (limit {discovery_limit_s:g} s)')
    if cycle.moment != 'startup' or output.is_file():
        cycle.problems += recording_problems(output)


def soak(args: argparse.Namespace) -> int:
    """The launch cycles; 0 when every one met every criterion."""
    variants = [(s, False) for s in args.scenarios]
    if args.twin:
        variants += [(s, True) for s in args.scenarios if s in TWIN_SCENARIOS]
    cycles: list[Cycle] = []
    with tempfile.TemporaryDirectory(prefix='uvms-soak-') as tmp:
        for index in range(args.cycles):
            scenario, twin = variants[index % len(variants)]
            cycle = run_cycle(Cycle(scenario, twin, random.choice(args.moments)), Path(tmp),
                              args.stop_limit, args.discovery_limit)
            cycles.append(cycle)
            stop = '-' if cycle.stop_s is None else f'{cycle.stop_s:.2f} s'
            found = '-' if cycle.discovery_s is None else f'{cycle.discovery_s:.2f} s'
            name = f'{scenario}{" (twin)" if twin else ""}'
            print(f'{index + 1:4d} {name:34s} {cycle.moment:11s} status {cycle.status!s:>4} '
                  f'stop {stop:>7} goal {found:>7}  '
                  f'{"ok" if cycle.ok else "; ".join(cycle.problems)}', flush=True)
            if args.logs is not None and not cycle.ok:
                args.logs.mkdir(parents=True, exist_ok=True)
                (args.logs / f'cycle{index + 1}.log').write_text(
                    ''.join(f'{t:.3f} {line}\n' for t, line in cycle.lines), encoding='utf-8')
            for stale in Path(tmp).glob('*.mcap'):
                stale.unlink()
    failed = [c for c in cycles if not c.ok]
    stops = sorted(c.stop_s for c in cycles if c.stop_s is not None)
    found = sorted(c.discovery_s for c in cycles if c.discovery_s is not None)
    print(f'{len(cycles) - len(failed)} of {len(cycles)} cycles clean; longest stop '
          f'{stops[-1] if stops else float("nan"):.2f} s; longest time to the goal '
          f'{found[-1] if found else float("nan"):.2f} s')
    return 1 if failed else 0


def suite_selection(test: str) -> list[str]:
    """run_suite's arguments for a module or a node id (``path::name``).

    run_suite selects groups by existing paths and hands every other argument to each
    group's pytest: a node id alone would run the whole suite with it appended. The module's
    path selects its group, ``-k`` the test.
    """
    path, _, name = test.partition('::')
    return [path, '-k', name.split('[')[0]] if name else [path]


def repeat_test(args: argparse.Namespace) -> int:
    """One test module or node id ``--runs`` times through the suite runner; 0 if all pass."""
    passes = 0
    netns = [str(REPO / 'tools' / 'loopback-netns')] if args.netns else []
    for run in range(args.runs):
        started = time.monotonic()
        result = subprocess.run([*netns, sys.executable, str(REPO / 'tools' / 'run_suite.py'),
                                 *suite_selection(args.test), '-q'], cwd=REPO,
                                capture_output=True, text=True, check=False)
        passes += result.returncode == 0
        last = (result.stdout.strip().splitlines() or [''])[-1]
        print(f'{run + 1:4d} {"pass" if result.returncode == 0 else "FAIL"} '
              f'{time.monotonic() - started:6.1f} s  {last}', flush=True)
        for line in result.stdout.splitlines():
            if line.startswith(('FAILED ', 'ERROR ')):
                print(f'       {line[:200]}', flush=True)  # which test, and why
        if args.logs is not None and result.returncode != 0:
            args.logs.mkdir(parents=True, exist_ok=True)
            (args.logs / f'run{run + 1}.log').write_text(result.stdout + result.stderr)
    print(f'{passes} of {args.runs} runs passed: {args.test}')
    return 0 if passes == args.runs else 1


def main() -> int:
    """Parse the arguments, start the load, soak or repeat, stop the load."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenarios', nargs='*', default=list(DEFAULT_SCENARIOS))
    parser.add_argument('--cycles', type=int, default=10)
    parser.add_argument('--twin', action='store_true', help='also through --hardware twin')
    parser.add_argument('--loads', type=int, default=2, help='busy loops beside (default 2)')
    parser.add_argument('--seed', type=int, default=None, help='seed of the stop moments')
    parser.add_argument('--stop-limit', type=float, default=2.0, help='s from signal to exit')
    parser.add_argument('--discovery-limit', type=float, default=3.0,
                        help="s from the mission's first line to its goal sent")
    parser.add_argument('--moments', nargs='+', choices=MOMENTS, default=list(MOMENTS),
                        help='the stop moments to draw from (default: all four)')
    parser.add_argument('--logs', type=Path, default=None, metavar='DIR',
                        help="each failed cycle's console lines to DIR/cycleN.log (with --test: "
                             "each failed run's output to DIR/runN.log)")
    parser.add_argument('--test', help='a test (path or node id) to repeat instead')
    parser.add_argument('--runs', type=int, default=30)
    parser.add_argument('--netns', action='store_true',
                        help='run the repeated test inside tools/loopback-netns')
    args = parser.parse_args()
    random.seed(args.seed)
    # A SIGTERM ends the soak through the ``finally`` below, so the busy loops end with it.
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    print(f'load average before: {os.getloadavg()[0]:.2f}; {args.loads} busy loop(s)')
    loads = busy_loops(args.loads)
    try:
        return repeat_test(args) if args.test else soak(args)
    finally:
        for process in loads:
            process.kill()
            process.wait()
        print(f'load average after: {os.getloadavg()[0]:.2f}')


if __name__ == '__main__':
    sys.exit(main())
