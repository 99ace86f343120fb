"""Lockstep speed of the whole graph with recording on genuine rclpy, and where the time goes.

Runs scenarios (default: case1_ke1e4 on paper_uvms and bluerov2_alpha5_contact on
bluerov2_alpha5, their 20 s; 1 kHz simulator, 500 Hz control), each through
the in-process graph (``uvms_run.graph``, as ``uvms run`` does) in lockstep with the
recorder on, on the EventsExecutor and/or the SingleThreadedExecutor in this one process,
and prints for each the real-time factor (simulated s per wall s). Those headline runs are
not instrumented.

Where the time goes comes from one more run (EventsExecutor) whose callbacks and publishers
are timed by wrapping them from the outside (``Subscription.callback``, ``Timer.callback``
and ``Publisher.publish`` of each node are writable; node code is not touched): the share of
wall time in each node's callbacks, split into our code and ``publish`` (rclpy serialization
and the rmw). The rest of that run's wall time (executor, waiting, taking and deserializing
messages, DDS delivery) is the middleware's. The wrappers cost time themselves; the table
states how much longer the instrumented run took than the uninstrumented one. The same run
times each node's core the same way (``Plant.step`` and ``observe``,
``UnifiedForceController.step_from_sensors``, ``ThrusterAllocator.step`` wrapped on the
instances), so "our cores" and "our glue" come from one run.

As a baseline the same simulated time runs through the pure cores in a plain loop, no ROS:
``uvms_sim.plant.Plant``, ``UnifiedForceController`` and ``ThrusterAllocator``, built as
the nodes build them from the nodes' own parameter values (a graph is built once to read
them: parameter files plus scenario overrides), stepped as lockstep does: every control
period observe -> controller step -> allocator step -> ``steps_per_publish`` plant steps.
graph wall / plain wall is the middleware's cost (target <= 3.0). Each core is timed in
the loop too (printed with the loop); a node's "glue" in the breakdown is its callback time
minus its publishes minus its core's time in that same instrumented run (conversions, node
logic). Last, the middleware floor (``bench_middleware_floor.py``, warmed up as that bench
does: a first short run settles discovery and caches, the second is measured): the same
message flow through stand-in nodes that do no work, per control period; plain loop + floor
is the least any
node code could take on this runtime, so (plain + floor) / plain bounds the ratio from
below. The last end-effector position of the recording is compared with the plain loop's,
as a check that both ran the same simulation. A benchmark prints figures, it asserts
nothing; the machine's load average is printed with them. ROS_DOMAIN_ID: the
environment's, else a random one of 101-149.

Usage::

    .venv/bin/python bench/bench_graph.py [SCENARIO ...] [--duration S] [--executor KIND]
        [--output F.mcap] [--integrator METHOD] [--no-breakdown]

With several scenarios (the default: one per shipped robot) a last table puts their
graph / plain-loop ratios and real-time factors side by side. The middleware floor is the
raw one (hot topics as CDR bytes, as the nodes publish them since issue 29).
"""

from __future__ import annotations

import argparse
import functools
import os
import random
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
for package in ('uvms_common', 'uvms_model', 'uvms_sim', 'uvms_control', 'uvms_thrusters',
                'uvms_bringup'):
    sys.path.insert(0, str(REPO / 'src' / package))

