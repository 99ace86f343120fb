"""Real time across processes: does the graph hold 1 kHz simulation and 500 Hz control?

Starts one process per node as ``uvms launch`` does (``uvms_bringup.launcher``), in real
time, and observes them from this process (an rclpy node of its own, started after the
nodes): the arrival time (monotonic clock of this machine) and the stamp of every
message on ``/clock`` (the simulator publishes it with its state every
``steps_per_publish`` = 2 steps of 1 ms), ``/uvms/controller/state`` (the controller's
500 Hz step; published only by a step that computed), ``/uvms/command/generalized_force``
(every controller tick, held or zeroed commands included) and ``/uvms/command/actuators``
(the allocator's 500 Hz tick). Controller and allocator run their timers on ``/clock``
(``use_sim_time``), so they can at best follow the simulator.

The nominal periods are read from the graph as built (``plan_launch``'s parameter files:
the simulator's ``physics_rate_hz`` and ``publish_rate_hz``, the controller's
``control_rate_hz``, the allocator's ``rate_hz``), not assumed. Printed per stream: the
wall-clock period between arrivals (mean, p99, max), the missed periods against the wall
clock (1 - periods done / periods elapsed) and, for the /clock-driven nodes, against
simulated time (1 - stamps / 2 ms slots), and each process's CPU use; then how far
simulated time fell behind the wall clock. The simulator publishes no message per physics
step, so its "step" row is derived, and labelled so: the publication period divided by the
steps per publication (from the parameters, and checked against the /clock stamps, whose
increments are printed as the measured steps per publication). It prints figures and asserts
nothing. Without a scenario it runs both shipped robots one after the other (the paper's
``case1_ke1e4`` and ``bluerov2_alpha5_contact``), and ends with one line per robot against
the targets of issue 29: every stream under 1 % missed periods against simulated time,
controller and allocator each under 20 % of a core, the whole graph (every node process:
the recorder, visualizer and mission too) under one core. The load average of the machine
is printed before and after: figures taken while others run are not a quiet machine's.

Usage::

    .venv/bin/python bench/bench_realtime.py [SCENARIO ...] [--seconds S] [--only-simulator]
"""

from __future__ import annotations

import argparse
import functools
import os
import random
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
for package in ('uvms_common', 'uvms_model', 'uvms_sim', 'uvms_control', 'uvms_thrusters',
                'uvms_bringup'):
    sys.path.insert(0, str(REPO / 'src' / package))

from uvms_bringup.launch_helpers import (  # noqa: E402
    CONTROLLER,
    DEFAULT_NAMESPACE,
    MISSION,
    SIMULATOR,
    THRUSTER_ALLOCATOR,
    file_parameters,
    resolve_scenario_path,
)
from uvms_bringup.launcher import plan_launch  # noqa: E402
from uvms_bringup.processes import Launcher, NodeProcess, NodeProcessSpec  # noqa: E402
from uvms_common.ros_environment import ros_environment_defaults  # noqa: E402
from uvms_scenarios.scenario import load_scenario  # noqa: E402
from uvms_sim.parameters import SIMULATOR_PARAMETERS  # noqa: E402

#: One scenario per shipped robot: the paper's UVMS and the BlueROV2 Heavy with an Alpha 5.
DEFAULT_SCENARIOS = ('case1_ke1e4', 'bluerov2_alpha5_contact')


@dataclass(frozen=True)
class Stream:
    """One observed topic.

    Attributes:
        label: Row name in the table.
        topic: Topic name.
        node: Node that publishes it.
        period_ns: Nominal period of what it times (ns).
        per_publication: Periods per message (the simulator publishes every
            ``steps_per_publish`` steps); above 1 the row is derived, not measured.
        sim_driven: Runs on /clock, so missed periods are also counted in simulated time.
    """

    label: str
    topic: str
    node: str
    period_ns: int
    per_publication: int = 1
    sim_driven: bool = False


@dataclass(frozen=True)
class GraphPeriods:
    """Nominal periods of the graph as built (ns), from its nodes' parameter files.

    Attributes:
        step_ns: The simulator's physics step.
        steps_per_publish: Physics steps per publication of the state and /clock.
        control_ns: The controller's tick.
        allocator_ns: The thruster allocator's tick.
    """

    step_ns: int
    steps_per_publish: int
    control_ns: int
    allocator_ns: int


def plan_parameters(plan: NodeProcessSpec) -> dict[str, Any]:
    """The parameters a planned node process gets: its ``--params-file``s in order, merged."""
    values: dict[str, Any] = {}
    command = list(plan.command)
    for index, arg in enumerate(command[:-1]):
        if arg == '--params-file':
            values.update(file_parameters(Path(command[index + 1]), plan.spec.name,
                                          DEFAULT_NAMESPACE))
    return values


