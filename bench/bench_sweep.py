"""Points per minute of `uvms sweep` with 1 and 2 Ray workers, and Ray's cost per point.

A fixed small sweep (case1_ke1e4, ``--points`` values of controller.model.mass_scale from
0.9 to 1.1, ``--duration`` simulated seconds each, no recording) runs three ways in this
one invocation, each point a full lockstep graph run in its own process and DDS domain:

1. plain: the same points one after another, each through ``sweep_point.execute_point``
   (the supervisor a Ray task runs) called directly: no Ray;
2. ``run_sweep`` on a local Ray with 1 worker (Ray start-up and shutdown timed apart);
3. ``run_sweep`` on a local Ray with 2 workers.

It prints points per minute of each, the scaling ratio (2 workers / 1 worker; 2.0 would be
perfect on 2 free cores), and Ray's overhead per point: (1-worker sweep - plain) / points,
which includes the table rewrite after each point and the figures at the end. A benchmark
prints figures, it asserts nothing; the machine's load average is printed with them (other
work on the 2 cores lowers the 2-worker figure first). Run it inside the loopback-only
network namespace like the tests::

    tools/loopback-netns .venv/bin/python bench/bench_sweep.py [--points N] [--duration S]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

SWEEP = """\
name: bench_sweep
scenario: case1_ke1e4
duration_s: {duration}
record: false
axes:
  controller.model.mass_scale: {{linspace: [0.9, 1.1, {points}]}}
metrics: [vehicle_displacement_mm]
"""


def main() -> int:
    """Run the three ways and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--points', type=int, default=6, help='points of the sweep (6)')
    parser.add_argument('--duration', type=float, default=1.0,
                        help='simulated seconds per point (1.0)')
    args = parser.parse_args()

    # Imported here, before anything imports ray: start_local_ray sets Ray's environment.
    from uvms_common.ros_environment import ros_environment_defaults
    from uvms_sweep.point import execute_point
    from uvms_sweep.sweep_file import load_sweep
    from uvms_sweep.validate import check_sweep

    from uvms_sweep import engine as sweep_engine

    ros_environment_defaults()
    with tempfile.TemporaryDirectory(prefix='bench-sweep-') as tmp:
        path = Path(tmp) / 'sweep.yaml'
        path.write_text(SWEEP.format(duration=args.duration, points=args.points),
                        encoding='utf-8')
        sweep, scenario = check_sweep(load_sweep(path))
        duration = sweep.duration_s or scenario.duration_s
        points = sweep.points(scenario.name, duration, scenario.seed)
        n = len(points)

        start = time.monotonic()
        failed = 0
        for point in points:
            request = sweep_engine.point_request(sweep, scenario, point, duration)
            outcome = execute_point(request, sweep_engine.DOMAIN_IDS[0], sweep.timeout_s)
            failed += outcome['status'] != 'done'
        plain_s = time.monotonic() - start

        timings = {}
        for workers in (1, 2):
            start = time.monotonic()
            ray = sweep_engine.start_local_ray(workers)
            init_s = time.monotonic() - start
            start = time.monotonic()
            summary = sweep_engine.run_sweep(sweep, scenario, Path(tmp) / f'w{workers}',
                                             workers=workers, progress=False)
            sweep_s = time.monotonic() - start
            start = time.monotonic()
            ray.shutdown()
            timings[workers] = (init_s, sweep_s, time.monotonic() - start, summary.failed)

    load = ', '.join(f'{x:.2f}' for x in os.getloadavg())
    print(f'bench_sweep: {n} points of {duration:g} s simulated (case1_ke1e4, mass_scale '
          f'0.9-1.1), {os.cpu_count()} CPUs, load average {load}')
    print(f'  plain, one after another : {plain_s:6.1f} s  {60.0 * n / plain_s:5.1f} points/min'
          f'  ({plain_s / n:.2f} s per point, {failed} failed)')
    for workers, (init_s, sweep_s, down_s, fails) in timings.items():
        print(f'  Ray, {workers} worker{"s" if workers > 1 else " "}            : '
              f'{sweep_s:6.1f} s  {60.0 * n / sweep_s:5.1f} points/min  (Ray start '
              f'{init_s:.1f} s, shutdown {down_s:.1f} s, {fails} failed)')
    ratio = timings[1][1] / timings[2][1]
    overhead = (timings[1][1] - plain_s) / n
    print(f'  scaling 2 workers / 1 worker: {ratio:.2f}x points/min')
    print(f'  Ray overhead per point (1 worker - plain): {overhead:+.2f} s '
          f'({100.0 * overhead / (plain_s / n):+.0f} % of a point)')
    return 0


if __name__ == '__main__':
    sys.path.insert(0, str(REPO / 'src' / 'uvms_common'))
    sys.exit(main())
