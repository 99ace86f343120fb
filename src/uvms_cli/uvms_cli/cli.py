"""The ``uvms`` command: run, launch, replay, plot, report, sweep, tune, task, param, doctor.

Exit status: 0 success, 1 the run or the tool failed, 2 bad usage or a bad scenario file,
130 interrupted (Ctrl-C). User errors are one line on stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from uvms_common.node_entry import end_process, mark_process_ends_after_main
from uvms_common.ros_environment import ros_environment_defaults
from uvms_common.stop_event import StopEvent
from uvms_sweep.ideal_devices import add_ideal_devices_argument, with_ideal_devices

from uvms_cli.argument_types import port, positive_seconds, seconds_or_zero, seed

if TYPE_CHECKING:
    from uvms_run.graph import Graph
    from uvms_scenarios.scenario import Scenario

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
#: Help of ``--robot`` (run and launch).
ROBOT_HELP = ("a robot folder of uvms_description by name (uvms doctor lists them) or a path "
              "to a robot folder of your own (any name with a /: ./my_robot; docs/robots.md); "
              "default: the scenario's robot:, else paper_uvms")
#: Exit statuses of every subcommand (``uvms --help``; README "Exit statuses").
EXIT_STATUSES = (
    'exit status, every subcommand: 0 success; 1 the run, the task or the tool failed (a node '
    'failed, a task did not succeed, a recording could not be read, no controller '
    'answered); 2 bad usage: a bad option, file, scenario, task file, or robot, found '
    "before anything started; 3 uvms launch only: the scenario's mission failed; 130 "
    'interrupted (Ctrl-C/SIGTERM).')

#: Subcommands handed over whole to another module's ``main(argv) -> int``.
DELEGATED = {
    'replay': ('uvms_recording.replay', 'publish a recording back onto its topics, or re-run '
                                      'the controller on it'),
    'plot': ('uvms_analysis.plots', "draw the paper's figures from a recording (PNG)"),
    'report': ('uvms_analysis.report', 'print the metrics of recordings'),
    'sweep': ('uvms_sweep.cli', 'run a parameter sweep of a scenario on Ray and map '
                                        'its metrics'),
    'tune': ('uvms_tune.cli', "tune the controller's gains by constrained Bayesian "
                              'optimization over scenarios on Ray'),
    'task': ('uvms_tasks.cli', 'send a task or mission file to the controller of a running graph'),
    'hardware': ('uvms_cli.hardware', 'check the devices of a hardware file, changing nothing '
                                      '(uvms hardware check twin|FILE); put back what a '
                                      'crashed bridge left changed (uvms hardware restore '
                                      'ardusub)'),
    'lifecycle': ('uvms_cli.lifecycle', "get or change a managed node's lifecycle state "
                                        '(reset: deactivate + activate, clears a safe hold)'),
    'identify': ('uvms_identify.cli', "identify the vehicle's hydrodynamics from its own "
                                      'recordings (plan, fit)'),
    'param': ('uvms_cli.param', "list, get or set a running node's parameters (as ros2 "
                                'param)'),
    'pilot': ('uvms_pilot.cli', 'drive the vehicle and the arm from the terminal or a gamepad; '
                                'hold, start and cancel a task'),
    'doctor': ('uvms_cli.doctor', 'show rclpy, rmw and DDS profile in use and check the '
                                      'messages'),
}


def _add_params_file_argument(parser: argparse.ArgumentParser) -> None:
    """``--params-file FILE`` (repeatable) of run and launch, as ROS's ``--params-file``."""
    parser.add_argument(
        '--params-file', action='append', default=[], metavar='FILE',
        help='a ROS 2 parameter file (node_name: ros__parameters: ..., /** and /**/node '
             'wildcards) applied to the nodes over the scenario; repeatable, later files '
             'win; every name is checked against what the nodes declare '
             '(e.g. config/tunes/*/gains.yaml; docs/running.md)')


