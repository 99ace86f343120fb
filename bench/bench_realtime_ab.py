"""CPU per node process in real time: another revision against this tree, alternating.

Runs ``bench/bench_realtime.py`` (one process per node, recording on) of the other revision
and of this tree in turn, ``--pairs`` times, on the same scenario, and prints each run's CPU
per node process (% of one core) side by side, then the mean of each node over the pairs
and the ratio this tree / the other. On a shared machine only the side-by-side ratios mean
something: the load average is printed with each run. The other revision's ``src``,
``config`` and ``bench`` are extracted with ``git archive`` into a temporary directory and
imported through PYTHONPATH (also in the node processes); its Numba kernels compile in a
first, short warm-up run that is not counted.

Usage::

    .venv/bin/python bench/bench_realtime_ab.py REV [--scenario NAME] [--seconds S] [--pairs N]
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from other_revision import extract_revision, python_path

REPO = Path(__file__).resolve().parents[1]
NODES = ('simulator', 'controller', 'thruster_allocator', 'visualizer', 'mission', 'recorder')


def run(root: Path, scenario: str, seconds: float) -> dict[str, float]:
    """CPU per node process (% of a core) and the whole graph of one bench_realtime run."""
    done = subprocess.run(
        [sys.executable, str(root / 'bench' / 'bench_realtime.py'), scenario,
         '--seconds', str(seconds)],
        env=dict(os.environ, PYTHONPATH=python_path(root)), capture_output=True, text=True,
        cwd=root, check=False)
    found = re.search(r'CPU per node process over the window \(% of one core\): (.*); '
                      r'whole graph (\d+)', done.stdout)
    if found is None:
        tail = (done.stdout + done.stderr).strip().splitlines()[-5:]
        raise SystemExit(f'bench_realtime failed in {root}:\n' + '\n'.join(tail))
    cpu = {name: float(value) for name, value in
           (item.rsplit(' ', 1) for item in found.group(1).split(', '))}
    cpu['whole graph'] = float(found.group(2))
    return cpu


def main() -> None:
    """Extract the other revision, warm it up, alternate the two trees, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('rev', help='git revision to compare with (e.g. the merge base)')
    parser.add_argument('--scenario', default='case1_ke1e4')
    parser.add_argument('--seconds', type=float, default=10.0, help='measured wall seconds')
    parser.add_argument('--pairs', type=int, default=2)
    args = parser.parse_args()
    columns = (*NODES, 'whole graph')
    runs: dict[str, list[dict[str, float]]] = {args.rev: [], 'this tree': []}
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / 'base'
        extract_revision(args.rev, base, ('src', 'config', 'bench'))
        run(base, args.scenario, 1.0)  # compiles the other tree's kernels
        print(f'{args.scenario}, real time, {args.seconds:g} s measured per run, one process '
              f'per node, recording on; CPU in % of one core')
        print(f'  {"tree":<12s} {"load":>5s} ' + ' '.join(f'{c[:10]:>10s}' for c in columns))
        for _ in range(args.pairs):
            for label, root in ((args.rev, base), ('this tree', REPO)):
                cpu = run(root, args.scenario, args.seconds)
                runs[label].append(cpu)
                print(f'  {label[:12]:<12s} {os.getloadavg()[0]:5.2f} '
                      + ' '.join(f'{cpu.get(c, float("nan")):10.0f}' for c in columns),
                      flush=True)
    mean = {label: {c: sum(r.get(c, float('nan')) for r in rs) / len(rs) for c in columns}
            for label, rs in runs.items()}
    for label in runs:
        print(f'  {"mean " + label[:7]:<12s} {"":>5s} '
              + ' '.join(f'{mean[label][c]:10.1f}' for c in columns))
    print(f'  {"this / other":<12s} {"":>5s} ' + ' '.join(
        f'{mean["this tree"][c] / mean[args.rev][c]:10.2f}' if mean[args.rev][c] else
        f'{"-":>10s}' for c in columns))


if __name__ == '__main__':
    main()
