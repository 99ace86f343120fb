"""The robot-side footprint of the twin stand, per process layout, side by side in one run.

Issue 47 asks what the processes that would run on the robot's own computer cost (the four
hardware bridges, the control nodes, the estimator and the recorder: not the simulator, the
twins, the visualizer or the mission), and what the twin stand costs per process, for
``uvms launch bluerov2_alpha5_contact --hardware twin`` in three layouts:

- ``separate``: one process per node (``--compose none``; without ``--compose`` a launch with
  ``--hardware`` runs the robot process);
- ``control``: ``--compose control`` (controller, allocator and estimator in one process);
- ``robot``: ``--compose robot``, the robot loop (those and the four bridges in one process
  on one timer: read, estimate, control, allocate, write in one period, no DDS between a
  device and the controller; ``uvms_hardware.robot_loop``).

``--layouts`` picks some of them (the first named is the baseline of the ratios).
``--revision REV`` runs the robot loop of git revision REV (extracted beside the tree) and of
this tree in turn instead: the before/after of a change to the robot process, side by side.

For each real-time factor (``--real-time-factors``, default 1.0 and 0.5) it runs the three
layouts in turn, ``--pairs`` times, to the scenario's end, and reads the launch's own closing
cost table (``uvms_common.process_costs``: CPU in % of one core per process from the first
simulated step, missed periods of the loop processes) instead of measuring anew. It prints
one row per run (outcome, contacts from the recording, robot-side CPU, the twin stand's CPU
per process, the missed share of each loop process) and per factor the robot-side
footprint of each layout against the separate layout's of the same round (measured side by
side), as ratios. The load average is printed before and after; only figures of an
otherwise quiet machine mean something. It asserts nothing.

For the robot loop it also reads the loop's own closing line: the time from the period's
first device read to its last device write (p50 / p99 / max, ms). The latency from a device's
reply to the command it causes is that, plus the wait for the device's read period (its own
rate), plus the device's own reply time; the twins (inside ``hardware_twins``) publish no
times of their own.

Usage::

    .venv/bin/python bench/bench_robot_side.py [--pairs N] [--real-time-factors F ...]
        [--hardware twin|FILE] [--scenario NAME]
"""

from __future__ import annotations

import argparse
import os
import random
import re
import statistics
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from bench_realtime_load import MISSION_FAILED, source_path
from other_revision import extract_revision, python_path

SCENARIO = 'bluerov2_alpha5_contact'
#: Layout name -> the ``uvms launch`` arguments that make it; the first is the baseline.
LAYOUTS: dict[str, tuple[str, ...]] = {
    'separate': ('--compose', 'none'),
    'control': ('--compose', 'control'),
    'robot': ('--compose', 'robot'),
}
#: The robot loop's closing line: its read-to-write time per period (ms).
LOOP_LINE = re.compile(r'robot loop: .*read->write p50 ([\d.]+) ms, p99 ([\d.]+) ms, '
                       r'max ([\d.]+) ms')
#: Processes that would run on the robot's computer, by the launch's process names
#: (``control``: the composed process of ``--compose control|robot``).
ROBOT_SIDE = frozenset({
    'ardusub_bridge', 'dvl_bridge', 'alpha5_bridge', 'netft_bridge', 'controller',
    'thruster_allocator', 'estimator', 'control', 'recorder',
})
#: The twin stand: the world and the devices' protocol twins.
TWIN_STAND = ('simulator', 'hardware_twins')
#: A row of the launch's closing cost table: ``name  CPU %  M of N (x %)  late`` or ``-``.
COST_ROW = re.compile(r'^\s+(\w+)\s+([\d.]+) %\s+(?:(\d+) of (\d+) \(|-)')
COST_HEADER = 'uvms launch: cost per process'


@dataclass
class Run:
    """One launch as its closing table and recording tell it.

    Attributes:
        outcome: SUCCEEDED, the mission's failure, NODE FAILED or the exit status.
        contacts: Separate contact intervals of the recording (None without a recording).
        cpu: CPU per process (% of one core) from the cost table.
        missed_pct: Missed share per loop process (%).
    """

    outcome: str
    contacts: int | None
    cpu: dict[str, float]
    missed_pct: dict[str, float]
    read_to_write_ms: tuple[float, float, float] | None = None

    @property
    def robot_side(self) -> float:
        """CPU of the processes that would run on the robot's computer (% of one core)."""
        return sum(v for name, v in self.cpu.items() if name in ROBOT_SIDE)


def read_costs(lines: list[str]) -> tuple[dict[str, float], dict[str, float]]:
    """CPU per process and the missed shares of the loop processes from the cost table."""
    cpu: dict[str, float] = {}
    shares: dict[str, float] = {}
    inside = False
    for line in lines:
        if line.startswith(COST_HEADER):
            inside = True
            continue
        match = COST_ROW.match(line) if inside else None
        if match is None or match.group(1) in ('process', 'graph'):
            continue
        cpu[match.group(1)] = float(match.group(2))
        if match.group(4) and int(match.group(4)):
            shares[match.group(1)] = 100.0 * int(match.group(3)) / int(match.group(4))
    return cpu, shares


