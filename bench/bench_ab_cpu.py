"""CPU time of a lockstep ``uvms run`` on another revision and on this tree, alternating.

Wall time on a shared machine says little; the CPU seconds of the one process that runs the
whole graph (all nodes, recording on) say more. The other revision's ``src`` and ``config``
are extracted with ``git archive`` into a temporary directory and imported through
PYTHONPATH (its Numba kernels compile on a first, short warm-up run that is not counted);
then the two trees run the same scenario in turn, ``--pairs`` times, and each run prints its
CPU seconds (user + system, start-up included), its wall line and the load average. A
``--duration 0.5`` run of each tree gives the start-up cost to take off.

Usage::

    .venv/bin/python bench/bench_ab_cpu.py REV [--scenario NAME] [--duration S] [--pairs N]
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

from other_revision import extract_revision, python_path

REPO = Path(__file__).resolve().parents[1]
UVMS = Path(sys.executable).parent / 'uvms'


def run(root: Path, scenario: str, duration: float, output: Path) -> tuple[float, str]:
    """CPU seconds and the summary line of one ``uvms run`` of the tree at ``root``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(
        [str(UVMS), 'run', str(root / 'config' / 'scenarios' / f'{scenario}.yaml'),
         '--duration', str(duration), '--output', str(output)],
        env=dict(os.environ, PYTHONPATH=python_path(root)), capture_output=True, text=True,
        cwd=root, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    found = re.search(r'uvms run: (simulated .*)', done.stdout + done.stderr)
    return cpu, found.group(1) if found else f'exit {done.returncode}'


def main() -> None:
    """Extract the other revision, warm it up, then alternate the two trees."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('rev', help='git revision to compare with (e.g. the merge base)')
    parser.add_argument('--scenario', default='case1_ke1e4')
    parser.add_argument('--duration', type=float, default=10.0, help='simulated s')
    parser.add_argument('--pairs', type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / 'base'
        extract_revision(args.rev, base)
        run(base, args.scenario, 0.5, Path(tmp) / 'warm.mcap')
        print(f'{args.scenario}, {args.duration:g} s simulated, lockstep, recording on; '
              f'{args.rev} against this tree; CPU = user + system of the uvms run process')
        for _ in range(args.pairs):
            for label, root in ((args.rev, base), ('this tree', REPO)):
                cpu, line = run(root, args.scenario, args.duration, Path(tmp) / 'run.mcap')
                print(f'  {label:<12} CPU {cpu:6.2f} s, load {os.getloadavg()[0]:5.2f}: {line}',
                      flush=True)


if __name__ == '__main__':
    main()
