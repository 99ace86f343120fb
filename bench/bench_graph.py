"""Lockstep speed of the whole graph with recording, and where the wall time goes.

Runs a scenario (default: case1_ke1e4, its 20 s) through the in-process graph in lockstep
with the recorder on, and prints the real-time factor (simulated s per wall s) and the
share of wall time spent in each node's callbacks. Callbacks are timed by wrapping them
here, from the outside; node code is not touched. A benchmark prints figures, it asserts
nothing. Targets: at least 2x real time, stretch 5x.

Usage::

    .venv/bin/python bench/bench_graph.py [SCENARIO] [--duration S] [--output F.mcap]
"""

from __future__ import annotations

import argparse
import functools
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
for package in ('uvms_model', 'uvms_sim', 'uvms_control', 'uvms_bringup', 'ros2_compat'):
    sys.path.insert(0, str(REPO / 'src' / package))

import ros2_compat  # noqa: E402

ros2_compat.activate()

from uvms_bringup.graph import Graph, build_graph, run_graph  # noqa: E402
from uvms_bringup.launch_helpers import resolve_scenario_path  # noqa: E402
from uvms_bringup.scenario import load_scenario  # noqa: E402


class CallbackTimer:
    """Accumulates the wall time of every callback of each node (perf_counter, s)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)

    def wrap(self, graph: Graph) -> None:
        """Replace each subscription and timer callback of the graph's nodes by a timed one."""
        for name, node in graph.nodes.items():
            for entity in [*node.subscriptions, *node.timers]:
                if entity.callback is not None:
                    entity.callback = self._timed(name, entity.callback)

    def _timed(self, name: str, callback: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(callback)
        def timed(*args: Any) -> Any:
            start = time.perf_counter()
            try:
                return callback(*args)
            finally:
                self.seconds[name] += time.perf_counter() - start
                self.calls[name] += 1

        return timed


def main() -> None:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenario', nargs='?', default='case1_ke1e4')
    parser.add_argument('--duration', type=float, default=None, help='simulated s')
    parser.add_argument('--output', default=None, help='MCAP file (default: a temporary one)')
    parser.add_argument('--integrator', choices=('rk4', 'semi_implicit_euler'), default=None,
                        help="simulator's integration.method (default: config/robot.yaml)")
    args = parser.parse_args()
    scenario = load_scenario(resolve_scenario_path(args.scenario))
    if args.duration is not None:
        scenario = scenario.with_changes(duration_s=args.duration)
    with tempfile.TemporaryDirectory() as tmp:
        output = Path(args.output) if args.output else Path(tmp) / 'bench.mcap'
        build_start = time.perf_counter()
        extra = ({'simulator': {'integration.method': args.integrator}}
                 if args.integrator else None)
        graph = build_graph(scenario, 'lockstep', output_path=output, extra_overrides=extra)
        build_s = time.perf_counter() - build_start
        timer = CallbackTimer()
        timer.wrap(graph)
        result = run_graph(graph)
        size_mb = output.stat().st_size / 1e6
    total = result.wall_time_s
    integrator = args.integrator or 'config/robot.yaml'
    print(f'scenario            {scenario.name} ({result.sim_time_s:.2f} s simulated, '
          f'lockstep, recording on, integrator {integrator})')
    print(f'graph build         {build_s:.2f} s wall')
    print(f'run                 {total:.2f} s wall')
    print(f'real-time factor    {result.real_time_factor:.2f}x (target >= 2x, stretch 5x)')
    print(f'recording           {size_mb:.1f} MB')
    print(f'lockstep timeouts   {result.lockstep_timeouts}')
    print('share of wall time in callbacks:')
    accounted = 0.0
    for name in graph_order(timer):
        seconds = timer.seconds[name]
        accounted += seconds
        per_call_us = 1e6 * seconds / max(timer.calls[name], 1)
        print(f'  {name:<20s} {100 * seconds / total:5.1f} %  {seconds:7.2f} s  '
              f'{timer.calls[name]:>8d} calls  {per_call_us:7.1f} us/call')
    print(f'  {"executor + rest":<20s} {100 * (total - accounted) / total:5.1f} %  '
          f'{total - accounted:7.2f} s')


def graph_order(timer: CallbackTimer) -> list[str]:
    """Node names, most expensive first."""
    return sorted(timer.seconds, key=lambda name: -timer.seconds[name])


if __name__ == '__main__':
    main()
