"""CPU of the simulator and the estimator per simulated second: another revision against this tree.

The navigation topics (imu, dvl, depth, position_fix, odometry/filtered) moved to raw CDR
(issue 29/31); this measures what that saved where it is spent: in the simulator process
(sampling and publishing the sensors) and in the estimator process (taking them, filtering,
publishing the estimate on each /clock tick). The graph of a scenario with the estimator
(default ``case1_estimated``) runs as ``uvms launch`` plans it, one process per node, but in
**lockstep** (``plan_launch(..., 'lockstep')``), so every state is answered and a run's
simulated seconds are exact whatever the machine's load. Each process's CPU (user + system)
comes from ``os.wait4``; start-up (imports, model, kernels) is taken off by differencing two
durations: CPU per simulated second = (CPU(long) - CPU(short)) / (long - short).

First, in this process and without middleware, the conversion work itself per simulated
second of ``case1_estimated``'s rates (IMU 200 Hz, depth 20 Hz, DVL 10 Hz, the estimate at
each 500 Hz state): typed (build the message, ``serialize_message`` as a typed publish does;
``deserialize_message`` as a typed take does, then the typed reader) against raw (fill the
payload; read it in place), best of 5 rounds of CPU time.

The other revision's ``src`` and ``config`` are extracted with ``git archive`` and imported
through PYTHONPATH (as bench_ab_cpu.py does; a warm-up run fills its Numba cache first); the
two trees then run in turn, ``--pairs`` times, and the table prints both side by side with
their ratio, and the load average (figures taken while others run are not a quiet machine's).

Usage::

    .venv/bin/python bench/bench_navigation_cpu.py [REV] [--scenario NAME] [--long S]
        [--short S] [--pairs N]
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from other_revision import extract_revision, python_path

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(p) for p in sorted((REPO / 'src').glob('uvms_*')) if p.name != 'uvms_msgs']

from uvms_bringup.launch_helpers import resolve_scenario_path  # noqa: E402
from uvms_bringup.launcher import plan_launch  # noqa: E402
from uvms_common.ros_environment import ros_environment_defaults  # noqa: E402
from uvms_scenarios.scenario import load_scenario  # noqa: E402

#: The processes whose CPU is reported.
WATCHED = ('simulator', 'estimator', 'controller')


#: Messages per simulated second of case1_estimated (paper robot's navigation.yaml, seabed 3 m).
RATES = {'imu': 200, 'depth': 20, 'dvl': 10, 'odometry/filtered': 500}


def conversion_costs(rounds: int = 5, seconds: float = 2.0) -> dict[str, tuple[float, float]]:
    """CPU ms per simulated second of each navigation topic: (typed, raw), both ends."""
    import numpy as np
    from rclpy.serialization import deserialize_message, serialize_message
    from uvms_model.kinematics import rot_ned_from_body
    from uvms_model.nav_sensor_parameters import NavigationParameters
    from uvms_model.nav_sensors import (
        DepthReading,
        DvlReading,
        ImuReading,
        NavigationSensors,
        NavigationTruth,
    )
    from uvms_sim.raw_conversions import UNUSED_VARIANCE, RawNavigationMessages

    from uvms_navigation import conversions, raw_conversions
    from uvms_sim import navigation_topics as typed

    sensors = NavigationSensors(NavigationParameters.from_flat_dict(
        {'world.seabed_depth_m': 3.0}), seed=1)
    found: dict[type, list] = {ImuReading: [], DepthReading: [], DvlReading: []}
    for k in range(0, 2000, 2):
        truth = NavigationTruth.of([0.0, 0.0, 0.25], [0.0, 0.0, 0.0], [0.1, 0.0, 0.0])
        for r in sensors.sample(k * 1_000_000, truth):
            if type(r) in found and getattr(r, 'valid', True):
                found[type(r)].append(r)
    imu_r, depth_r, dvl_r = found[ImuReading][0], found[DepthReading][0], found[DvlReading][0]
    raw = RawNavigationMessages(1e-6, 1e-4)
    p, v, w = np.ones(3), np.ones(3) * 0.1, np.ones(3) * 0.01
    rot, cov = rot_ned_from_body(0.1, 0.2, 0.3), np.eye(6)
    writer = raw_conversions.OdometryWriter()
    readers = {'imu': raw_conversions.imu_reader(), 'depth': raw_conversions.depth_reader(),
               'dvl': raw_conversions.dvl_reader()}
    cases = {
        'imu': (lambda: conversions.imu_arrays(deserialize_message(serialize_message(
                    typed.imu_message(imu_r, 1e-6, 1e-4)), type(typed.imu_message(
                        imu_r, 1e-6, 1e-4)))),
                lambda: readers['imu'].read(raw.imu(imu_r.t_ns, imu_r.rpy, imu_r.rpy_sigma,
                                                    imu_r.w_body, imu_r.f_body))),
        'depth': (lambda: conversions.depth_value(deserialize_message(serialize_message(
                      typed.depth_message(depth_r, 0.01)), type(typed.depth_message(
                          depth_r, 0.01)))),
                  lambda: readers['depth'].read(raw.pose(
                      depth_r.t_ns, (0.0, 0.0, depth_r.depth_m),
                      (UNUSED_VARIANCE, UNUSED_VARIANCE, depth_r.sigma_m ** 2)))),
        'dvl': (lambda: conversions.dvl_arrays(deserialize_message(serialize_message(
                    typed.dvl_message(dvl_r)), type(typed.dvl_message(dvl_r)))),
                lambda: readers['dvl'].read(raw.dvl(dvl_r.t_ns, dvl_r.v_dvl, dvl_r.sigma_m_s))),
        'odometry/filtered': (
            lambda: serialize_message(conversions.odometry_message(0, p, rot, v, w, cov, cov)),
            lambda: writer.payload(0, p, rot, v, w, cov, cov)),
    }
    out = {}
    for topic, pair in cases.items():
        count = round(RATES[topic] * seconds)
        best = []
        for convert in pair:
            times = []
            for _ in range(rounds):
                start = time.process_time()
                for _ in range(count):
                    convert()
                times.append(time.process_time() - start)
            best.append(min(times) / seconds * 1e3)
        out[topic] = (best[0], best[1])
    return out


def run(root: Path, scenario: str, duration_s: float, work: Path, domain: int
        ) -> dict[str, float]:
    """CPU seconds per node process of one lockstep run of ``duration_s`` simulated s."""
    loaded = load_scenario(resolve_scenario_path(scenario, root / 'config'))
    plans = plan_launch(loaded, 'lockstep', work, duration_s=duration_s,
                        config=root / 'config', log_level='warn')
    ros_environment_defaults(os.environ)
    env = {**os.environ, 'PYTHONPATH': python_path(root), 'ROS_DOMAIN_ID': str(domain)}
    procs = {plan.spec.name: subprocess.Popen(plan.command, env=env, cwd=root,
                                              stdout=subprocess.DEVNULL,
                                              stderr=subprocess.DEVNULL)
             for plan in plans}
    cpu: dict[str, float] = {}

    def reap(name: str, proc: subprocess.Popen[bytes]) -> None:
        _, _, usage = os.wait4(proc.pid, 0)
        proc.returncode = 0
        cpu[name] = usage.ru_utime + usage.ru_stime

    reap('simulator', procs.pop('simulator'))  # ends by itself at duration_s
    time.sleep(0.5)
    for proc in procs.values():
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
    for name, proc in procs.items():
        reap(name, proc)
    return cpu


def per_second(long: dict[str, float], short: dict[str, float], seconds: float
               ) -> dict[str, float]:
    """CPU seconds per simulated second of each watched process."""
    return {name: (long[name] - short[name]) / seconds for name in WATCHED}


def main() -> None:
    """Extract the other revision, warm it up, then alternate the two trees."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('rev', nargs='?', default='main', help='revision to compare with')
    parser.add_argument('--scenario', default='case1_estimated')
    parser.add_argument('--long', type=float, default=4.0, help='simulated s of the long run')
    parser.add_argument('--short', type=float, default=1.0, help='simulated s of the short run')
    parser.add_argument('--pairs', type=int, default=1)
    parser.add_argument('--conversions-only', action='store_true')
    args = parser.parse_args()
    print('conversion work per simulated second (CPU ms, both ends, no middleware), '
          f'load average {os.getloadavg()[0]:.2f}:')
    print(f'  {"topic":<20}{"typed":>8}{"raw":>8}{"ratio":>8}')
    total = [0.0, 0.0]
    for topic, (typed_ms, raw_ms) in conversion_costs().items():
        total = [total[0] + typed_ms, total[1] + raw_ms]
        print(f'  {topic:<20}{typed_ms:8.2f}{raw_ms:8.2f}{raw_ms / typed_ms:8.2f}')
    print(f'  {"all":<20}{total[0]:8.2f}{total[1]:8.2f}{total[1] / total[0]:8.2f}', flush=True)
    if args.conversions_only:
        return
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / 'base'
        extract_revision(args.rev, base)
        domain = 40 + os.getpid() % 50
        work = Path(tmp) / 'params'
        work.mkdir()
        run(base, args.scenario, 0.2, work, domain)  # the base tree's Numba cache
        print(f'{args.scenario}, lockstep, one process per node; CPU (user + system) per '
              f'simulated second = (CPU of {args.long:g} s - CPU of {args.short:g} s) / '
              f'{args.long - args.short:g} s; load average before: '
              f'{os.getloadavg()[0]:.2f}', flush=True)
        print(f'  {"pair":<5}{"node":<12}{args.rev:>12}{"this tree":>12}{"ratio":>8}')
        for pair in range(args.pairs):
            figures = {}
            for label, root in ((args.rev, base), ('this tree', REPO)):
                short = run(root, args.scenario, args.short, work, domain)
                long = run(root, args.scenario, args.long, work, domain)
                figures[label] = per_second(long, short, args.long - args.short)
            for name in WATCHED:
                before, after = figures[args.rev][name], figures['this tree'][name]
                print(f'  {pair + 1:<5}{name:<12}{before:12.3f}{after:12.3f}'
                      f'{after / before:8.2f}', flush=True)
        print(f'load average after: {os.getloadavg()[0]:.2f}')


if __name__ == '__main__':
    main()