from bench_middleware_floor import run_floor  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from rclpy.serialization import deserialize_message  # noqa: E402
from uvms_bringup.launch_helpers import (  # noqa: E402
    CONTROLLER,
    SIMULATOR,
    THRUSTER_ALLOCATOR,
    resolve_scenario_path,
)
from uvms_common.robot_parameters import robot_model_values  # noqa: E402
from uvms_common.ros_environment import ros_environment_defaults  # noqa: E402
from uvms_control.controller_node import safety_limits  # noqa: E402
from uvms_control.core.law.unified_controller import UnifiedForceController  # noqa: E402
from uvms_control.core.parameter_specs import (  # noqa: E402
    CONTROLLER_PARAMETER_SPECS,
    SAFETY_PARAMETER_SPECS,
)
from uvms_control.core.parameters import ControllerParameters  # noqa: E402
from uvms_control.core.task.task_supervisor import TaskSupervisor  # noqa: E402
from uvms_control.task_conversions import contact_task_goal  # noqa: E402
from uvms_model.thrusters import ThrusterLayout  # noqa: E402
from uvms_recording.mcap_reader import open_recording  # noqa: E402
from uvms_run.graph import Graph, RunResult, build_graph, run_graph  # noqa: E402
from uvms_scenarios.scenario import ParameterValue, Scenario, load_scenario  # noqa: E402
from uvms_sim.parameters import (  # noqa: E402
    SIMULATOR_PARAMETERS,
    SimulatorSettings,
    default_joint_positions,
)
from uvms_sim.plant import Plant, initial_coordinates  # noqa: E402
from uvms_tasks.goals import goal_from_task  # noqa: E402
from uvms_tasks.task_file import TaskSpec  # noqa: E402
from uvms_thrusters.allocation import AllocatorParameters, ThrusterAllocator  # noqa: E402
from uvms_thrusters.parameter_specs import ALLOCATOR_PARAMETER_SPECS  # noqa: E402
from uvms_thrusters.parameters import thruster_parameters_from_flat_dict  # noqa: E402

from uvms_model import (  # noqa: E402
    PARAMETER_SPECS,
    UvmsModel,
    UvmsParameters,
    load_description,
)

EXECUTORS = ('events', 'single')
#: Longest accepted graph wall / plain-loop wall (the middleware's cost).
TARGET_RATIO = 3.0
#: The recorded end-effector pose, compared with the plain loop's last observation.
EE_POSE_TOPIC = '/uvms/ee_pose'
#: Where each node keeps its core and the core methods its callbacks call per period.
CORE_METHODS = (
    (SIMULATOR.name, '_plant', ('step', 'observe')),
    (CONTROLLER.name, 'core', ('step_from_sensors',)),
    (THRUSTER_ALLOCATOR.name, 'core', ('step',)),
)
#: Control periods of the floor's warm-up run (as bench_middleware_floor.py's main does).
FLOOR_WARMUP_PERIODS = 500
#: ROS_DOMAIN_IDs this bench picks from when none is set, away from the test suite's (0,
#: 1-100, 150-199): another graph in the domain would feed this one's lockstep exchange.
DOMAINS = (101, 149)


