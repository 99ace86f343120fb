#!/usr/bin/env python3
"""Run the test suite as one pytest process per group, so that no module can hang the job.

A Fast DDS livelock in a participant's teardown spins inside C, where neither pytest-timeout's
signal nor SIGINT reaches it (CI of 2026-12-03 and 12-04). So every integration module (the
modules that start DDS participants and node processes) runs in a pytest process of its own;
the unit tests run one process per sub-folder, two at a time (pure CPU work: on two cores
they take half the time), the scenario tests in one (their runs are shared across modules
and happen in child processes, two at a time, with their own time limit).

The unit tests keep no periods and wait on no clock: what they compute does not depend on
when they get the CPU. They run in a lane of their own beside the rest, at
SCHED_IDLE (``chrt --idle``), so they take only the CPU time the integration tests leave
(those wait on their nodes' real-time periods much of the time) and never delay one of them:
a runnable SCHED_IDLE task yields to every other task at once. ``--one-lane`` runs the
groups one after the other, as before. Each process gets
a time limit (``--group-limit``, the scenario group ``--scenario-limit``); past it the process
gets SIGABRT, on which Python's faulthandler (enabled by pytest) prints every thread's stack,
then its whole process group is killed. The rest of the suite runs on, and the
summary names the group, the test it was in (the progress file written by test/conftest.py)
and its stacks above.

    tools/run_suite.py [--group-limit S] [--scenario-limit S] [--one-lane] [--list]
                       [PYTEST_ARG ...] [PATH ...]

Arguments that are existing paths under test/ select groups; every other argument goes to
each pytest. The last line is pytest's: ``N passed, N failed, N skipped`` (or ``N errors``)
for the whole suite. Exit status 0 when every group passed, 1 otherwise, 5 when no test ran.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / 'test'
#: Top-level test folders whose every module runs in a process of its own.
ISOLATED = ('integration',)
#: Top-level test folders that run whole, in one process each (the scenario runs are shared
#: across modules).
WHOLE = ('scenarios', 'ros2_way')
#: Folders whose sub-folders run as groups of their own, this many at a time, each one's
#: output shown as it ends: the unit tests start no node processes and keep no periods, so
#: two of them share the two cores of CI without changing what they test.
CONCURRENT = {'unit': 2}
#: Top-level test folders whose groups run in the idle lane (SCHED_IDLE, beside the others):
#: they keep no periods, so when they get the CPU changes nothing they check. Not the scenario
#: tests: beside their runs (two lockstep graphs at a time, each writing its recording) the
#: UDP device tests of the main lane failed in 3 runs of 4 (the ArduSub twin silent for
#: 1.7-2.7 s at their first test, in both interpreters), never otherwise; cause not found.
#: Ruled out since (issue 48, tools/stall_probe.py): the scenario runs' processes stay
#: SCHED_IDLE (none asks for SCHED_FIFO); no port of the twin held by another socket; no
#: import or cache load on the test's main thread during its commands (the dialect import is
#: in the fixture, before them). Where it failed the same way on a machine under other load,
#: the whole test process (main, twin and DDS threads) waited 0.5-0.9 s on the run queue.
IDLE_LANE = ('unit',)
#: Unit sub-folders that stay in the main lane: test/unit/hardware serves device twins on
#: wall time (a 50 Hz RC loop, a 100 ms watchdog, 200 Hz streams) to the components and
#: links it tests, which a starved SCHED_IDLE process misses.
TIMED_UNIT_FOLDERS = ('hardware',)
#: How much longer than its limit an idle-lane group, and each of its tests (pyproject's
#: pytest-timeout and faulthandler_timeout), may take: it gets the CPU only when the other
#: lane leaves it (the integration tests want most of 2 cores at moments). These limits catch
#: hangs; a test waiting for the CPU is not one.
IDLE_LIMIT_FACTOR = 2.0
#: ROS domains of each lane's test modules (test/conftest.py hands them out in turn): the two
#: lanes' tests run at once and must not hear each other. The scenario runs take their
#: group's lane's (test/scenarios/scenario_runs.py; a lane runs one group at a time). All
#: under 101: higher domains' ports are in Linux's ephemeral range.
MAIN_DOMAINS = (1, 70)
IDLE_DOMAINS = (71, 100)
#: pyproject.toml's per-test limits (s), scaled for the idle lane.
TEST_TIMEOUT_S = 300.0
FAULTHANDLER_TIMEOUT_S = 240.0
#: Hypothesis's pytest plugin, loaded by every pytest process where hypothesis is installed
#: (0.6 s of imports each, about 25 s a suite); left out of groups whose modules do not use
#: hypothesis (the library works without it; the plugin adds its options and statistics).
HYPOTHESIS_PLUGIN = 'hypothesispytest'
#: Seconds between SIGABRT (stacks printed) and SIGKILL of the group's process group.
ABORT_GRACE_S = 10.0
#: pytest's own "no tests collected" status (every test deselected): not a failure.
NO_TESTS = 5
#: Set on Ctrl-C (or the suite's own time limit): no group starts after it.
STOPPING = threading.Event()


@dataclass
class Group:
    """One pytest process: the paths it runs and what it reported."""

    name: str
    paths: list[Path]
    limit_s: float
    counts: dict[str, int] = field(default_factory=dict)
    failed: list[str] = field(default_factory=list)
    status: int | None = None
    timed_out: bool = False
    last_test: str = ''
    took_s: float = 0.0
    batch: str = ''
    idle: bool = False
    #: The interpreter whose pytest runs the group.
    python: str = sys.executable
    process: subprocess.Popen[bytes] | None = field(default=None, repr=False)

    @property
    def wall_limit_s(self) -> float:
        """Seconds it may take: longer in the idle lane, which gets the CPU left over."""
        return self.limit_s * (IDLE_LIMIT_FACTOR if self.idle else 1.0)


def groups_for(paths: list[Path], group_limit_s: float, scenario_limit_s: float) -> list[Group]:
    """The groups that run ``paths`` (files or folders under test/), in a stable order."""
    groups: dict[str, Group] = {}

    def add(name: str, path: Path, limit_s: float) -> None:
        groups.setdefault(name, Group(name, [], limit_s)).paths.append(path)

    pooled: dict[str, Group] = {}

    for path in paths:
        files = [path] if path.is_file() else sorted(path.rglob('test_*.py'))
        for module in files:
            parts = module.relative_to(TESTS).parts
            top = parts[0] if len(parts) > 1 else ''
            if top in ISOLATED:
                add(str(module.relative_to(ROOT)), module, group_limit_s)
            elif top in CONCURRENT:
                name = '/'.join(('test', *parts[:2])) if len(parts) > 2 else f'test/{top}'
                pooled.setdefault(name, Group(name, [], group_limit_s, batch=top)).paths.append(
                    module)
            elif top in WHOLE:
                add(f'test/{top}', module,
                    scenario_limit_s if top == 'scenarios' else group_limit_s)
            else:  # a module at the top of test/
                add(str(module.relative_to(ROOT)), module, group_limit_s)
    # Largest first (file size: a proxy for time), so that the pool ends close together.
    for group in sorted(pooled.values(),
                        key=lambda g: (-sum(p.stat().st_size for p in g.paths), g.name)):
        groups[group.name] = group
    for group in groups.values():
        group.paths.sort()
        parts = group.paths[0].relative_to(TESTS).parts
        group.idle = parts[0] in IDLE_LANE and not (
            len(parts) > 2 and parts[1] in TIMED_UNIT_FOLDERS)
        if not group.idle and parts[0] in IDLE_LANE:
            group.batch = ''  # alone in the main lane, not in the idle lane's pool
    return list(groups.values())


#: Top-level test folders the second interpreter does not run again: the colcon workspace is
#: built by the ROS 2 tools of the first (its test builds and runs the installed packages).
FIRST_ONLY = ('ros2_way',)


def python_label(python: str) -> str:
    """``py3.12`` for an interpreter (asked, as it reports itself)."""
    version = subprocess.run([python, '-c', 'import sys; print(*sys.version_info[:2], sep=".")'],
                             capture_output=True, text=True, check=True).stdout.strip()
    return f'py{version}'


def groups_again(groups: list[Group], python: str) -> list[Group]:
    """The groups once more on another interpreter, named after it (the colcon ones not)."""
    label = python_label(python)
    return [Group(f'{label} {g.name}', list(g.paths), g.limit_s, batch=g.batch and
                  f'{label} {g.batch}', idle=g.idle, python=python)
            for g in groups if g.paths[0].relative_to(TESTS).parts[0] not in FIRST_ONLY]


def read_junit(group: Group, path: Path) -> None:
    """Counts and failed test ids of a group from its JUnit XML (absent when it was killed)."""
    if not path.exists():
        return
    root = ET.parse(path).getroot()
    for suite in root.iter('testsuite'):
        for key in ('tests', 'failures', 'errors', 'skipped'):
            group.counts[key] = group.counts.get(key, 0) + int(suite.get(key, 0))
        for case in suite.iter('testcase'):
            if case.find('failure') is not None or case.find('error') is not None:
                group.failed.append(f"{case.get('classname')}::{case.get('name')}")


def uses_hypothesis(group: Group) -> bool:
    """Whether a module of the group names hypothesis (then its plugin is loaded)."""
    return any('hypothesis' in path.read_text(encoding='utf-8') for path in group.paths)


def run_group(group: Group, index: int, pytest_args: list[str], work: Path,
              output: Path | None = None) -> None:
    """Run one group's pytest to its end or its time limit, its output streamed or to a file.

    Nothing starts once the suite is stopping (the group keeps no status: not run).
    """
    if STOPPING.is_set():
        return
    junit = work / f'{index}.xml'
    progress = work / f'{index}.progress'
    low, high = IDLE_DOMAINS if group.idle else MAIN_DOMAINS
    env = dict(os.environ, UVMS_TEST_PROGRESS=str(progress),
               UVMS_TEST_DOMAINS=f'{low}-{high}',
               UVMS_TEST_DOMAIN_START=str(low + (index * 7) % (high - low + 1)))
    plugins = [] if uses_hypothesis(group) else ['-p', f'no:{HYPOTHESIS_PLUGIN}']
    command = [group.python, '-m', 'pytest', '-p', 'no:cacheprovider', *plugins,
               '-o', 'addopts=-ra --strict-markers', f'--junitxml={junit}',
               *pytest_args,
               *(str(p.relative_to(ROOT) if p.is_relative_to(ROOT) else p) for p in group.paths)]
    if group.idle:
        command = ['chrt', '--idle', '0', *command[:3],
                   f'--timeout={TEST_TIMEOUT_S * IDLE_LIMIT_FACTOR:g}',
                   '-o', f'faulthandler_timeout={FAULTHANDLER_TIMEOUT_S * IDLE_LIMIT_FACTOR:g}',
                   *command[3:]]
    start = time.monotonic()
    sink = None if output is None else output.open('wb')
    process = subprocess.Popen(command, cwd=ROOT, env=env, start_new_session=True,
                               stdout=sink, stderr=subprocess.STDOUT if sink else None)
    group.process = process
    try:
        group.status = process.wait(timeout=group.wall_limit_s)
    except subprocess.TimeoutExpired:
        group.timed_out = True
        print(f'\nrun_suite: {group.name} still running after {group.wall_limit_s:.0f} s: '
              "SIGABRT (its threads' stacks follow), then SIGKILL", flush=True)
        process.send_signal(signal.SIGABRT)
        try:
            process.wait(timeout=ABORT_GRACE_S)
        except subprocess.TimeoutExpired:
            pass
        group.status = -1
    except KeyboardInterrupt:
        process.send_signal(signal.SIGINT)
        process.wait(timeout=60)
        raise
    finally:
        _kill_group(process.pid)
        if sink is not None:
            sink.close()
    group.took_s = time.monotonic() - start
    if progress.exists():
        group.last_test = progress.read_text().strip()
    read_junit(group, junit)


def run_batch(batch: list[Group], first: int, total: int, pytest_args: list[str],
              work: Path, stream: bool = True) -> None:
    """Run one group, streamed (or its output printed at its end), or a batch in a pool."""
    if len(batch) == 1 and stream:
        print(f'\n== run_suite [{first + 1}/{total}] {batch[0].name}', flush=True)
        run_group(batch[0], first, pytest_args, work)
        return
    label, _, folder = batch[0].batch.rpartition(' ')  # 'py3.12 unit': another interpreter's
    workers = CONCURRENT.get(folder, 1)
    lane = ' (idle lane)' if batch[0].idle else ''
    if len(batch) > 1:
        print(f'\n== run_suite [{first + 1}-{first + len(batch)}/{total}] {len(batch)} groups '
              f'of {label + " " if label else ""}test/{folder}, {workers} at a time{lane}',
              flush=True)
    logs = {id(group): work / f'{first + k}.log' for k, group in enumerate(batch)}
    pool = ThreadPoolExecutor(max_workers=workers)
    futures = {pool.submit(run_group, group, first + k, pytest_args, work, logs[id(group)]):
               group for k, group in enumerate(batch)}
    try:
        for future in as_completed(futures):
            group = futures[future]
            future.result()
            log = logs[id(group)]
            print(f'\n== run_suite: {group.name} ({group.took_s:.0f} s){lane}', flush=True)
            sys.stdout.buffer.write(log.read_bytes() if log.exists() else b'')
            sys.stdout.flush()
    except KeyboardInterrupt:
        STOPPING.set()
        pool.shutdown(wait=False, cancel_futures=True)
        for group in batch:
            if group.process is not None and group.process.poll() is None:
                group.process.send_signal(signal.SIGINT)
        raise
    pool.shutdown()


def batches(groups: list[Group]) -> list[tuple[int, list[Group]]]:
    """(index of the first group, groups run together): a pooled folder's groups together."""
    out: list[tuple[int, list[Group]]] = []
    index = 0
    while index < len(groups):
        batch = [groups[index]]
        while (batch[0].batch and index + len(batch) < len(groups)
               and groups[index + len(batch)].batch == batch[0].batch):
            batch.append(groups[index + len(batch)])
        out.append((index, batch))
        index += len(batch)
    return out