def launch(layout: str, factor: float, hardware: str, scenario: str, directory: Path,
           root: Path | None = None) -> Run:
    """One ``uvms launch`` to the scenario's end in a layout, read from its output.

    ``root``: another revision's tree to run (``--revision``), this tree's when None.
    """
    output = directory / f'{layout}-{random.randrange(1 << 30)}.mcap'
    env = dict(os.environ, PYTHONPATH=source_path() if root is None else python_path(root),
               ROS_DOMAIN_ID=str(random.randint(1, 100)))
    command = [str(Path(sys.executable).parent / 'uvms'), 'launch', scenario, '--hardware',
               hardware, '--real-time-factor', str(factor), '--output', str(output),
               *LAYOUTS[layout.split('@')[0]]]
    result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=1200,
                            check=False, stdin=subprocess.DEVNULL, cwd=root)
    lines = result.stderr.splitlines()
    outcome = {0: 'SUCCEEDED', 1: 'NODE FAILED', 130: 'INTERRUPTED'}.get(result.returncode,
                                                                       str(result.returncode))
    for line in lines:
        failed = MISSION_FAILED.match(line)
        if failed:
            outcome = failed.group(1)
    cpu, missed = read_costs(lines)
    loop = next((m for m in map(LOOP_LINE.search, lines) if m), None)
    read_to_write = None if loop is None else tuple(float(v) for v in loop.groups())
    if not cpu:
        print(f'    {layout}: no cost table; the end of its output:\n'
              + '\n'.join(f'      {line}' for line in lines[-12:]))
    contacts = None
    if output.is_file():
        from uvms_analysis.metrics import compute_metrics
        from uvms_analysis.series import load_run

        try:
            contacts = compute_metrics(load_run(output)).contact_count
        except Exception as exc:  # a recording cut short by a failed node
            print(f'    {output.name}: no metrics ({type(exc).__name__}: {exc})')
        output.unlink()
    return Run(outcome, contacts, cpu, missed, read_to_write)  # type: ignore[arg-type]


def row(factor: float, layout: str, index: int, run: Run) -> str:
    """One run's Markdown row."""
    robot = ', '.join(f'{name} {value:.0f}' for name, value in sorted(run.cpu.items())
                      if name in ROBOT_SIDE)
    stand = ', '.join(f'{name} {run.cpu[name]:.0f}' for name in TWIN_STAND if name in run.cpu)
    missed = ', '.join(f'{name} {share:.2f}' for name, share in sorted(run.missed_pct.items())
                       if share > 0.0) or '0'
    contacts = '-' if run.contacts is None else str(run.contacts)
    loop = ('-' if run.read_to_write_ms is None
            else ' / '.join(f'{v:.2f}' for v in run.read_to_write_ms))
    return (f'| {factor:g} | {layout} {index} | {run.outcome} | {contacts} | '
            f'{run.robot_side:.0f} ({robot}) | {stand} | {missed} | {loop} |')


def summary(factor: float, runs: dict[str, list[Run]]) -> list[str]:
    """Per layout: footprint range, and its ratios to the baseline (the first layout)."""
    lines = []
    baseline = next(iter(runs))
    base = [r.robot_side for r in runs[baseline]]
    for layout, done in runs.items():
        sides = [r.robot_side for r in done]
        stand = {name: [r.cpu[name] for r in done if name in r.cpu] for name in TWIN_STAND}
        text = (f'factor {factor:g}, {layout}: robot side {min(sides):.0f}-{max(sides):.0f} % '
                f'of one core; twin stand '
                + ', '.join(f'{name} {statistics.fmean(v):.0f} %' for name, v in stand.items()
                            if v))
        if layout != baseline:
            ratios = [s / b for s, b in zip(sides, base, strict=True) if b > 0]
            text += (f'; / {baseline}, round by round: '
                     + (', '.join(f'{r:.2f}' for r in ratios) or '-'))
        lines.append(text)
    return lines


def main() -> None:
    """Rounds of the three layouts per factor; the rows, then the footprints and ratios."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--pairs', type=int, default=2, help='rounds of the three layouts')
    parser.add_argument('--real-time-factors', type=float, nargs='+', default=[1.0, 0.5],
                        metavar='F')
    parser.add_argument('--hardware', default='twin', help='twin or a hardware file')
    parser.add_argument('--scenario', default=SCENARIO)
    parser.add_argument('--layouts', nargs='+', choices=list(LAYOUTS), default=list(LAYOUTS),
                        help='the layouts to run; the first is the baseline of the ratios')
    parser.add_argument('--revision', metavar='REV',
                        help="the robot loop of git revision REV, then this tree's, in turn")
    args = parser.parse_args()
    sys.path[:0] = source_path().split(os.pathsep)
    layouts = [f'robot@{args.revision}', 'robot'] if args.revision else args.layouts
    print(f'load before: {" ".join(f"{v:.2f}" for v in os.getloadavg())} '
          f'({os.cpu_count()} CPUs); {args.scenario} --hardware {args.hardware}')
    print('| factor | layout | outcome | contacts | robot side, % of one core | '
          'twin stand, % | missed %, per loop process | loop read->write p50 / p99 / max, '
          'ms |')
    print('| --- | --- | --- | --- | --- | --- | --- | --- |')
    closing = []
    with tempfile.TemporaryDirectory(prefix='uvms_robot_side_') as directory:
        other = (extract_revision(args.revision, Path(directory) / 'other')
                 if args.revision else None)
        for factor in args.real_time_factors:
            runs: dict[str, list[Run]] = {layout: [] for layout in layouts}
            for index in range(1, args.pairs + 1):
                for layout in layouts:
                    run = launch(layout, factor, args.hardware, args.scenario, Path(directory),
                                 other if '@' in layout else None)
                    runs[layout].append(run)
                    print(row(factor, layout, index, run), flush=True)
            closing += summary(factor, runs)
    print('\n'.join(closing))
    print(f'load after: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')


if __name__ == '__main__':
    main()