class CallbackTimer:
    """Accumulates the wall time (perf_counter, s) of each node's callbacks and publishes."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self.publish_seconds: dict[str, float] = defaultdict(float)
        self.publishes: dict[str, int] = defaultdict(int)
        self.core_seconds: dict[str, float] = defaultdict(float)

    def wrap(self, graph: Graph) -> None:
        """Replace each callback and publish of the graph's nodes by a timed one.

        Raises:
            RuntimeError: A node has no subscription or timer to time (a wrapping that would
                silently measure nothing).
        """
        for name, node in graph.nodes.items():
            entities = [*node.subscriptions, *node.timers]
            if not entities:
                msg = f'node {name!r} has no subscription or timer to time'
                raise RuntimeError(msg)
            for entity in entities:
                if entity.callback is not None:
                    entity.callback = self._timed(name, entity.callback)
            for publisher in node.publishers:
                # An instance attribute shadows Publisher.publish for the node's calls.
                publisher.publish = self._timed_publish(name, publisher.publish)  # type: ignore[method-assign]
        self._wrap_cores(graph)

    def _wrap_cores(self, graph: Graph) -> None:
        """Time each node's core inside the graph: the methods its callbacks call per period.

        Raises:
            RuntimeError: A node no longer holds its core where this looks for it.
        """
        for node_name, attribute, methods in CORE_METHODS:
            core = getattr(graph.nodes[node_name], attribute, None)
            if core is None:
                msg = f'node {node_name!r} has no {attribute!r}: its core cannot be timed'
                raise RuntimeError(msg)
            for method in methods:
                setattr(core, method, self._timed_core(node_name, getattr(core, method)))

    def _timed_core(self, name: str, method: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any, **kwargs: Any) -> Any:
            start = time.perf_counter()
            try:
                return method(*args, **kwargs)
            finally:
                self.core_seconds[name] += time.perf_counter() - start

        return timed

    def _timed(self, name: str, callback: Callable[..., Any]) -> Callable[..., Any]:
        # functools.wraps keeps the signature that rclpy inspects (message, or message+info).
        @functools.wraps(callback)
        def timed(*args: Any) -> Any:
            start = time.perf_counter()
            try:
                return callback(*args)
            finally:
                self.seconds[name] += time.perf_counter() - start
                self.calls[name] += 1

        return timed

    def _timed_publish(self, name: str, publish: Callable[[Any], None]) -> Callable[[Any], None]:
        def timed(msg: Any) -> None:
            start = time.perf_counter()
            try:
                publish(msg)
            finally:
                self.publish_seconds[name] += time.perf_counter() - start
                self.publishes[name] += 1

        return timed


@dataclass
class GraphRun:
    """One run of the graph on one executor (``timer`` None: not instrumented)."""

    executor: str
    build_s: float
    result: RunResult
    timer: CallbackTimer | None
    recording_mb: float
    p_ee_end: np.ndarray | None


@dataclass
class Cores:
    """The pure cores of one run, built as the nodes build them, and the loop's settings."""

    plant: Plant
    controller: UnifiedForceController
    allocator: ThrusterAllocator
    settings: SimulatorSettings
    values: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: The controller node's task supervisor around ``controller`` and the scenario's mission.
    supervisor: TaskSupervisor | None = None
    mission: tuple[TaskSpec, ...] = ()


@dataclass
class PlainRun:
    """The plain loop's wall time (s), control steps, last end-effector position (m).

    ``core_s`` holds the wall time (s) of each core, keyed by the node that runs it.
    """

    wall_s: float
    control_steps: int
    sim_time_s: float
    p_ee_end: np.ndarray
    core_s: dict[str, float]


def node_values(graph: Graph) -> dict[str, dict[str, Any]]:
    """Every parameter of the simulator, controller and allocator, as plain Python values."""

    def plain(value: Any) -> Any:
        if isinstance(value, bool | int | float | str) or value is None:
            return value
        return [plain(item) for item in value]

    return {
        name: {key: plain(parameter.value)
               for key, parameter in graph.nodes[name].get_parameters_by_prefix('').items()}
        for name in (SIMULATOR.name, CONTROLLER.name, THRUSTER_ALLOCATOR.name)
    }


