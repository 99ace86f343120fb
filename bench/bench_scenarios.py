"""Wall time of every shipped scenario, each run through the whole graph with recording.

Runs each scenario of config/scenarios that runs a mission (its full duration, 20 s
simulated; idle_wall, a standby graph waiting for live goals, is left out) as
``uvms run SCENARIO --output F.mcap`` in its own process, ``--jobs`` at a time (default 2,
the development machine's cores), and prints the wall time of each run (process start to
exit, start-up included), their serial sum (what one process after another would take) and
the wall time of the whole batch. Each run gets a ROS domain of its own (``ROS_DOMAIN_ID``
200-214, below the 215-232 of ``uvms sweep``): two lockstep graphs in one domain would hear
each other. Target: the batch under 2 minutes on 2 cores. A benchmark prints figures, it
asserts nothing.

With ``--out DIR`` the recordings are kept; ``--plot`` then writes the figures of each
(``uvms plot``, into DIR/NAME/), ``--docs-figures DIR`` copies the ones docs/results.md shows
there (palette PNGs, a third of the size), and ``--report`` prints the metrics table
(``uvms report --format markdown --force-source contact``: on the ground truth), all after
the timing. This regenerates docs/results.md's numbers and figures in one command::

    .venv/bin/python bench/bench_scenarios.py --out out --plot --docs-figures docs/figures \
        --report

Usage::

    .venv/bin/python bench/bench_scenarios.py [NAME ...] [--jobs N] [--out DIR] [--plot]
        [--docs-figures DIR] [--report] [--duration S]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO

REPO = Path(__file__).resolve().parents[1]
SCENARIO_DIR = REPO / 'config' / 'scenarios'
SOURCES = [str(REPO / 'src' / package) for package in
           ('uvms_common', 'uvms_model', 'uvms_sim', 'uvms_control', 'uvms_thrusters',
            'uvms_bringup')]
sys.path.insert(0, SOURCES[0])

from uvms_common.ros_environment import ros_environment_defaults  # noqa: E402

#: The batch target on the 2-core development machine (s).
TARGET_S = 120.0
#: Wall-clock limit of one run (s): a run past it is stopped and reported as failed.
RUN_TIMEOUT_S = 600.0
#: ROS_DOMAIN_IDs of the runs: the n-th run gets DOMAIN_BASE + n % DOMAIN_COUNT. Two lockstep
#: graphs in one domain hear each other's commands (same node names, same stamps from
#: t = 0) and stall; the test suite uses 0, 1-100 and 150-199, ``uvms sweep`` 215-232.
DOMAIN_BASE = 200
DOMAIN_COUNT = 15
#: The figures docs/results.md shows: ``uvms plot`` output (under --out) -> docs file name.
DOCS_FIGURES = {
    'case1_ke1e4/trajectory_xz.png': 'case1_ke1e4_trajectory_xz.png',
    'case1_ke1e4/force_response.png': 'case1_ke1e4_force.png',
    'case1_ke1e4/position_errors_weight.png': 'case1_ke1e4_errors_weight.png',
    'case1_ke1e5/force_response.png': 'case1_ke1e5_force.png',
    'case2_noise/force_response.png': 'case2_noise_force.png',
    'case3_moving_wall/trajectory_xz.png': 'case3_moving_wall_trajectory_xz.png',
    'case3_moving_wall/vehicle_motion.png': 'case3_moving_wall_vehicle_motion.png',
    'case4_model_error/force_response.png': 'case4_model_error_force.png',
    'hybrid_only/force_response.png': 'hybrid_only_force.png',
    'fuzzy/fuzzy_surface.png': 'fuzzy_surface.png',
}
#: Palette size of the copied figures: line plots and one colour map need no more.
DOCS_FIGURE_COLOURS = 128


@dataclass
class Job:
    """One scenario run in a child process.

    Attributes:
        name: Scenario name.
        output: Its recording.
        process: The running ``uvms run``, None before it starts.
        log: Its stderr (a temporary file: a pipe could fill up and stall the run).
        start: perf_counter at its start (s).
        wall_s: Wall time from start to exit (s), None while running.
        ok: True once it exited with status 0 (a run stopped at RUN_TIMEOUT_S is not).
    """

    name: str
    output: Path
    process: subprocess.Popen[bytes] | None = None
    log: IO[bytes] | None = None
    start: float = 0.0
    wall_s: float | None = None
    ok: bool = False


def uvms(*args: str) -> list[str]:
    """The ``uvms`` command line run by this interpreter (works in a bare checkout too)."""
    return [sys.executable, '-m', 'uvms_cli.cli', *args]


def child_env() -> dict[str, str]:
    """Environment whose PYTHONPATH finds the sources without an install, loopback-only DDS.

    ``uvms`` applies the project's ROS 2 defaults itself; they are set here as well so that
    every child process starts with them, whatever its entry point.
    """
    paths = [*SOURCES, os.environ.get('PYTHONPATH', '')]
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join(p for p in paths if p)}
    ros_environment_defaults(env)
    return env


def run_batch(jobs: list[Job], workers: int, duration_s: float | None = None) -> float:
    """Run the jobs, ``workers`` at a time; returns the batch wall time (s).

    Args:
        jobs: The runs.
        workers: Runs at a time.
        duration_s: Simulated time of each run; None: each scenario's own.
    """
    duration = [] if duration_s is None else ['--duration', f'{duration_s:g}']
    pending, running = list(jobs), []
    env = child_env()
    started = 0
    batch_start = time.perf_counter()
    while pending or running:
        while pending and len(running) < workers:
            job = pending.pop(0)
            domain = str(DOMAIN_BASE + started % DOMAIN_COUNT)
            started += 1
            job.log = tempfile.TemporaryFile()
            job.start = time.perf_counter()
            job.process = subprocess.Popen(
                uvms('run', str(SCENARIO_DIR / f'{job.name}.yaml'), '--output', str(job.output),
                     '--quiet', *duration),
                stdout=subprocess.DEVNULL, stderr=job.log, env={**env, 'ROS_DOMAIN_ID': domain})
            running.append(job)
        time.sleep(0.02)
        for job in list(running):
            assert job.process is not None and job.log is not None
            if job.process.poll() is None:
                if time.perf_counter() - job.start < RUN_TIMEOUT_S:
                    continue
                job.process.kill()
                job.process.wait()
                job.log.seek(0, os.SEEK_END)
                job.log.write(f'\nstopped after {RUN_TIMEOUT_S:g} s wall'.encode())
            job.wall_s = time.perf_counter() - job.start
            running.remove(job)
            job.log.seek(0)
            stderr = job.log.read().decode(errors='replace')
            job.log.close()
            status = job.process.returncode
            job.ok = status == 0
            note = '' if status == 0 else f'  FAILED (exit {status}): {stderr.strip()[-300:]}'
            print(f'{job.name:20s} {job.wall_s:6.1f} s{note}', flush=True)
    return time.perf_counter() - batch_start


def copy_docs_figures(out: Path, target: Path) -> None:
    """Copy the figures docs/results.md shows as palette PNGs (about a third of the bytes)."""
    from PIL import Image  # matplotlib's own dependency

    target.mkdir(parents=True, exist_ok=True)
    for source, name in DOCS_FIGURES.items():
        if not (out / source).is_file():
            print(f'missing {out / source}: run its scenario with --plot')
            continue
        with Image.open(out / source) as image:
            palette = image.convert('RGB').quantize(
                colors=DOCS_FIGURE_COLOURS, method=Image.Quantize.MEDIANCUT,
                dither=Image.Dither.NONE)
        palette.save(target / name, optimize=True)
    print(f'docs figures in {target}/')


def has_mission(path: Path) -> bool:
    """Whether a scenario file runs a mission.

    One without (idle_wall) waits for live goals for an hour of simulated time: nothing to
    measure.
    """
    return any(line.startswith('mission:')
               for line in path.read_text(encoding='utf-8').splitlines())


def main() -> None:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('names', nargs='*', metavar='NAME',
                        help='scenarios of config/scenarios (default: all)')
    parser.add_argument('--jobs', '-j', type=int, default=2, help='parallel runs (default 2)')
    parser.add_argument('--out', default=None,
                        help='keep the recordings here (default: a temporary directory)')
    parser.add_argument('--plot', action='store_true', help='write the figures (needs --out)')
    parser.add_argument('--docs-figures', metavar='DIR', default=None,
                        help="copy docs/results.md's figures here (needs --plot)")
    parser.add_argument('--report', action='store_true', help='print the metrics table')
    parser.add_argument('--duration', type=float, default=None, metavar='S',
                        help="simulated s of each run (default: each scenario's, 20 s; "
                             'shorter runs are for checking the bench, not for the target)')
    args = parser.parse_args()
    if args.plot and args.out is None:
        parser.error('--plot needs --out')
    if args.docs_figures and not args.plot:
        parser.error('--docs-figures needs --plot')
    names = args.names or sorted(path.stem for path in SCENARIO_DIR.glob('*.yaml')
                                 if has_mission(path))
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.out) if args.out else Path(tmp)
        out.mkdir(parents=True, exist_ok=True)
        jobs = [Job(name, out / f'{name}.mcap') for name in names]
        print(f'{len(jobs)} scenarios, {args.jobs} at a time, recording to {out}')
        batch_s = run_batch(jobs, max(1, args.jobs), args.duration)
        # A failed run (an error, or stopped at RUN_TIMEOUT_S) has no meaningful wall time:
        # it counts in neither the sum nor the verdict, and the batch gets no verdict at all.
        done = [job for job in jobs if job.ok]
        failed = len(jobs) - len(done)
        serial_s = sum(job.wall_s or 0.0 for job in done)
        of = f' (the {len(done)} runs that succeeded)' if failed else ''
        print(f'{"serial sum":20s} {serial_s:6.1f} s{of}')
        if failed:
            target = f'{failed} of {len(jobs)} runs FAILED: no verdict on the target'
        elif args.duration is not None:
            target = f'{args.duration:g} s each: the target is for the full durations'
        else:
            verdict = 'under' if batch_s < TARGET_S else 'OVER'
            target = f'{verdict} the {TARGET_S:.0f} s target'
        print(f'{"parallel wall":20s} {batch_s:6.1f} s  ({args.jobs} jobs; {target})')
        recordings = [str(job.output) for job in done if job.output.is_file()]
        if args.plot:
            for job in done:
                if job.output.is_file():
                    subprocess.run(uvms('plot', str(job.output), '--out', str(out / job.name)),
                                   check=False, env=child_env(), stdout=subprocess.DEVNULL)
            subprocess.run(uvms('plot', '--fuzzy', '--out', str(out / 'fuzzy')), check=False,
                           env=child_env(), stdout=subprocess.DEVNULL)
            print(f'figures in {out}/NAME/ and {out}/fuzzy/')
        if args.docs_figures:
            copy_docs_figures(out, Path(args.docs_figures))
        if args.report and recordings:
            sys.stdout.flush()
            subprocess.run(uvms('report', *recordings, '--format', 'markdown',
                                '--force-source', 'contact'), check=False, env=child_env())


if __name__ == '__main__':
    main()