def _add_foxglove_arguments(parser: argparse.ArgumentParser) -> None:
    """``--foxglove [PORT]`` and ``--foxglove-host HOST`` of run and launch."""
    from uvms_viz.foxglove_defaults import FOXGLOVE_HOST, FOXGLOVE_PORT

    parser.add_argument(
        '--foxglove', type=port, nargs='?', const=FOXGLOVE_PORT, metavar='PORT',
        help='serve the running graph to the Foxglove app on ws://127.0.0.1:PORT '
             f'(default port {FOXGLOVE_PORT}; 0 picks a free one)')
    parser.add_argument(
        '--foxglove-host', metavar='HOST', default=None,
        help=f'address the live view binds (default {FOXGLOVE_HOST}, this machine only); '
             'another one makes it reachable from other machines (warned)')


def _foxglove_address(args: argparse.Namespace) -> tuple[str, int] | None:
    """(host, port) of the live view the flags ask for, or None."""
    from uvms_viz.foxglove_defaults import FOXGLOVE_HOST

    if args.foxglove is None:
        if args.foxglove_host is not None:
            msg = '--foxglove-host needs --foxglove [PORT]'
            raise ValueError(msg)
        return None
    return (args.foxglove_host or FOXGLOVE_HOST, args.foxglove)


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``uvms``."""
    parser = argparse.ArgumentParser(
        prog='uvms',
        description='UVMS unified force control stack: run the node graph on a scenario, '
                    'launch it in real time, and analyse recordings.',
        epilog=EXIT_STATUSES,
    )
    sub = parser.add_subparsers(dest='command', metavar='COMMAND')
    run = sub.add_parser(
        'run', help='run a scenario in lockstep (deterministic, as fast as possible)',
        description='Run the whole graph (simulator, controller, thruster_allocator, '
                    'visualizer; mission when the scenario has a mission:, foxglove_server '
                    'with --foxglove, recorder with --output) in one process, in lockstep on '
                    "simulated time, until the scenario's duration_s or --duration.")
    run.add_argument('scenario', metavar='SCENARIO.yaml',
                     help='scenario file, or a name of config/scenarios/NAME.yaml')
    run.add_argument('--duration', type=positive_seconds, metavar='S',
                     help="simulated seconds to run (default: the scenario's duration_s)")
    run.add_argument('--output', '-o', metavar='F.mcap', help='record every topic to this file')
    run.add_argument('--seed', type=seed, metavar='N',
                     help="sensor noise seed (default: the scenario's)")
    run.add_argument('--robot', metavar='NAME',
                     help=ROBOT_HELP)
    run.add_argument('--quiet', '-q', action='store_true',
                     help='no progress bar, only warnings, errors and the summary line')
    run.add_argument('--pilot', metavar='FILE',
                     help="timed pilot commands played by the controller (YAML list; over the "
                          "scenario's pilot:, docs/piloting.md)")
    _add_params_file_argument(run)
    add_ideal_devices_argument(run)
    _add_foxglove_arguments(run)
    launch = sub.add_parser(
        'launch', help="run the graph, one process per node, in real time for the scenario's "
                       'duration_s',
        description='Start simulator, controller, thruster_allocator, visualizer (and '
                    'mission when the scenario has a mission:, foxglove_server with '
                    '--foxglove, recorder with --output) each as its own process, as ros2 '
                    'launch uvms_bringup uvms.launch.py would, on wall-clock timers by '
                    'default. Ctrl-C or '
                    "SIGTERM stops every node; the run ends when the simulator "
                    "reaches the scenario's duration_s or --duration (--duration 0 "
                    'runs on until stopped); a node that fails is named and the others are '
                    "stopped. When the scenario's mission fails, one line says what failed "
                    '("mission failed: NO_CONTACT (the path ended without contact)") and the '
                    'run goes on to its end.',
        epilog='exit status: 0 the simulator reached the duration and every node stopped; '
               '1 a node failed (could not start, crashed, or the simulation diverged; named '
               'on stderr); 2 bad usage or a bad scenario file (nothing started); 3 the '
               "scenario's mission failed (a task did not succeed) and no node failed; 130 "
               'stopped by Ctrl-C/SIGTERM.')
    launch.add_argument('scenario', metavar='SCENARIO.yaml', nargs='?',
                        help='scenario file or name (default: the parameter files only)')
    launch.add_argument('--duration', type=seconds_or_zero, metavar='S',
                        help="stop after this many simulated seconds (default: the scenario's "
                             'duration_s; without a scenario, or with 0: run until Ctrl-C)')
    launch.add_argument('--output', '-o', metavar='F.mcap', help='record every topic to this file')
    launch.add_argument('--mode', choices=('realtime', 'lockstep'), default='realtime',
                        help='execution mode (default: realtime)')
    launch.add_argument('--robot', metavar='NAME',
                        help=ROBOT_HELP)
    launch.add_argument('--quiet', '-q', action='store_true', help='only warnings and errors')
    _add_params_file_argument(launch)
    add_ideal_devices_argument(launch)
    launch.add_argument(
        '--hardware', metavar='twin|FILE',
        help='drive the hardware bridges (ArduSub, DVL, Alpha 5, Net F/T) named by a hardware '
             'file (config/hardware/NAME.yaml or a path): "twin" runs them against protocol '
             'twins fed by the simulator (docs/hardware.md)')
    _add_foxglove_arguments(launch)
    _add_realtime_arguments(launch)
    for name, (_, help_text) in DELEGATED.items():
        sub.add_parser(name, help=help_text, add_help=False)
    return parser


def _add_realtime_arguments(launch: argparse.ArgumentParser) -> None:
    """``--rt-priority N``, ``--no-rt``, ``--cpus LIST`` and ``--lock-memory`` of launch."""
    from uvms_common.scheduling import DEFAULT_RT_PRIORITY, MAX_RT_PRIORITY

    def priority(text: str) -> int:
        value = int(text)
        if not 1 <= value <= MAX_RT_PRIORITY:
            raise argparse.ArgumentTypeError(f'1 to {MAX_RT_PRIORITY}, got {value}')
        return value

    launch.add_argument('--rt-priority', type=priority, default=DEFAULT_RT_PRIORITY,
                        metavar='N',
                        help='SCHED_FIFO priority of simulator, controller, allocator and '
                             f'estimator (default {DEFAULT_RT_PRIORITY}, as ros2_control); '
                             'where refused, one warning and they run at normal priority')
    launch.add_argument('--no-rt', action='store_true',
                        help='every node at normal priority (no SCHED_FIFO)')
    launch.add_argument('--cpus', metavar='LIST', default='',
                        help='pin the loop processes to these CPUs (e.g. 1 or 0,1)')
    launch.add_argument('--lock-memory', action='store_true',
                        help='the loop processes lock their memory in RAM (mlockall)')
    launch.add_argument('--real-time-factor', type=_real_time_factor, default=1.0,
                        metavar='F',
                        help='realtime: simulated seconds per wall second (default 1); below '
                             '1 runs a graph too heavy for this machine slower, every node '
                             'on /clock (docs/running.md)')
    launch.add_argument('--compose', choices=('control', 'robot', 'robot-topics', 'none'),
                        help='control: controller, allocator and estimator in one process; '
                             'robot (default with --hardware): those and the bridges in one '
                             'real-time loop (docs/robot_process.md); robot-topics: that '
                             'process on DDS; none: one process per node')
    launch.add_argument('--twins-apart', action='store_true',
                        help="--hardware twin: the twins in their own process, not the "
                             "simulator's")


def _real_time_factor(text: str) -> float:
    """``--real-time-factor``: a float in the range of the simulator's ``real_time_factor``."""
    from uvms_sim.parameters import SPECS_BY_NAME

    spec = SPECS_BY_NAME['real_time_factor']
    low, high = float(spec.min_value or 0.0), float(spec.max_value or 0.0)
    value = float(text)
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(f'{low:g} to {high:g}, got {value:g}')
    return value


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``uvms``; returns the exit status, or as the console script ends with it."""
    args_list = list(sys.argv[1:] if argv is None else argv)
    ros_environment_defaults()
    # Installed first, so that a signal at any later point (building the graph, opening the
    # recording) ends the run cleanly with status 130.
    stop = StopEvent()
    if argv is None:
        # The console script ends with end_process after main: a delegated command (uvms
        # task) then skips a DDS teardown that could hang (rclpy's ActionClient.destroy).
        mark_process_ends_after_main()
    try:
        status = _main(args_list, stop)
    finally:
        stop.restore()
    if argv is None:
        # The console script: end now. Finalizing the interpreter (Pinocchio, LLVM, rclpy
        # loaded to check the scenario) took 5 s after a stopped launch on 2 loaded cores.
        end_process(status)
    return status


def _main(args_list: list[str], stop: StopEvent) -> int:
    """``main`` once the stop handlers are in place."""
    if args_list and args_list[0] in DELEGATED:
        module = importlib.import_module(DELEGATED[args_list[0]][0])
        try:
            return int(module.main(args_list[1:]) or 0)
        except KeyboardInterrupt:
            return EXIT_INTERRUPTED
    parser = build_parser()
    try:
        args = parser.parse_args(args_list)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    try:
        if args.command == 'run':
            return _run(args, stop)
        return _launch(args, stop)
    except KeyboardInterrupt:
        print('uvms: interrupted', file=sys.stderr)
        return EXIT_INTERRUPTED


def _error(command: str, message: str) -> None:
    """One-line error on stderr."""
    print(f'uvms {command}: error: {message}', file=sys.stderr)


def _check_robot(robot: str | None) -> None:
    """A robot folder that is not there is bad usage (exit 2), found before any node starts.

    Raises:
        ValueError: ``RobotFolderError``, naming the folder or listing the robots there are.
    """
    if robot is not None:
        from uvms_description.robots import robot_files

        robot_files(robot)


def _run(args: argparse.Namespace, stop: StopEvent) -> int:
    """``uvms run``: lockstep run of a scenario in this process."""
    return _run_in_process(args, 'lockstep', stop, progress=not args.quiet)


def _launch(args: argparse.Namespace, stop: StopEvent) -> int:
    """``uvms launch``: one process per node (``uvms_bringup.launcher``), real time by default."""
    from uvms_bringup.launch_helpers import resolve_scenario_path
    from uvms_bringup.launcher import launch_graph
    from uvms_bringup.processes import LaunchError
    from uvms_common.scheduling import parse_cpus
    from uvms_scenarios.scenario import ScenarioError, load_scenario

    try:
        cpus = parse_cpus(args.cpus)
        scenario = None
        duration = args.duration or None  # 0: run on until stopped
        if args.scenario is not None:
            scenario = load_scenario(resolve_scenario_path(args.scenario))
            scenario = scenario.with_changes(duration_s=duration)
            if args.duration is None:
                duration = scenario.duration_s
        scenario = _with_params_files(scenario, args.params_file)
        hardware = None
        if args.hardware is not None:
            from uvms_cli.hardware import launch_plan

            hardware = launch_plan(args.hardware, twins_apart=args.twins_apart)
        if args.twins_apart and not (hardware is not None and hardware.twins):
            raise ValueError('--twins-apart needs --hardware twin: no twins to run apart')
        compose = args.compose or ('robot' if hardware is not None else None)
        if args.ideal_devices:
            scenario = _with_ideal_devices(scenario)
        _check_robot(args.robot or (scenario.robot if scenario is not None else None))
        return launch_graph(scenario, args.mode, duration_s=duration,
                            output_path=args.output, quiet=args.quiet, stop=stop,
                            foxglove=_foxglove_address(args), robot=args.robot,
                            hardware=hardware,
                            rt_priority=0 if args.no_rt else args.rt_priority, cpus=cpus,
                            lock_memory=args.lock_memory,
                            compose=None if compose == 'none' else compose,
                            real_time_factor=args.real_time_factor)
    except (ScenarioError, FileNotFoundError, ValueError) as exc:
        _error('launch', str(exc))
        return EXIT_USAGE
    except LaunchError as exc:
        _error('launch', str(exc))
        return EXIT_FAILURE


def _run_in_process(
    args: argparse.Namespace, mode: str, stop: StopEvent, progress: bool
) -> int:
    """Build and run the graph in this process; report the outcome."""
    from uvms_bringup.launch_helpers import resolve_scenario_path
    from uvms_run.graph import GraphError, build_graph
    from uvms_scenarios.scenario import ScenarioError, load_scenario, short_duration_warning

    command = args.command
    scenario = None
    warning = None
    try:
        if args.scenario is not None:
            scenario = load_scenario(resolve_scenario_path(args.scenario))
            scenario = scenario.with_changes(duration_s=args.duration,
                                             seed=getattr(args, 'seed', None))
            if getattr(args, 'pilot', None):
                from uvms_scenarios.pilot import with_pilot
                scenario = with_pilot(scenario, args.pilot)
            warning = short_duration_warning(scenario, scenario.duration_s)
        duration = args.duration if scenario is None else scenario.duration_s
        scenario = _with_params_files(scenario, args.params_file)
        if args.ideal_devices:
            scenario = _with_ideal_devices(scenario)
        _check_robot(args.robot or (scenario.robot if scenario is not None else None))
        if args.quiet:
            _quiet_logs()
        graph = build_graph(scenario, mode, output_path=args.output, duration_s=duration,
                            foxglove=_foxglove_address(args), robot=args.robot)
    except (ScenarioError, FileNotFoundError, ValueError) as exc:
        _error(command, str(exc))
        return EXIT_USAGE
    except GraphError as exc:
        _error(command, str(exc))
        return EXIT_FAILURE
    if warning:  # after the scenario's keys were checked: a typo's error comes alone
        print(f'uvms {command}: warning: {warning}', file=sys.stderr)
    return _run_graph_and_report(args, graph, mode, stop, progress)


def _with_params_files(scenario: Scenario | None, files: Sequence[str]) -> Scenario | None:
    """The scenario with the ``--params-file`` files' parameters over its own.

    Raises:
        ScenarioError: A file, a section or a name the nodes do not take (named).
    """
    if not files:
        return scenario
    from uvms_bringup.launch_helpers import graph_nodes, uses_estimator
    from uvms_sweep.params_files import apply_params_files

    specs = graph_nodes(record=False, estimator=uses_estimator(scenario))
    return apply_params_files(scenario, files, specs)


def _with_ideal_devices(scenario: Scenario | None) -> Scenario:
    """The scenario (a blank one if None) with ``--ideal-devices``' values over its own."""
    from pathlib import Path

    from uvms_scenarios.scenario import Scenario

    base = scenario if scenario is not None else Scenario(
        path=Path(), name='', description='', duration_s=0.0)
    return replace(base, overrides=with_ideal_devices(base.overrides))