def build_cores(values: Mapping[str, Mapping[str, Any]],
                mission: Sequence[TaskSpec] = ()) -> Cores:
    """Build plant, controller and allocator cores the way their nodes do, from their values.

    Mirrors ``SimulatorNode``, ``ControllerNode`` and ``ThrusterAllocatorNode`` ``__init__``;
    the controller runs inside the node's task supervisor, which the loop hands the mission.
    """
    def model_values(node: Mapping[str, Any]) -> dict[str, Any]:
        # As the nodes do: the robot's URDF and hydrodynamics paths from robot_name.
        return robot_model_values({s.name: node[s.name] for s in PARAMETER_SPECS},
                                  str(node['robot_name']))

    sim = values[SIMULATOR.name]
    params = UvmsParameters.from_flat_dict(model_values(sim))
    settings = SimulatorSettings.from_values({s.name: sim[s.name] for s in SIMULATOR_PARAMETERS})
    n_joints = len(load_description(params.description.urdf_path,
                                    params.description.hydrodynamics_path).joint_names)
    probe = Plant(params, [0.0] * (6 + n_joints), settings.physics_dt_ns)
    q0 = initial_coordinates(probe.model, settings.vehicle_pose,
                             default_joint_positions(settings.joint_positions, n_joints),
                             settings.ee_position if settings.arm_from_ee_position else None)
    plant = Plant(params, q0, settings.physics_dt_ns, settings.wall_enabled,
                  settings.wall_motion_start_force_n)

    ctl = values[CONTROLLER.name]
    gains = ControllerParameters.from_flat_dict(
        {s.name: ctl[s.name] for s in CONTROLLER_PARAMETER_SPECS})
    model = UvmsModel(UvmsParameters.from_flat_dict(model_values(ctl)))
    controller = UnifiedForceController(gains, model)
    supervisor = TaskSupervisor(controller, safety_limits(
        {s.name: ctl[s.name] for s in SAFETY_PARAMETER_SPECS}))

    alloc = values[THRUSTER_ALLOCATOR.name]
    uvms = UvmsParameters.from_flat_dict(model_values(alloc))
    layout = ThrusterLayout.from_parameters(uvms.thrusters)
    joint_names = load_description(uvms.description.urdf_path,
                                   uvms.description.hydrodynamics_path).joint_names
    allocator_values = {s.name: alloc[s.name] for s in ALLOCATOR_PARAMETER_SPECS}
    thruster = thruster_parameters_from_flat_dict(
        {k: v for k, v in allocator_values.items() if k.startswith('thruster.')},
        uvms.hydrodynamics.water_density_kg_m3)
    torque_limits = np.asarray(allocator_values['allocator.max_joint_torque_n_m'], dtype=float)
    if torque_limits.size != len(joint_names):
        msg = (f'allocator.max_joint_torque_n_m has {torque_limits.size} values, '
               f'expected {len(joint_names)}')
        raise ValueError(msg)
    allocator = ThrusterAllocator(AllocatorParameters(
        layout.thrust_matrix(), layout.max_thrust_n, torque_limits, thruster))
    return Cores(plant, controller, allocator, settings, dict(values), supervisor,
                 tuple(mission))


def run_plain_loop(cores: Cores) -> PlainRun:
    """Step the cores as lockstep does, until the simulator's ``duration_s``.

    Every control period: observe (all frames when /tf is due), controller step on the
    observation (what joint_states, odometry and wrench carry), allocator step over the time
    since the last command, then ``steps_per_publish`` plant steps on its output. It ends,
    as the simulator does, once the state at ``duration_s`` has been answered. The controller
    steps inside its task supervisor; the mission's goals go in as the mission node sends
    them: the first after the first step, each next one when the previous ends, from the X_d
    of then (their start times are on the controller's clock, so the graph's run matches).
    """
    plant, allocator = cores.plant, cores.allocator
    supervisor = cores.supervisor
    assert supervisor is not None
    pending = list(cores.mission)
    sent = 0
    settings = cores.settings
    if settings.duration_ns <= 0:
        msg = 'the plain loop needs a positive duration_s'
        raise ValueError(msg)
    clock = time.perf_counter
    plant_s = controller_s = allocator_s = 0.0
    published = 0
    last_stamp_ns: int | None = None
    start = clock()
    while True:
        t0 = clock()
        tf_due = bool(settings.publishes_per_tf) and published % settings.publishes_per_tf == 0
        seen = plant.observe(all_frames=tf_due)
        published += 1
        t1 = clock()
        result, events = supervisor.step(seen.t_ns * 1e-9, seen.q, seen.w, seen.sensor_force)
        if pending and (sent == 0 or events):
            goal = goal_from_task(pending.pop(0), result.X_d.tolist())
            supervisor.submit(sent, contact_task_goal(goal), seen.t_ns * 1e-9)
            sent += 1
        t2 = clock()
        dt_s = 0.0 if last_stamp_ns is None else (seen.t_ns - last_stamp_ns) * 1e-9
        last_stamp_ns = seen.t_ns
        output = allocator.step(result.tau_b, dt_s)
        t3 = clock()
        plant_s += t1 - t0
        controller_s += t2 - t1
        allocator_s += t3 - t2
        if plant.t_ns >= settings.duration_ns:
            break
        for _ in range(settings.steps_per_publish):
            plant.step(output.thrust, output.joint_torques)
        plant_s += clock() - t3
    wall_s = clock() - start
    core_s = {SIMULATOR.name: plant_s, CONTROLLER.name: controller_s,
              THRUSTER_ALLOCATOR.name: allocator_s}
    return PlainRun(wall_s, published, plant.t_ns * 1e-9, seen.poses['ee_link'][0], core_s)