def graph_periods(plans: Sequence[NodeProcessSpec]) -> GraphPeriods:
    """Read the nominal periods from the planned processes (the simulator's defaults if unset)."""
    by_node = {plan.spec.name: plan_parameters(plan) for plan in plans}
    defaults = {spec.name: spec.default for spec in SIMULATOR_PARAMETERS}
    simulator = {**defaults, **by_node[SIMULATOR.name]}
    physics_hz = float(simulator['physics_rate_hz'])
    publish_hz = float(simulator['publish_rate_hz'])
    controller = by_node.get(CONTROLLER.name, {})
    allocator = by_node.get(THRUSTER_ALLOCATOR.name, {})
    return GraphPeriods(
        step_ns=round(1e9 / physics_hz),
        steps_per_publish=round(physics_hz / publish_hz),
        control_ns=round(1e9 / float(controller.get('control_rate_hz', publish_hz))),
        allocator_ns=round(1e9 / float(allocator.get('rate_hz', publish_hz))),
    )


def streams_of(periods: GraphPeriods) -> tuple[Stream, ...]:
    """The observed streams with the graph's nominal periods."""
    n = periods.steps_per_publish
    return (
        Stream(f'sim step derived/{n}', '/clock', SIMULATOR.name, periods.step_ns, n),
        Stream('simulator publish', '/clock', SIMULATOR.name, periods.step_ns * n),
        Stream('controller step', '/uvms/controller/state', CONTROLLER.name,
               periods.control_ns, sim_driven=True),
        Stream('controller tick', '/uvms/command/generalized_force', CONTROLLER.name,
               periods.control_ns, sim_driven=True),
        Stream('allocator tick', '/uvms/command/actuators', THRUSTER_ALLOCATOR.name,
               periods.allocator_ns, sim_driven=True),
    )


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process so far (s), from /proc."""
    try:
        fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    except OSError:
        return float('nan')
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def stamp_ns(msg: Any) -> int:
    """Stamp of a Clock message or of a message with a header (ns)."""
    stamp = msg.clock if hasattr(msg, 'clock') else msg.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def row(stream: Stream, samples: Sequence[tuple[int, Any]], window_ns: int,
        cpu_percent: float) -> str:
    """One table row from (arrival ns, message) samples inside the window."""
    if len(samples) < 3:
        return f'  {stream.label:<18s} {stream.topic:<32s} fewer than 3 messages'
    arrivals = np.array([t for t, _ in samples], dtype=np.int64)
    stamps = np.array(sorted({stamp_ns(msg) for _, msg in samples}), dtype=np.int64)
    periods_ms = np.diff(arrivals) * 1e-6 / stream.per_publication
    nominal_ms = stream.period_ns * 1e-6
    done = (len(samples) - 1) * stream.per_publication
    missed_wall = max(0.0, 1.0 - done * stream.period_ns / window_ns) * 100.0
    missed_sim = '-'
    if stream.sim_driven:
        slots = (stamps[-1] - stamps[0]) / stream.period_ns
        missed_sim = f'{max(0.0, 1.0 - (len(stamps) - 1) / slots) * 100.0:6.1f}%'
    return (f'  {stream.label:<18s} {stream.topic:<32s} {nominal_ms:7.3f} '
            f'{periods_ms.mean():8.3f} {np.percentile(periods_ms, 99):8.3f} '
            f'{periods_ms.max():8.3f} {missed_wall:6.1f}% {missed_sim:>7s} {cpu_percent:5.0f}%')


def observe(launcher: Launcher, topics: dict[str, type], warmup_s: float, seconds: float,
            domain_id: int) -> tuple[dict[str, list[tuple[int, bytes]]], int, int,
                                     dict[str, float]]:
    """Subscribe raw, wait for every topic plus the warm-up, record ``seconds`` of arrivals.

    Returns:
        Topic to (arrival ns, raw message), the window's start and end (monotonic ns), and
        each node's CPU use over the window (% of one core).
    """
    import rclpy
    from rclpy.context import Context
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy.signals import SignalHandlerOptions
    from uvms_common.node_main import make_executor

    context = Context()
    rclpy.init(args=[], context=context, domain_id=domain_id,
               signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node('bench_observer', context=context)
    arrivals: dict[str, list[tuple[int, bytes]]] = {topic: [] for topic in topics}

    def on_message(topic: str, data: bytes) -> None:
        arrivals[topic].append((time.monotonic_ns(), data))

    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    for topic, msg_class in topics.items():
        node.create_subscription(msg_class, topic, functools.partial(on_message, topic), qos,
                                 raw=True)
    executor = make_executor('events', context)
    executor.add_node(node)

    def spin_until(condition: Any, timeout_s: float, what: str) -> None:
        deadline = time.monotonic() + timeout_s
        while not condition():
            if time.monotonic() > deadline:
                raise SystemExit(f'bench: {what} not within {timeout_s} s')
            for process in launcher.processes:
                # The mission ends by itself when its goals are done (or aborted).
                if process.name != MISSION.name and process.poll() is not None:
                    raise SystemExit(f'bench: {process.name} ended with {process.status}')
            executor.spin_once(timeout_sec=0.05)

    try:
        spin_until(lambda: all(arrivals.values()), 60.0, 'a message on every topic')
        warm_end = time.monotonic() + warmup_s
        spin_until(lambda: time.monotonic() > warm_end, warmup_s + 5.0, 'warm-up')
        cpu_start = {p.name: cpu_seconds(p.popen.pid) for p in launcher.processes}
        start_ns = time.monotonic_ns()
        end = time.monotonic() + seconds
        spin_until(lambda: time.monotonic() > end, seconds + 5.0, 'the measurement')
        end_ns = time.monotonic_ns()
        cpu = {p.name: 100.0 * (cpu_seconds(p.popen.pid) - cpu_start[p.name])
               / ((end_ns - start_ns) * 1e-9) for p in launcher.processes}
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return arrivals, start_ns, end_ns, cpu


def main() -> None:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenarios', nargs='*', default=list(DEFAULT_SCENARIOS),
                        help='scenarios to run in turn (default: one per shipped robot)')
    parser.add_argument('--seconds', type=float, default=20.0,
                        help='wall-clock seconds measured, after the warm-up')
    parser.add_argument('--warmup', type=float, default=2.0,
                        help='wall-clock seconds skipped once every topic has a message')
    parser.add_argument('--no-record', action='store_true',
                        help='launch without the recorder (by default it records, in its own '
                             'process, into a temporary file, as uvms launch --output does)')
    parser.add_argument('--only-simulator', action='store_true',
                        help='start the simulator alone (what it can do without the others)')
    parser.add_argument('--executor', choices=('events', 'single'), default=None,
                        help="the nodes' executor (UVMS_EXECUTOR; default: events)")
    parser.add_argument('--integrator', choices=('rk4', 'semi_implicit_euler'), default=None,
                        help="simulator's integration.method (default: config/robot.yaml)")
    args = parser.parse_args()
    summaries = [run_one(args, name) for name in args.scenarios]
    print(f'load average after: {" ".join(f"{v:.2f}" for v in os.getloadavg())} '
          f'({os.cpu_count()} CPUs)')
    print('against the targets (sim-time missed < 1 % per stream, controller and allocator '
          '< 20 % of a core each, whole graph < 100 %):')
    for line in summaries:
        print(f'  {line}')


def run_one(args: argparse.Namespace, scenario_name: str) -> str:
    """Launch one scenario, observe it, print its tables; return its summary line."""
    print(f'load average before {scenario_name}: '
          f'{" ".join(f"{v:.2f}" for v in os.getloadavg())} ({os.cpu_count()} CPUs)')
    ros_environment_defaults()
    domain_id = int(os.environ.get('ROS_DOMAIN_ID') or random.randint(1, 100))
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain_id))
    if args.executor:
        env['UVMS_EXECUTOR'] = args.executor
    scenario = load_scenario(resolve_scenario_path(scenario_name))
    extra = {'simulator': {'integration.method': args.integrator}} if args.integrator else None

    from rosgraph_msgs.msg import Clock

    from uvms_msgs.msg import ActuatorCommand, ControllerState, GeneralizedForce

    classes: dict[str, type] = {'/clock': Clock, '/uvms/controller/state': ControllerState,
                                '/uvms/command/generalized_force': GeneralizedForce,
                                '/uvms/command/actuators': ActuatorCommand}
    with tempfile.TemporaryDirectory(prefix='uvms_bench_') as parameters_dir:
        output = None if args.no_record else Path(parameters_dir) / 'bench.mcap'
        plans = plan_launch(scenario, 'realtime', Path(parameters_dir), log_level='warn',
                            extra_overrides=extra, output_path=output)
        periods = graph_periods(plans)
        streams = [s for s in streams_of(periods)
                   if not args.only_simulator or s.node == SIMULATOR.name]
        topics = {s.topic: classes[s.topic] for s in streams}
        if args.only_simulator:
            plans = [plan for plan in plans if plan.spec is SIMULATOR]
        # Started before this process creates its own DDS participant (and its threads).
        launcher = Launcher(plans, env=env)
        launcher.start()
        try:
            arrivals, start_ns, end_ns, cpu = observe(launcher, topics, args.warmup,
                                                      args.seconds, domain_id)
        finally:
            launcher.stop()
    return report(args, scenario.name, periods, streams, classes, arrivals, start_ns, end_ns,
                  cpu, launcher.processes)


def report(args: argparse.Namespace, scenario: str, periods: GraphPeriods,
           streams: Sequence[Stream], classes: dict[str, type],
           arrivals: dict[str, list[tuple[int, bytes]]], start_ns: int, end_ns: int,
           cpu: dict[str, float], processes: Sequence[NodeProcess]) -> str:
    """Print the table of periods, CPU per node and the lag; return the summary line."""
    from rclpy.serialization import deserialize_message

    window = {topic: [(t, deserialize_message(data, classes[topic]))
                      for t, data in samples if start_ns <= t <= end_ns]
              for topic, samples in arrivals.items()}
    window_ns = end_ns - start_ns
    nodes = ', '.join(p.name for p in processes)
    print(f'scenario {scenario}, real time, one process per node ({nodes}), executor '
          f'{args.executor or os.environ.get("UVMS_EXECUTOR", "events")}, integrator '
          f'{args.integrator or "config/robot.yaml"}; {window_ns * 1e-9:.1f} s measured after '
          f'{args.warmup:g} s warm-up; {os.cpu_count()} CPUs')
    print(f'nominal periods from the built graph: physics step {periods.step_ns * 1e-6:g} ms, '
          f'{periods.steps_per_publish} steps per publication, controller '
          f'{periods.control_ns * 1e-6:g} ms, allocator {periods.allocator_ns * 1e-6:g} ms')
    print('periods (ms) from arrival times in a separate observer process; missed periods '
          'against the wall clock and, for /clock-driven nodes, against simulated time')
    print(f'  {"stream":<18s} {"topic":<32s} {"nominal":>7s} {"mean":>8s} {"p99":>8s} '
          f'{"max":>8s} {"missed":>7s} {"sim":>7s} {"cpu":>6s}')
    missed: dict[str, float] = {}
    for stream in streams:
        print(row(stream, window[stream.topic], window_ns, cpu.get(stream.node, float('nan'))))
        share = missed_sim_share(stream, window[stream.topic])
        if share is not None:
            missed[stream.label] = share
    print('CPU per node process over the window (% of one core): ' + ', '.join(
        f'{name} {value:.0f}' for name, value in cpu.items())
        + f'; whole graph {sum(cpu.values()):.0f}')
    clock = window['/clock']
    if len(clock) >= 2:
        increments = np.diff(sorted({stamp_ns(msg) for _, msg in clock}))
        if increments.size:
            print(f'  (derived: the simulator publishes no message per step; its row is the '
                  f'publication period / {periods.steps_per_publish}. Measured in the /clock '
                  f'stamps: median increment {np.median(increments) * 1e-6:g} ms = '
                  f'{np.median(increments) / periods.step_ns:g} steps)')
        wall_s = (clock[-1][0] - clock[0][0]) * 1e-9
        sim_s = (stamp_ns(clock[-1][1]) - stamp_ns(clock[0][1])) * 1e-9
        # Wall minus simulated time of each /clock arrival, from the window's first one.
        lag_ms = np.array([(t - stamp_ns(msg)) * 1e-6 for t, msg in clock])
        lag_ms -= lag_ms[0]
        print(f'simulated {sim_s:.2f} s in {wall_s:.2f} s wall: real-time factor '
              f'{sim_s / wall_s:.3f} (1.000 = keeping up); over the window simulated time fell '
              f'{lag_ms[-1]:.0f} ms behind the wall clock (arrival jitter: p99 of the lag '
              f'increments {np.percentile(np.diff(lag_ms), 99):.2f} ms)')
    for process in processes:
        if process.status not in (0, 130, None):
            print(f'note: {process.name} ended with status {process.status}')
    by_node = {p.name: cpu[p.name] for p in processes if p.name in cpu}
    worst = max(missed.items(), key=lambda item: item[1], default=('-', float('nan')))
    control = {name: by_node.get(name, float('nan'))
               for name in (CONTROLLER.name, THRUSTER_ALLOCATOR.name)}
    total = sum(by_node.values())
    ok = (worst[1] < 1.0 and all(v < 20.0 for v in control.values()) and total < 100.0)
    return (f'{scenario}: worst sim-time missed {worst[1]:.1f} % ({worst[0]}); controller '
            f'{control[CONTROLLER.name]:.0f} %, allocator {control[THRUSTER_ALLOCATOR.name]:.0f} '
            f'%, whole graph {total:.0f} % of a core: {"met" if ok else "NOT met"}')


def missed_sim_share(stream: Stream, samples: Sequence[tuple[int, Any]]) -> float | None:
    """Missed periods against simulated time (%), for a /clock-driven stream."""
    if not stream.sim_driven or len(samples) < 3:
        return None
    stamps = sorted({stamp_ns(msg) for _, msg in samples})
    slots = (stamps[-1] - stamps[0]) / stream.period_ns
    return max(0.0, 1.0 - (len(stamps) - 1) / slots) * 100.0 if slots > 0 else None


if __name__ == '__main__':
    main()