def _run_graph_and_report(
    args: argparse.Namespace, graph: Graph, mode: str, stop: StopEvent, progress: bool
) -> int:
    """Spin a built graph to its end and print the outcome."""
    from uvms_run.bars import RunBar
    from uvms_run.graph import GraphError, run_graph

    command = args.command
    bar = RunBar(graph.duration_s) if progress and graph.duration_s > 0.0 else None
    try:
        result = run_graph(graph, progress=bar, stop=stop)
    except GraphError as exc:
        _error(command, str(exc))
        if args.output:
            print(f'uvms {command}: the recording {args.output} holds the run up to the error',
                  file=sys.stderr)
        return EXIT_FAILURE
    summary = (f'simulated {result.sim_time_s:.2f} s in {result.wall_time_s:.2f} s wall '
               f'({result.real_time_factor:.2f}x real time)')
    if result.lockstep_timeouts:
        summary += f', {result.lockstep_timeouts} lockstep timeouts'
    if result.output_path is not None:
        summary += f'; recorded {result.output_path}'
    print(f'uvms {command}: {summary}', file=sys.stderr)  # --quiet too: where the run went
    return EXIT_INTERRUPTED if result.interrupted else EXIT_OK


def _quiet_logs() -> None:
    """Show only warnings and errors of the nodes."""
    import rclpy.logging

    rclpy.logging.set_logger_level('uvms', rclpy.logging.LoggingSeverity.WARN)


if __name__ == '__main__':
    sys.exit(main())