def run_lanes(groups: list[Group], pytest_args: list[str], work: Path, one_lane: bool) -> None:
    """The idle lane's batches in a thread of their own, the others here, one after the other."""
    if one_lane or shutil.which('chrt') is None:
        for group in groups:
            group.idle = False
    lanes: dict[bool, list[tuple[int, list[Group]]]] = {False: [], True: []}
    for first, batch in batches(groups):
        lanes[batch[0].idle].append((first, batch))
    if lanes[True]:
        count = sum(len(batch) for _, batch in lanes[True])
        print(f'run_suite: {count} groups in the idle lane (SCHED_IDLE), beside the other '
              f'{len(groups) - count}', flush=True)

    def idle_lane() -> None:
        for first, batch in lanes[True]:
            run_batch(batch, first, len(groups), pytest_args, work, stream=False)

    beside = threading.Thread(target=idle_lane, name='idle-lane', daemon=True)
    beside.start()
    try:
        for first, batch in lanes[False]:
            run_batch(batch, first, len(groups), pytest_args, work)
        beside.join()
    except KeyboardInterrupt:
        STOPPING.set()
        for group in groups:
            if group.process is not None and group.process.poll() is None:
                group.process.send_signal(signal.SIGINT)
        beside.join(timeout=60.0)
        raise


