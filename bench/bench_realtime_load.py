"""Real time on a busy computer: ``uvms launch`` beside busy loops, with and without priorities.

For each robot (``case1_ke1e4``, ``bluerov2_alpha5_contact``), each load (0, 2 and 4 busy
loops: ``while True: pass`` processes at normal priority, as many cores' worth of other work)
and each scheduling (the launch's default SCHED_FIFO 50, and ``--no-rt``), it runs ``uvms
launch SCENARIO --output F.mcap`` N times (``--runs``, default 3) to the scenario's duration
and prints one row per cell: the outcomes (exit status 0: SUCCEEDED; 3: the mission's code;
1: a node failed), contacts per run (separate contact intervals of the recording; 1: no
bounce), the worst missed share of the loop processes (the launch's closing table), and the
RMS force error of the constrained phase (``uvms_analysis.metrics.force_rms_error``) against
the quiet run's (0 loops, priorities, first run), as a ratio.

Issue 40's acceptance: with priorities every run succeeds with one contact and < 1 % missed
periods, the RMS force error within 10 % of the quiet run's; without, the figures as they
come. Only figures of an otherwise quiet machine mean that: the load average is printed
before and after. It asserts nothing.

Usage::

    .venv/bin/python bench/bench_realtime_load.py [SCENARIO ...] [--runs N] [--loads 0 2 4]
"""

from __future__ import annotations

import argparse
import os
import random
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
#: One scenario per shipped robot.
DEFAULT_SCENARIOS = ('case1_ke1e4', 'bluerov2_alpha5_contact')
BUSY_LOOP = 'while True:\n    pass\n'
#: A loop process's row of the launch's closing table: ``name  CPU  M of N (x %)  late``.
ROW = re.compile(r'^\s+(simulator|controller|thruster_allocator|estimator|control)\s+.*?'
                 r'(\d+) of (\d+) \(')
MISSION_FAILED = re.compile(r'^mission failed: (\w+)')


@dataclass
class Outcome:
    """One launch: its outcome, contacts, worst missed share (%) and RMS force error (N)."""

    outcome: str
    contacts: int | None
    missed_pct: float | None
    rms_n: float | None


def source_path() -> str:
    """PYTHONPATH of this tree's packages (uvms_msgs is the venv's built one)."""
    return os.pathsep.join(str(p) for p in sorted((REPO / 'src').glob('uvms_*'))
                           if p.name != 'uvms_msgs')


def launch(scenario: str, priorities: bool, directory: Path) -> Outcome:
    """One ``uvms launch`` to the scenario's duration, read from its output and recording."""
    output = directory / f'{scenario}-{random.randrange(1 << 30)}.mcap'
    env = dict(os.environ, PYTHONPATH=source_path(), ROS_DOMAIN_ID=str(random.randint(1, 100)))
    command = [str(Path(sys.executable).parent / 'uvms'), 'launch', scenario, '--output',
               str(output), *([] if priorities else ['--no-rt'])]
    result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600,
                            check=False)
    lines = result.stderr.splitlines()
    outcome = {0: 'SUCCEEDED', 1: 'NODE FAILED', 130: 'INTERRUPTED'}.get(result.returncode,
                                                                       str(result.returncode))
    for line in lines:
        match = MISSION_FAILED.match(line)
        if match:
            outcome = match.group(1)
    shares = [100.0 * int(m.group(2)) / int(m.group(3))
              for m in map(ROW.match, lines) if m and int(m.group(3))]
    contacts = rms = None
    if output.is_file():
        from uvms_analysis.metrics import compute_metrics
        from uvms_analysis.series import load_run

        try:
            metrics = compute_metrics(load_run(output))
            contacts, rms = metrics.contact_count, metrics.force_rms_error
        except Exception as exc:  # a recording cut short by a failed node
            print(f'    {output.name}: no metrics ({type(exc).__name__}: {exc})')
        output.unlink()
    return Outcome(outcome, contacts, max(shares) if shares else None, rms)


def busy_loops(n: int) -> list[subprocess.Popen[bytes]]:
    """``n`` processes spinning at normal priority."""
    return [subprocess.Popen([sys.executable, '-I', '-S', '-c', BUSY_LOOP])
            for _ in range(n)]


def row(scenario: str, loads: int, priorities: bool, runs: list[Outcome],
        quiet_rms: float | None) -> str:
    """One table row of a cell."""
    ratios = [f'{r.rms_n / quiet_rms:.2f}' if r.rms_n and quiet_rms else '-' for r in runs]
    missed = [f'{r.missed_pct:.2f}' if r.missed_pct is not None else '-' for r in runs]
    return (f'| {scenario} | {loads} | {"FIFO 50" if priorities else "none"} | '
            f'{", ".join(r.outcome for r in runs)} | '
            f'{", ".join(str(r.contacts) if r.contacts is not None else "-" for r in runs)} | '
            f'{", ".join(missed)} | {", ".join(ratios)} |')


def main() -> None:
    """Every cell N times; the table in Markdown."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenarios', nargs='*', default=list(DEFAULT_SCENARIOS))
    parser.add_argument('--runs', type=int, default=3, help='runs per cell')
    parser.add_argument('--loads', type=int, nargs='+', default=[0, 2, 4],
                        help='busy loops beside the launch')
    args = parser.parse_args()
    sys.path[:0] = source_path().split(os.pathsep)
    print(f'load before: {" ".join(f"{v:.2f}" for v in os.getloadavg())} '
          f'({os.cpu_count()} CPUs)')
    print('| robot | busy loops | priority | outcomes | contacts | missed % (worst loop '
          'process) | RMS force error / quiet |')
    print('| --- | --- | --- | --- | --- | --- | --- |')
    with tempfile.TemporaryDirectory(prefix='uvms_load_') as directory:
        for scenario in args.scenarios:
            quiet_rms: float | None = None
            for loads in args.loads:
                for priorities in (True, False):
                    loops = busy_loops(loads)
                    try:
                        runs = [launch(scenario, priorities, Path(directory))
                                for _ in range(args.runs)]
                    finally:
                        for loop in loops:
                            loop.kill()
                            loop.wait()
                    if quiet_rms is None and loads == 0 and priorities:
                        quiet_rms = runs[0].rms_n
                    print(row(scenario, loads, priorities, runs, quiet_rms), flush=True)
    print(f'load after: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')


if __name__ == '__main__':
    main()
