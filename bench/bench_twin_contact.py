"""The contact task through the robot's protocols against the simulator alone, side by side.

Issues 38 and 39 ask that ``uvms launch bluerov2_alpha5_contact --hardware twin`` (simulator,
the four protocol twins, the four bridges, estimator, controller, allocator, mission and
recorder) succeed with one contact, its mid-contact RMS force error within 10 % and its peak
within 15 % of the simulator-only run's. The simulator-only run is
``bluerov2_alpha5_contact_estimated``: the same scenario with the controller on the same
estimator, nothing in between. This runs both, alternating, ``--runs`` times each, at
``--real-time-factor`` (default 1; a 2-core machine needs 0.5: docs/hardware.md), both with
``--compose control``, and prints one row per run (the contact task's figures as ``uvms
report`` gives them: the simulator's ground-truth contact force, RMS from settling to
release) and the twin runs' ratios to the mean of the simulator-only runs, with the issues'
verdict. ``--hardware FILE``
takes another hardware file (e.g. with other bridge rates). It asserts nothing: only the
figures of an otherwise quiet machine mean something (the load average is printed).

Usage::

    .venv/bin/python bench/bench_twin_contact.py [--runs N] [--real-time-factor F]
        [--hardware twin|FILE]
"""

from __future__ import annotations

import argparse
import os
import random
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from bench_realtime_load import source_path

SIMULATOR_ONLY = 'bluerov2_alpha5_contact_estimated'
THROUGH_TWINS = 'bluerov2_alpha5_contact'
#: The issues' tolerances against the simulator-only run: RMS force error, peak force.
RMS_TOLERANCE, PEAK_TOLERANCE = 0.10, 0.15


def launch(scenario: str, hardware: str | None, factor: float, directory: Path) -> Any:
    """One ``uvms launch`` to the scenario's end: (exit status, the recording's metrics)."""
    output = directory / f'{scenario}-{random.randrange(1 << 30)}.mcap'
    env = dict(os.environ, PYTHONPATH=source_path(), ROS_DOMAIN_ID=str(random.randint(1, 100)))
    command = [str(Path(sys.executable).parent / 'uvms'), 'launch', scenario, '--compose',
               'control', '--real-time-factor', str(factor), '--output', str(output),
               *(['--hardware', hardware] if hardware else [])]
    result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=900,
                            check=False)
    metrics = None
    if output.is_file():
        from uvms_analysis.metrics import task_metrics
        from uvms_analysis.series import load_run

        try:
            run = load_run(output)
            if run.tasks:  # the contact task's row, as `uvms report` gives it
                metrics = task_metrics(run, run.tasks[0])
            else:
                print(f'    {output.name}: no task record in the recording')
        except Exception as exc:  # a recording cut short by a failed node
            print(f'    {output.name}: no metrics ({type(exc).__name__}: {exc})')
        output.unlink()
    return result.returncode, metrics


def figure(value: float | None, digits: int = 2) -> str:
    """A figure of the table, '-' where there is none."""
    return '-' if value is None else f'{value:.{digits}f}'


def row(label: str, status: int, m: Any) -> str:
    """One run's row."""
    if m is None:
        return f'| {label} | exit {status} | - | - | - | - | - |'
    return (f'| {label} | exit {status} | {m.contact_count} | {figure(m.first_contact_time)} | '
            f'{figure(m.contact_duration)} | {figure(m.peak_force)} | '
            f'{figure(m.force_rms_error, 3)} |')


def verdict(reference: list[Any], twin: Any) -> str:
    """The twin run's ratios to the simulator-only mean and whether the issues' checks pass."""
    rms_ref = [m.force_rms_error for m in reference if m and m.force_rms_error]
    peak_ref = [m.peak_force for m in reference if m and m.peak_force]
    if twin is None or not rms_ref or not peak_ref or not twin.force_rms_error:
        return 'no ratio (a run without settled contact)'
    rms = twin.force_rms_error / statistics.fmean(rms_ref)
    peak = twin.peak_force / statistics.fmean(peak_ref)
    ok = (twin.contact_count == 1 and abs(rms - 1.0) <= RMS_TOLERANCE
          and abs(peak - 1.0) <= PEAK_TOLERANCE)
    return f'RMS {rms:.2f}, peak {peak:.3f} of the simulator-only: {"PASS" if ok else "FAIL"}'


def main() -> None:
    """Alternate the two launches; print the rows, then the twin runs' verdicts."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--runs', type=int, default=2, help='runs of each')
    parser.add_argument('--real-time-factor', type=float, default=1.0, metavar='F')
    parser.add_argument('--hardware', default='twin', help='twin or a hardware file')
    args = parser.parse_args()
    sys.path[:0] = source_path().split(os.pathsep)
    print(f'load before: {" ".join(f"{v:.2f}" for v in os.getloadavg())} '
          f'({os.cpu_count()} CPUs); real-time factor {args.real_time_factor:g}, '
          f'--hardware {args.hardware}')
    print('| run | status | contacts | first contact (s) | contact (s) | peak F (N) | '
          'RMS F error (N) |')
    print('| --- | --- | --- | --- | --- | --- | --- |')
    reference: list[Any] = []
    twins: list[Any] = []
    with tempfile.TemporaryDirectory(prefix='uvms_twin_') as directory:
        for i in range(args.runs):
            status, m = launch(SIMULATOR_ONLY, None, args.real_time_factor, Path(directory))
            reference.append(m)
            print(row(f'simulator only {i + 1}', status, m), flush=True)
            status, m = launch(THROUGH_TWINS, args.hardware, args.real_time_factor,
                               Path(directory))
            twins.append(m)
            print(row(f'through the twins {i + 1}', status, m), flush=True)
    for i, m in enumerate(twins):
        print(f'through the twins {i + 1}: {verdict(reference, m)}')
    print(f'load after: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')


if __name__ == '__main__':
    main()