def last_ee_position(path: Path) -> np.ndarray | None:
    """The end-effector position (m, map_ned) of the recording's last ee_pose message."""
    last = None
    for message in open_recording(path).messages(topics=[EE_POSE_TOPIC]):
        last = message
    if last is None:
        return None
    pose = deserialize_message(last.data, PoseStamped).pose.position
    return np.array((pose.x, pose.y, pose.z))


def run_on(
    kind: str,
    scenario: Scenario,
    output: Path,
    extra: Mapping[str, Mapping[str, ParameterValue]] | None,
    instrumented: bool = False,
) -> GraphRun:
    """Build the graph with recording, run it on one executor, its callbacks timed if asked."""
    start = time.perf_counter()
    graph = build_graph(scenario, 'lockstep', output_path=output, extra_overrides=extra)
    build_s = time.perf_counter() - start
    timer = None
    if instrumented:
        timer = CallbackTimer()
        timer.wrap(graph)
    result = run_graph(graph, executor_kind=kind)
    return GraphRun(kind, build_s, result, timer, output.stat().st_size / 1e6,
                    last_ee_position(output))


def print_graph_run(run: GraphRun, plain: PlainRun) -> None:
    """Real-time factor and ratio to the plain loop of an uninstrumented run."""
    result = run.result
    total = result.wall_time_s
    ratio = total / plain.wall_s
    verdict = 'within' if ratio <= TARGET_RATIO else 'OVER'
    print(f'\n== {run.executor} executor ==')
    print(f'graph build         {run.build_s:.2f} s wall')
    print(f'run                 {total:.2f} s wall for {result.sim_time_s:.2f} s simulated')
    print(f'real-time factor    {result.real_time_factor:.2f}x')
    print(f'graph / plain loop  {ratio:.2f} ({verdict} the {TARGET_RATIO:g} target)')
    print(f'recording           {run.recording_mb:.1f} MB; lockstep timeouts '
          f'{result.lockstep_timeouts}')
    if run.p_ee_end is not None:
        gap = float(np.linalg.norm(run.p_ee_end - plain.p_ee_end))
        print(f'last ee position    {np.round(run.p_ee_end, 6).tolist()} m '
              f'(plain loop differs by {gap:.2e} m)')


def print_breakdown(run: GraphRun, uninstrumented: GraphRun | None) -> None:
    """The table of where the wall time of an instrumented run went."""
    timer = run.timer
    assert timer is not None
    total = run.result.wall_time_s
    print(f'\n== where the time goes ({run.executor} executor, callbacks and publishes timed) ==')
    line = f'instrumented run    {total:.2f} s wall'
    if uninstrumented is not None:
        extra = total / uninstrumented.result.wall_time_s - 1.0
        line += f" ({100 * extra:+.0f}% against the uninstrumented run: the wrappers' cost)"
    print(line)
    header = (f'  {"where":<20}{"calls":>8}{"wall s":>8}{"share":>8}{"us/call":>9}'
              f'{"publish s":>10}{"core s":>8}{"glue s":>8}')
    rule = '  ' + '-' * (len(header) - 2)
    print(header)
    print(rule)
    callbacks = publishes = cores = 0.0
    for name in sorted(timer.seconds, key=lambda n: -timer.seconds[n]):
        seconds, calls = timer.seconds[name], timer.calls[name]
        pub_s = timer.publish_seconds[name]
        core_s = timer.core_seconds.get(name, 0.0)
        callbacks += seconds
        publishes += pub_s
        cores += core_s
        print(f'  {name:<20}{calls:>8d}{seconds:>8.2f}{100 * seconds / total:>7.1f}%'
              f'{1e6 * seconds / max(calls, 1):>9.1f}{pub_s:>10.2f}{core_s:>8.2f}'
              f'{seconds - pub_s - core_s:>8.2f}')
    rest = total - callbacks
    print(rule)
    rows = (
        ('our cores', cores, 'timed inside this run'),
        ('our glue', callbacks - publishes - cores,
         'conversions, node logic, recorder writes'),
        ('publish', publishes, 'rclpy serialization + rmw write'),
        ('executor + rest', rest, 'wait, take, deserialize, dispatch, DDS'),
    )
    for label, seconds, note in rows:
        print(f'  {label:<20}{"":>8}{seconds:>8.2f}{100 * seconds / total:>7.1f}%   {note}')
    middleware = publishes + rest
    print(f'  {"middleware":<20}{"":>8}{middleware:>8.2f}{100 * middleware / total:>7.1f}%'
          '   publish + executor + rest')


