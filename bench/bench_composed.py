"""What controller and allocator in one process would save: CPU, side by side, in real time.

Issue 29 asks for the controller and the allocator each under 20 % of a core and the whole
graph under one core, with one process per node. This measures the alternative it left
open: the same launch (``plan_launch``, real time, recording), once as ``uvms launch`` starts
it and once as ``uvms launch --compose control`` does, the controller and the thruster
allocator built in one process on one executor (``uvms_bringup.composed``: their messages to
each other stay in the process),
alternating, each run observed like ``bench_realtime`` (CPU of every process over the
window; the controller's states and the allocator's commands counted against the 2 ms
periods of the window). It prints figures and asserts nothing.

Usage::

    .venv/bin/python bench/bench_composed.py [SCENARIO] [--seconds S] [--pairs N]
"""

from __future__ import annotations

import argparse
import os
import random
import tempfile
from pathlib import Path

from bench_realtime import observe  # also puts the packages on sys.path
from uvms_bringup.composed import COMPOSED
from uvms_bringup.launch_helpers import CONTROLLER, THRUSTER_ALLOCATOR, resolve_scenario_path
from uvms_bringup.launcher import plan_launch
from uvms_bringup.processes import Launcher
from uvms_common.ros_environment import ros_environment_defaults
from uvms_scenarios.scenario import load_scenario

PAIR = COMPOSED.name
#: Topics counted against the 2 ms periods: the controller's step and the allocator's tick.
COUNTED = ('/uvms/controller/state', '/uvms/command/actuators')


def run(scenario_name: str, compose: bool, seconds: float) -> tuple[dict[str, float], str]:
    """CPU per process (% of a core) and the periods line of one observed launch."""
    from rosgraph_msgs.msg import Clock

    from uvms_msgs.msg import ActuatorCommand, ControllerState

    ros_environment_defaults()
    domain_id = random.randint(1, 100)
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain_id))
    scenario = load_scenario(resolve_scenario_path(scenario_name))
    topics = {'/clock': Clock, COUNTED[0]: ControllerState, COUNTED[1]: ActuatorCommand}
    with tempfile.TemporaryDirectory(prefix='uvms_bench_') as parameters_dir:
        plans = plan_launch(scenario, 'realtime', Path(parameters_dir), log_level='warn',
                            output_path=Path(parameters_dir) / 'bench.mcap',
                            compose='control' if compose else None)
        launcher = Launcher(plans, env=env)
        launcher.start()
        try:
            arrivals, start_ns, end_ns, cpu = observe(launcher, topics, 3.0, seconds, domain_id)
        finally:
            launcher.stop()
    periods = (end_ns - start_ns) / 2e6
    done = [sum(start_ns <= t <= end_ns for t, _ in arrivals[topic]) for topic in COUNTED]
    line = ', '.join(f'{topic.rsplit("/", 1)[1]} {max(0.0, 1 - n / periods):.1%} missed'
                     for topic, n in zip(COUNTED, done, strict=True))
    return cpu, line


def main() -> None:
    """Alternate the two layouts and print CPU per process and the sums."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenario', nargs='?', default='case1_ke1e4')
    parser.add_argument('--seconds', type=float, default=15.0, help='measured wall seconds')
    parser.add_argument('--pairs', type=int, default=2)
    args = parser.parse_args()
    print(f'{args.scenario}, real time, recording; {args.seconds:g} s measured per run; '
          f'load {" ".join(f"{v:.2f}" for v in os.getloadavg())} ({os.cpu_count()} CPUs)')
    sums: dict[bool, list[tuple[float, float]]] = {False: [], True: []}
    for _ in range(args.pairs):
        for compose in (False, True):
            cpu, line = run(args.scenario, compose, args.seconds)
            pair = (cpu[PAIR] if compose
                    else cpu[CONTROLLER.name] + cpu[THRUSTER_ALLOCATOR.name])
            graph = sum(cpu.values())
            sums[compose].append((pair, graph))
            layout = 'composed ' if compose else 'separate '
            print(f'  {layout} ' + ', '.join(f'{name} {value:.0f}' for name, value in cpu.items())
                  + f'; controller + allocator {pair:.0f} %, graph {graph:.0f} %; {line}',
                  flush=True)
    for compose in (False, True):
        pairs = [p for p, _ in sums[compose]]
        graphs = [g for _, g in sums[compose]]
        print(f'{"composed" if compose else "separate"}: controller + allocator '
              f'{min(pairs):.0f}-{max(pairs):.0f} % of a core, whole graph '
              f'{min(graphs):.0f}-{max(graphs):.0f} %')
    ratio = [c[0] / s[0] for s, c in zip(sums[False], sums[True], strict=True)]
    print('composed / separate, controller + allocator, pair by pair: '
          + ', '.join(f'{r:.2f}' for r in ratio))
    print(f'load after: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')


if __name__ == '__main__':
    main()