def _kill_group(pgid: int) -> None:
    """SIGKILL whatever the group's processes left behind (node processes, a hung pytest)."""
    try:
        os.killpg(pgid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def closing_line(groups: list[Group]) -> str:
    """The closing line for the whole suite, as pytest words it."""
    total = sum(g.counts.get('tests', 0) for g in groups)
    failed = sum(g.counts.get('failures', 0) for g in groups)
    errors = sum(g.counts.get('errors', 0) for g in groups)
    skipped = sum(g.counts.get('skipped', 0) for g in groups)
    passed = total - failed - errors - skipped
    broken = sum(1 for g in groups if g.timed_out or _crashed(g))
    parts = [f'{passed} passed', f'{failed + broken} failed']
    if skipped:
        parts.append(f'{skipped} skipped')
    if errors:
        parts.append(f'{errors} errors')
    return ', '.join(parts)


def _crashed(group: Group) -> bool:
    """A group that ended badly without a failure of its own on record (killed, no XML)."""
    bad = group.status not in (0, 1, NO_TESTS)
    return not group.timed_out and bad and not group.failed


def summary(groups: list[Group], took_s: float) -> list[str]:
    """What went wrong, the slowest groups, and the closing line."""
    lines = ['', f'run_suite: {len(groups)} pytest processes in {took_s:.0f} s']
    for group in sorted(groups, key=lambda g: -g.took_s)[:8]:
        lines.append(f'  {group.took_s:7.1f} s  {group.name}')
    for group in groups:
        if group.timed_out:
            lines.append(f'TIMED OUT {group.name} after {group.wall_limit_s:.0f} s, in test '
                         f'{group.last_test or "(before its first test)"}')
        elif _crashed(group):
            lines.append(f'CRASHED {group.name} (exit status {group.status}), in test '
                         f'{group.last_test or "(before its first test)"}')
        lines.extend(f'FAILED {test_id}' for test_id in group.failed)
    pythons = list(dict.fromkeys(g.python for g in groups))
    if len(pythons) > 1:
        for python in pythons:
            lines.append(f'{python_label(python)}: '
                         f'{closing_line([g for g in groups if g.python == python])}')
    lines.append(closing_line(groups))
    return lines


def split_arguments(arguments: list[str]) -> tuple[list[Path], list[str]]:
    """(paths under test/, the other arguments for pytest)."""
    paths, rest = [], []
    for argument in arguments:
        candidate = (ROOT / argument).resolve()
        if not argument.startswith('-') and candidate.exists() and TESTS in (
                candidate, *candidate.parents):
            paths.append(candidate)
        else:
            rest.append(argument)
    return paths or [TESTS], rest


def main(argv: list[str] | None = None) -> int:
    """Run the groups in their lanes; print the summary; 0 when all passed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--group-limit', type=float, default=900.0, metavar='S',
                        help='seconds one group may take (default 900)')
    parser.add_argument('--scenario-limit', type=float, default=1500.0, metavar='S',
                        help='seconds the scenario group may take (default 1500)')
    parser.add_argument('--also-python', metavar='PYTHON',
                        help='run every group again on this interpreter (its own venv), '
                             'the colcon workspace tests excepted, in the same two lanes')
    parser.add_argument('--one-lane', action='store_true',
                        help='run every group one after the other (no idle lane)')
    parser.add_argument('--list', action='store_true', help='print the groups and stop')
    options, arguments = parser.parse_known_args(argv)
    paths, pytest_args = split_arguments(arguments)
    groups = groups_for(paths, options.group_limit, options.scenario_limit)
    if options.also_python:
        groups += groups_again(groups, os.path.abspath(options.also_python))
    if options.list:
        for group in groups:
            lane = ', idle lane' if group.idle and not options.one_lane else ''
            print(f'{group.name} ({len(group.paths)} modules, limit {group.limit_s:.0f} s{lane})')
        return 0
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix='uvms-suite-') as work:
        run_lanes(groups, pytest_args, Path(work), options.one_lane)
    for line in summary(groups, time.monotonic() - start):
        print(line)
    if all(g.status == NO_TESTS for g in groups):
        return NO_TESTS
    ok = all(g.status in (0, NO_TESTS) and not g.timed_out for g in groups)
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
