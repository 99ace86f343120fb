"""Real-time mode in one process: does the graph hold 1 kHz simulation and 500 Hz control?

Runs the graph in real time (wall-clock timers, the bundled runtime, one executor thread
unless --threads)
for 30 s of wall time and prints, for each node's timers, the period mean, its 99th
percentile, its maximum and the share of missed periods (timer ticks that never ran
because the callback came late; the simulator then catches up with extra steps), plus how
far simulated time fell behind wall time.
Timer callbacks are timed by wrapping them here; node code is not touched. It prints
figures and asserts nothing.

Usage::

    .venv/bin/python bench/bench_realtime.py [SCENARIO] [--seconds S]
"""

from __future__ import annotations

import argparse
import functools
import sys
import threading
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
for package in ('uvms_model', 'uvms_sim', 'uvms_control', 'uvms_bringup', 'ros2_compat'):
    sys.path.insert(0, str(REPO / 'src' / package))

import ros2_compat  # noqa: E402

ros2_compat.activate()

from uvms_bringup.graph import Graph, build_graph, run_graph  # noqa: E402
from uvms_bringup.launch_helpers import resolve_scenario_path  # noqa: E402
from uvms_bringup.scenario import load_scenario  # noqa: E402


class TimerLog:
    """Start times (perf_counter, s) of each timer callback, keyed by node and period."""

    def __init__(self) -> None:
        self.starts: dict[tuple[str, int], list[float]] = defaultdict(list)
        self.busy_s: dict[tuple[str, int], float] = defaultdict(float)
        self._lock = threading.Lock()

    def wrap(self, graph: Graph) -> None:
        """Wrap every timer callback of the graph's nodes."""
        for name, node in graph.nodes.items():
            for timer in node.timers:
                if timer.callback is not None:
                    key = (name, int(timer.timer_period_ns))
                    timer.callback = self._logged(key, timer.callback)

    def _logged(self, key: tuple[str, int], callback: Callable[[], Any]) -> Callable[[], Any]:
        @functools.wraps(callback)
        def logged() -> Any:
            start = time.perf_counter()
            try:
                return callback()
            finally:
                with self._lock:
                    self.starts[key].append(start)
                    self.busy_s[key] += time.perf_counter() - start

        return logged


def main() -> None:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenario', nargs='?', default='case1_ke1e4')
    parser.add_argument('--seconds', type=float, default=30.0, help='wall-clock duration')
    parser.add_argument('--threads', type=int, default=1,
                        help='executor threads (1: SingleThreadedExecutor, the default of '
                             'uvms launch; more: MultiThreadedExecutor)')
    parser.add_argument('--integrator', choices=('rk4', 'semi_implicit_euler'), default=None,
                        help="simulator's integration.method (default: config/robot.yaml)")
    args = parser.parse_args()
    scenario = load_scenario(resolve_scenario_path(args.scenario))
    extra = {'simulator': {'integration.method': args.integrator}} if args.integrator else None
    graph = build_graph(scenario, 'realtime', duration_s=args.seconds, extra_overrides=extra)
    log = TimerLog()
    log.wrap(graph)
    deadline = [0.0]
    lags_ms: list[float] = []
    start = [0.0]

    def watch(g: Graph) -> None:
        now = time.monotonic()
        if not deadline[0]:
            deadline[0] = now + args.seconds * 1.5
        sim_s = g.simulator.sim_time_ns * 1e-9
        if sim_s > 0.0:
            if not start[0]:
                start[0] = now - sim_s
            lags_ms.append(1e3 * (now - start[0] - sim_s))
        if now > deadline[0]:
            raise KeyboardInterrupt

    result = run_graph(graph, on_spin=watch, threads=args.threads)
    executor = 'SingleThreadedExecutor' if args.threads == 1 else (
        f'MultiThreadedExecutor({args.threads})')
    print(f'scenario          {scenario.name}, real time, one process, {executor}, '
          f'integrator {args.integrator or "config/robot.yaml"}, {result.wall_time_s:.1f} s wall')
    print(f'simulated         {result.sim_time_s:.2f} s '
          f'(real-time factor {result.real_time_factor:.3f}; 1.000 = keeping up)')
    # Lag of simulated time behind the wall clock, from its smallest value (the alignment
    # of the two clocks at start-up is not observable from here).
    lags = np.array(lags_ms) - min(lags_ms)
    print(f'simulated time lag behind the wall clock: mean {lags.mean():.2f} ms, '
          f'p99 {np.percentile(lags, 99):.2f} ms, max {lags.max():.2f} ms')
    header = (f'  {"node":<20s} {"nominal":>9s} {"mean":>9s} {"p99":>9s} {"max":>9s} '
              f'{"missed":>8s} {"busy":>6s}')
    print('timer periods (ms):')
    print(header)
    for (name, period_ns), starts in sorted(log.starts.items()):
        if len(starts) < 3:
            continue
        periods = np.diff(np.array(starts)) * 1e3
        nominal = period_ns * 1e-6
        span_s = starts[-1] - starts[0]
        expected = span_s / (period_ns * 1e-9)
        missed = max(0.0, 1.0 - (len(starts) - 1) / expected) * 100.0 if expected else 0.0
        busy = 100.0 * log.busy_s[(name, period_ns)] / span_s if span_s else 0.0
        print(f'  {name:<20s} {nominal:9.3f} {periods.mean():9.3f} '
              f'{np.percentile(periods, 99):9.3f} {periods.max():9.3f} {missed:7.1f}% '
              f'{busy:5.1f}%')


if __name__ == '__main__':
    main()