def main() -> None:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenario', nargs='*',
                        default=['case1_ke1e4', 'bluerov2_alpha5_contact'],
                        help='scenario names or files (default: one per shipped robot)')
    parser.add_argument('--duration', type=float, default=None, help='simulated s')
    parser.add_argument('--executor', choices=(*EXECUTORS, 'both'), default='both',
                        help='executor of the graph (default both, one after the other)')
    parser.add_argument('--output', default=None,
                        help='MCAP file (default: a temporary one; with both executors the '
                             'last run keeps it)')
    parser.add_argument('--integrator', choices=('rk4', 'semi_implicit_euler'), default=None,
                        help="simulator's integration.method (default: config/robot.yaml)")
    parser.add_argument('--side-rates', type=float, default=None, metavar='HZ',
                        help='rate of the topics no node of the loop needs (ee_pose, contact, '
                             'controller/state, thrusters/state; default: every step)')
    parser.add_argument('--no-breakdown', dest='breakdown', action='store_false',
                        help='skip the instrumented run (where the time goes)')
    args = parser.parse_args()
    ros_environment_defaults()
    if not os.environ.get('ROS_DOMAIN_ID'):
        os.environ['ROS_DOMAIN_ID'] = str(random.SystemRandom().randint(*DOMAINS))
    rows = [bench_scenario(name, args) for name in args.scenario]
    if len(rows) > 1:
        print('\n== robots side by side (figures of this one run; machine load: see above) ==')
        print(f'  {"scenario":<26}{"robot":<18}{"executor":<10}{"RTF":>8}{"/ plain":>9}')
        for row in rows:
            for scenario_name, robot, executor, factor, ratio in row:
                print(f'  {scenario_name:<26}{robot:<18}{executor:<10}{factor:>7.2f}x'
                      f'{ratio:>9.2f}')


