"""Start-up of ``uvms launch``: where the seconds to the first simulated step go, before/after.

Runs ``uvms launch SCENARIO --duration 1`` on this tree and on another git revision
(``bench/other_revision.py``, default the revision before issue 40's start-up work),
alternating, and reads the launch's output as it comes: per node process, the time of its
first log line (its imports and rclpy's init done: the node is being built) and of its
ready line (model and kernels loaded), and the time of the simulator's "control loop closed"
line, the first simulated step. Times are wall seconds from the launcher's start (the
lines' own time stamps, ``time.time()`` of the node). It prints a table and asserts nothing.
The imports of one node alone: ``python -X importtime -c 'import uvms_sim.simulator_node'``.

Usage::

    .venv/bin/python bench/bench_startup.py [SCENARIO] [--before REV] [--pairs N]
"""

from __future__ import annotations

import argparse
import os
import random
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from other_revision import REPO, extract_revision, python_path

#: The revision before the start-up changes of issue 40 (lazy scipy.interpolate).
BEFORE = '48c6354'
#: ``[label] [LEVEL] [epoch] [logger]: message`` as the launcher prefixes a node's log line.
LINE = re.compile(r'^\[(\S+?)-\d+\] \[\w+\] \[(\d+\.\d+)\] \[[\w.]+\]: (.*)$')
#: A node's line saying it is built and ready (the last line of its construction).
READY = ('realtime simulation at', 'unified force controller', 'thrusters, ',
         'markers on', 'mission of', 'recording')
FIRST_STEP = 'control loop closed'


def launch_once(scenario: str, tree: Path) -> dict[str, float]:
    """Seconds from the start to each node's first and ready lines, and to the first step."""
    env = dict(os.environ, PYTHONPATH=python_path(tree),
               ROS_DOMAIN_ID=str(random.randint(1, 100)))
    started = time.time()
    result = subprocess.run([str(Path(sys.executable).parent / 'uvms'), 'launch', scenario,
                             '--duration', '1'], env=env, capture_output=True, text=True,
                            timeout=300, check=False)
    times: dict[str, float] = {}
    for line in result.stderr.splitlines():
        match = LINE.match(line)
        if match is None:
            continue
        label, stamp, message = match.group(1), float(match.group(2)) - started, match.group(3)
        times.setdefault(f'{label} first line', stamp)
        if any(message.startswith(r) or r in message for r in READY):
            times.setdefault(f'{label} ready', stamp)
        if message.startswith(FIRST_STEP):
            times['first simulated step'] = stamp
    if 'first simulated step' not in times:
        times['first simulated step'] = float('nan')
        print(f'  no first step seen (status {result.returncode}):\n{result.stderr[-2000:]}')
    return times


def main() -> None:
    """Alternate before and after; print each run's times and the medians."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenario', nargs='?', default='case1_ke1e4')
    parser.add_argument('--before', default=BEFORE, help='git revision to compare against')
    parser.add_argument('--pairs', type=int, default=3)
    args = parser.parse_args()
    print(f'{args.scenario}: uvms launch --duration 1, {args.before} against this tree; '
          f'load {" ".join(f"{v:.2f}" for v in os.getloadavg())} ({os.cpu_count()} CPUs)')
    runs: dict[str, list[dict[str, float]]] = {'before': [], 'after': []}
    with tempfile.TemporaryDirectory(prefix='uvms_startup_') as directory:
        trees = {'before': extract_revision(args.before, Path(directory)), 'after': REPO}
        # Numba's cache is keyed by the source file's path: a fresh extraction compiles every
        # kernel on its first start (8 s more here). One untimed run per tree fills it.
        for tree in trees.values():
            launch_once(args.scenario, tree)
        for _ in range(args.pairs):
            for name, tree in trees.items():
                times = launch_once(args.scenario, tree)
                runs[name].append(times)
                print(f'  {name:<6} first step {times["first simulated step"]:5.2f} s; '
                      + ', '.join(f'{k} {v:.2f}' for k, v in sorted(times.items())
                                  if k != 'first simulated step'), flush=True)
    for name, times in runs.items():
        steps = sorted(t['first simulated step'] for t in times)
        print(f'{name}: first simulated step {steps[len(steps) // 2]:.2f} s median '
              f'({", ".join(f"{s:.2f}" for s in steps)})')
    print(f'load after: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')


if __name__ == '__main__':
    main()
