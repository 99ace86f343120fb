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
import io
import os
import signal
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(p) for p in sorted((REPO / 'src').glob('uvms_*')) if p.name != 'uvms_msgs']

from uvms_bringup.launch_helpers import resolve_scenario_path  # noqa: E402
from uvms_bringup.launcher import plan_launch  # noqa: E402
from uvms_bringup.scenario import load_scenario  # noqa: E402
from uvms_common.ros_environment import ros_environment_defaults  # noqa: E402

#: The processes whose CPU is reported.
WATCHED = ('simulator', 'estimator', 'controller')


def python_path(root: Path) -> str:
    """PYTHONPATH importing a tree's packages (uvms_msgs is the built one of the venv)."""
    return ':'.join(str(p) for p in sorted((root / 'src').glob('uvms_*'))
                    if p.name != 'uvms_msgs')


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
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / 'base'
        archive = subprocess.run(['git', 'archive', args.rev, 'src', 'config'], cwd=REPO,
                                 capture_output=True, check=True).stdout
        with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
            tar.extractall(base, filter='data')
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