def bench_scenario(name: str, args: argparse.Namespace) -> list[tuple[str, str, str, float,
                                                                        float]]:
    """Bench one scenario; (scenario, robot, executor, real-time factor, / plain) per run."""
    scenario = load_scenario(resolve_scenario_path(name))
    if args.duration is not None:
        scenario = scenario.with_changes(duration_s=args.duration)
    extra: dict[str, dict[str, ParameterValue]] = {
        SIMULATOR.name: {}, CONTROLLER.name: {}, THRUSTER_ALLOCATOR.name: {}}
    if args.integrator:
        extra[SIMULATOR.name]['integration.method'] = args.integrator
    if args.side_rates is not None:
        extra[SIMULATOR.name]['ground_truth_rate_hz'] = args.side_rates
        extra[CONTROLLER.name]['state_rate_hz'] = args.side_rates
        extra[THRUSTER_ALLOCATOR.name]['state_rate_hz'] = args.side_rates
    kinds = EXECUTORS if args.executor == 'both' else (args.executor,)

    probe = build_graph(scenario, 'lockstep', extra_overrides=extra)
    try:
        cores = build_cores(node_values(probe), scenario.mission)
    finally:
        probe.destroy()
    settings = cores.settings
    integrator = cores.values[SIMULATOR.name]['integration.method']
    load = ', '.join(f'{x:.2f}' for x in os.getloadavg())
    print(f'\n######## {scenario.name} (robot {scenario.robot or "paper_uvms"}) ########')
    print(f'scenario            {scenario.name}: {settings.duration_ns * 1e-9:g} s simulated, '
          f'lockstep, recording on, integrator {integrator}')
    print(f'rates               simulator {1e9 / settings.physics_dt_ns:g} Hz, control '
          f'{1e9 / (settings.physics_dt_ns * settings.steps_per_publish):g} Hz, /tf every '
          f'{settings.publishes_per_tf} states, ee_pose and contact every '
          f'{settings.publishes_per_ground_truth}, controller and thruster state '
          f'{"every step" if args.side_rates is None else f"at {args.side_rates:g} Hz"}')
    print(f'machine             {os.cpu_count()} CPUs, load average {load} (1, 5, 15 min); '
          f'ROS_DOMAIN_ID {os.environ["ROS_DOMAIN_ID"]}')

    runs: list[GraphRun] = []
    breakdown: GraphRun | None = None
    with tempfile.TemporaryDirectory() as tmp:
        for kind in kinds:
            output = Path(args.output) if args.output else Path(tmp) / f'bench_{kind}.mcap'
            runs.append(run_on(kind, scenario, output, extra))
        if args.breakdown:
            breakdown = run_on('events', scenario, Path(tmp) / 'bench_timed.mcap', extra,
                               instrumented=True)
    plain = run_plain_loop(cores)
    periods = plain.control_steps
    run_floor(min(periods, FLOOR_WARMUP_PERIODS), 'events', recorder=True, raw=True)  # warm-up
    floor_s, _ = run_floor(periods, 'events', recorder=True, raw=True)
    print(f'plain loop          {plain.wall_s:.2f} s wall for {plain.sim_time_s:.2f} s '
          f'simulated ({plain.control_steps} control steps, '
          f'{1e6 * plain.wall_s / plain.control_steps:.0f} us each), real-time factor '
          f'{plain.sim_time_s / plain.wall_s:.2f}x')
    print('                    ' + ', '.join(f'{name} core {seconds:.2f} s'
                                              for name, seconds in plain.core_s.items()))
    print(f'middleware floor    {floor_s:.2f} s wall for the same {periods} control periods '
          f'through stand-in nodes that do no work (events executor, hot topics raw, raw '
          f'recorder sink; '
          f'after a warm-up run of {min(periods, FLOOR_WARMUP_PERIODS)}): '
          f'{1e6 * floor_s / periods:.0f} us per period')
    print(f'                    least possible graph / plain loop: '
          f'{(plain.wall_s + floor_s) / plain.wall_s:.2f}')
    for run in runs:
        print_graph_run(run, plain)
    if breakdown is not None:
        events = next((run for run in runs if run.executor == 'events'), None)
        print_breakdown(breakdown, events)

    print('\n== summary ==')
    print(f'  {"":<14}{"wall s":>9}{"RTF":>8}{"/ plain":>9}')
    print(f'  {"plain loop":<14}{plain.wall_s:>9.2f}{plain.sim_time_s / plain.wall_s:>7.2f}x'
          f'{1.0:>9.2f}')
    floor_total = plain.wall_s + floor_s
    print(f'  {"plain + floor":<14}{floor_total:>9.2f}{plain.sim_time_s / floor_total:>7.2f}x'
          f'{floor_total / plain.wall_s:>9.2f}')
    for run in runs:
        wall = run.result.wall_time_s
        print(f'  {run.executor:<14}{wall:>9.2f}{run.result.real_time_factor:>7.2f}x'
              f'{wall / plain.wall_s:>9.2f}')
    if len(runs) == 2:
        events, single = runs
        print(f'  events / single real-time factor: '
              f'{events.result.real_time_factor / single.result.real_time_factor:.2f}')
    robot = scenario.robot or 'paper_uvms'
    return [(scenario.name, robot, run.executor, run.result.real_time_factor,
             run.result.wall_time_s / plain.wall_s) for run in runs]


if __name__ == '__main__':
    main()
