"""Where a sensor bridge's SCHED_FIFO priority belongs: at the control loop's, below, or normal.

Two stand-in processes share CPU 0, as they may on a 2-core robot computer: a controller
(500 Hz, 0.3 ms of work a period, SCHED_FIFO 50) and a 1 kHz sensor bridge (0.15 ms a
sample, and every 200 samples a 10 ms burst: a stream that arrived late and is drained at
once, as a Net F/T bridge does after a pause). The sensor runs at FIFO 50 (the loop's, as
before issue 46), FIFO 40 (``launch_layout.SENSOR_BELOW_LOOP`` below) and normal priority,
beside 0 or N busy loops (``while True: pass`` at normal priority, on CPU 0 too). It prints
how late each one's periods started (p99 and worst), in ms; a sensor that cannot keep up
falls further behind every period, which its lateness shows. Needs SCHED_FIFO (root or
CAP_SYS_NICE). It asserts nothing.

Usage::

    .venv/bin/python bench/bench_rt_sensor_priority.py [--busy 0 2] [--seconds 8]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from collections.abc import Callable

#: A periodic process on CPU 0: argv period_s, work_us, burst_every, burst_us, run_s.
PERIODIC = r"""
import json, os, sys, time
period, work_us, burst_every, burst_us, run_s = (float(a) for a in sys.argv[1:6])
os.sched_setaffinity(0, {0})
late = []
start = time.monotonic()
due = start + period
count = 0
while due - start < run_s:
    time.sleep(max(due - time.monotonic(), 0.0))
    began = time.monotonic()
    late.append(began - due)
    count += 1
    work = burst_us if burst_every and count % int(burst_every) == 0 else work_us
    while time.monotonic() < began + work * 1e-6:
        pass
    due += period
late.sort()
print(json.dumps({'p99_ms': late[int(len(late) * 0.99)] * 1e3, 'max_ms': late[-1] * 1e3}))
"""
BUSY = 'import os\nos.sched_setaffinity(0, {0})\nwhile True:\n    pass\n'


def _at(priority: int) -> Callable[[], None]:
    def setup() -> None:
        if priority:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    return setup


def periodic(priority: int, *args: float) -> subprocess.Popen[str]:
    """Start a periodic stand-in at ``priority`` (0: normal)."""
    return subprocess.Popen([sys.executable, '-c', PERIODIC, *map(str, args)],
                            preexec_fn=_at(priority), stdout=subprocess.PIPE, text=True)


def run(sensor_priority: int, busy: int, seconds: float) -> str:
    """One cell: the controller's and the sensor's lateness, worded."""
    loops = [subprocess.Popen([sys.executable, '-c', BUSY]) for _ in range(busy)]
    try:
        controller = periodic(50, 0.002, 300, 0, 0, seconds)
        sensor = periodic(sensor_priority, 0.001, 150, 200, 10_000, seconds)
        ctrl = json.loads(controller.communicate()[0])
        sens = json.loads(sensor.communicate()[0])
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()
    where = f'FIFO {sensor_priority}' if sensor_priority else 'normal'
    return (f'| {busy} | {where} | {ctrl["p99_ms"]:.2f} | {ctrl["max_ms"]:.2f} | '
            f'{sens["p99_ms"]:.2f} | {sens["max_ms"]:.2f} |')


def main() -> None:
    """Print one row per busy-loop count and sensor priority."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--busy', type=int, nargs='+', default=[0, 2])
    parser.add_argument('--seconds', type=float, default=8.0)
    args = parser.parse_args()
    print(f'load average before: {os.getloadavg()[0]:.1f}')
    print('| busy loops | sensor | controller late p99 ms | worst | sensor late p99 ms | worst |')
    print('| --- | --- | --- | --- | --- | --- |')
    for busy in args.busy:
        for priority in (50, 40, 0):
            print(run(priority, busy, args.seconds), flush=True)
    print(f'load average after: {os.getloadavg()[0]:.1f}')


if __name__ == '__main__':
    main()
