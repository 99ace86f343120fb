"""``uvms launch``: one OS process per node, started as ``ros2 run`` / ``ros2 launch`` would.

A wheel venv has no ``launch``/``launch_ros``, so this module does that one job with plain
subprocesses (no rclpy in the launching process): each node's console script (or
``python -m`` of its module when the script is not installed) is started with
``--ros-args -r __node:=NAME -r __ns:=/uvms --params-file ...``, the parameter files of
``config/`` first and then a generated file per node holding the scenario's overrides and
the mode (as launch_ros writes its temporary parameter files). The recorder's
``run.parameters`` holds what the other nodes were given, as ``launch/uvms.launch.py``
fills it. ``uvms_bringup.processes`` starts, watches and stops the processes.
"""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from uvms_common.process_costs import CostWatch
from uvms_common.ros_environment import ros_environment_defaults
from uvms_common.scheduling import DEFAULT_RT_PRIORITY, Scheduling
from uvms_hardware.stop_report import ENV as STOP_REPORT_ENV
from uvms_hardware.stop_report import read_stop_reports, stop_summary
from uvms_scenarios.scenario import Scenario
from uvms_tasks.mission_outcome import EXIT_MISSION_FAILED, read_outcome

from uvms_bringup.composed import LOOP_FLAG
from uvms_bringup.executables import node_executable
from uvms_bringup.hardware_plan import (
    HardwarePlan,
    hardware_nodes,
    hardware_parameters,
    hardware_scenario,
)
from uvms_bringup.launch_helpers import (
    DEFAULT_NAMESPACE,
    MISSION,
    RECORDER,
    SIMULATOR,
    SIMULATOR_WITH_TWINS,
    NodeSpec,
    config_dir,
    file_parameters,
    graph_nodes,
    mission_wait,
    node_parameters,
    parameters_file_text,
    recorder_wait,
    uses_estimator,
    write_mission_file,
)
from uvms_bringup.launch_layout import (
    composed_nodes,
    describe_scheduling,
    launch_scheduling,
    node_niceness,
    node_scheduling,
)
from uvms_bringup.processes import (
    EXIT_FAILURE,
    EXIT_INTERRUPTED,
    EXIT_OK,
    Launcher,
    LaunchError,
    NodeProcess,
    NodeProcessSpec,
    StopRequest,
    end_line,
)
from uvms_common import process_stats


def ros_arguments(
    spec: NodeSpec,
    namespace: str,
    parameter_files: Iterable[Path],
    log_level: str | None = None,
    remaps: Iterable[tuple[str, str]] = (),
    scheduling: Scheduling | None = None,
) -> list[str]:
    """``--ros-args`` of a node: name, namespace and topics remapped, parameter files, scheduling.

    The scheduling goes on the command line (``-p rt_priority:=50``), not into the generated
    parameter file, so that the recorder's ``run.parameters`` holds only the graph's own.
    """
    args = ['--ros-args', '-r', f'__node:={spec.name}', '-r', f'__ns:=/{namespace.strip("/")}']
    for source, target in remaps:
        args += ['-r', f'{source}:={target}']
    for path in parameter_files:
        args += ['--params-file', str(path)]
    if scheduling is not None and scheduling.asks:
        args += ['-p', f'rt_priority:={scheduling.priority}']
        if scheduling.cpus:
            args += ['-p', f"rt_cpus:='{','.join(map(str, scheduling.cpus))}'"]
        if scheduling.lock_memory:
            args += ['-p', 'rt_lock_memory:=true']
    if log_level is not None:
        args += ['--log-level', log_level]
    return args


def plan_launch(
    scenario: Scenario | None,
    mode: str,
    parameters_dir: Path,
    *,
    duration_s: float | None = None,
    output_path: str | Path | None = None,
    namespace: str = DEFAULT_NAMESPACE,
    config: Path | None = None,
    log_level: str | None = None,
    extra_overrides: Mapping[str, Mapping[str, Any]] | None = None,
    bin_dir: Path | None = None,
    foxglove: tuple[str, int] | None = None,
    hardware: HardwarePlan | None = None,
    scheduling: Scheduling | None = None,
    compose: str | None = None,
) -> list[NodeProcessSpec]:
    """The node processes of a launch, with one generated parameter file each.

    Args:
        scenario: The scenario, or None for the parameter files' defaults.
        mode: ``realtime`` or ``lockstep``.
        parameters_dir: Directory to write the generated parameter files to.
        duration_s: Simulated seconds after which the simulator stops; None or 0: never.
        output_path: MCAP file of the recorder; None launches no recorder.
        namespace: Namespace of the nodes.
        config: Directory of robot.yaml and controller.yaml (``config_dir()`` if None).
        log_level: ``--log-level`` of every node (e.g. ``warn``), None for the default.
        extra_overrides: Further parameters per node name (tests, benchmarks).
        bin_dir: Directory of the console scripts (that of ``sys.executable`` if None).
        foxglove: Host and port of a Foxglove live view (``foxglove_server``); None: none.
        hardware: The hardware file's plan (``--hardware``): bridges, twins; None: the
            simulator alone. The scenario must already be ``hardware_scenario``'s.
        scheduling: What the loop processes (``LOOP_NODES``) ask for, the sensor bridges
            ``launch_layout.SENSOR_BELOW_LOOP`` lower; None: nothing.
        compose: A composition of ``uvms_bringup.composed`` (``control``) to run in one
            process; None: one process per node.

    Returns:
        The processes in start order: simulator, controller, thruster allocator,
        visualizer, foxglove_server (for a live view), recorder.

    Raises:
        LaunchError: A parameter file of ``config/`` is missing.
    """
    config = config if config is not None else config_dir()
    output = None if output_path is None else str(Path(output_path).resolve())
    fq_prefix = f'/{namespace.strip("/")}'
    run_values: dict[str, dict[str, Any]] = {}
    plans: list[NodeProcessSpec] = []
    mission = scenario is not None and bool(scenario.mission)
    nodes = graph_nodes(record=output is not None, foxglove=foxglove is not None,
                        mission=mission, estimator=uses_estimator(scenario))
    remaps: list[tuple[str, str]] = []
    if hardware is not None:
        nodes = tuple(hardware_nodes(nodes, hardware))
        added = hardware_parameters(nodes, hardware)
        extra_overrides = {name: {**added.get(name, {}), **(extra_overrides or {}).get(name, {})}
                           for name in {*added, *(extra_overrides or {})}}
        remaps = hardware.simulator_remaps()
    for spec in nodes:
        if spec is MISSION:
            assert scenario is not None
            plans.append(_mission_process(scenario, namespace, parameters_dir, log_level,
                                          bin_dir, len(plans) + 1))
            continue
        overrides: dict[str, Any] = {
            **node_parameters(spec, scenario, mode, duration_s, output, foxglove),
            **recorder_wait(spec, output is not None, scenario),
            **mission_wait(spec, mission),
            **(extra_overrides or {}).get(spec.name, {}),
        }
        files = [config / file for file in spec.parameter_files]
        for path in files:
            if not path.is_file():
                msg = f'node {spec.name!r}: parameter file {path} does not exist'
                raise LaunchError(msg)
        if spec is RECORDER:
            # What the other nodes were given, so that replay can rebuild the controller.
            overrides['run.parameters'] = parameters_file_text(run_values)
        else:
            values: dict[str, Any] = {}
            for path in files:
                values.update(file_parameters(path, spec.name, namespace))
            run_values[f'{fq_prefix}/{spec.name}'] = {**values, **overrides}
        generated = parameters_dir / f'{spec.name}.yaml'
        generated.write_text(parameters_file_text({f'{fq_prefix}/{spec.name}': overrides}),
                             encoding='utf-8')
        asks = node_scheduling(spec, scheduling, hardware is None or not hardware.twins)
        # With the twins in its process the simulator keeps its name, remaps, gates and
        # scheduling; only its executable changes.
        twins_inside = (spec is SIMULATOR and hardware is not None and hardware.twins
                        and hardware.twins_in_simulator)
        command = [*node_executable(SIMULATOR_WITH_TWINS if twins_inside else spec, bin_dir),
                   *ros_arguments(spec, namespace, [*files, generated], log_level,
                                  remaps if spec is SIMULATOR else (), asks)]
        plans.append(NodeProcessSpec(spec, f'{spec.executable}-{len(plans) + 1}',
                                     tuple(command), generated,
                                     rt_priority=asks.priority if asks is not None else 0,
                                     nice=node_niceness(spec, scheduling)))
    if compose is not None:
        from uvms_bringup.composed import COMPOSED, compose_plans

        return compose_plans(plans, compose, node_executable(COMPOSED, bin_dir))
    return plans


def _mission_process(scenario: Scenario, namespace: str, parameters_dir: Path,
                     log_level: str | None, bin_dir: Path | None, index: int
                     ) -> NodeProcessSpec:
    """The mission sender of a scenario: its ``mission:`` copied into a mission file."""
    mission_file = write_mission_file(scenario, parameters_dir)
    outcome_file = parameters_dir / 'mission_outcome.json'
    generated = parameters_dir / 'mission_parameters.yaml'
    generated.write_text(parameters_file_text({f'/{namespace.strip("/")}/mission': {
        'mission_file': str(mission_file), 'outcome_file': str(outcome_file)}}),
        encoding='utf-8')
    command = [*node_executable(MISSION, bin_dir),
               *ros_arguments(MISSION, namespace, [generated], log_level)]
    return NodeProcessSpec(MISSION, f'{MISSION.executable}-{index}', tuple(command), generated,
                           outcome_file)


def launch_graph(
    scenario: Scenario | None,
    mode: str = 'realtime',
    *,
    duration_s: float | None = None,
    output_path: str | Path | None = None,
    namespace: str = DEFAULT_NAMESPACE,
    quiet: bool = False,
    stop: StopRequest | None = None,
    config: Path | None = None,
    foxglove: tuple[str, int] | None = None,
    robot: str | None = None,
    hardware: HardwarePlan | None = None,
    rt_priority: int = DEFAULT_RT_PRIORITY,
    cpus: tuple[int, ...] = (),
    lock_memory: bool = False,
    compose: str | None = None,
    real_time_factor: float = 1.0,
) -> int:
    """Run the graph as one process per node until the duration, a signal, or a failure.

    Args:
        scenario: The scenario, or None for the parameter files' defaults.
        mode: ``realtime`` (wall-clock timers) or ``lockstep`` (the simulator waits for
            the actuator command of each step, across processes).
        duration_s: Simulated seconds after which the simulator exits by itself; None or 0
            runs until stopped.
        output_path: MCAP file to record every topic to; None launches no recorder.
        namespace: Namespace of the nodes.
        quiet: The nodes log only warnings and errors; the launcher reports only errors and
            its closing line.
        stop: Set by SIGINT/SIGTERM (``uvms``'s ``StopEvent``); a ``StopEvent`` of its own
            is installed if None.
        config: Directory of the parameter files (``config_dir()`` if None).
        foxglove: Host and port of a Foxglove live view (a ``foxglove_server`` process);
            None starts none.
        robot: Robot folder (``robot_name`` of the nodes); None: the scenario's or default.
        hardware: A hardware file's plan (``--hardware``): the bridges stand where the
            simulator's device topics were, with the twins on the simulator or on the
            robot (docs/hardware.md); None: the simulator alone.
        rt_priority: SCHED_FIFO priority of the loop processes (``LOOP_NODES``); 0: none.
            Where the system refuses it, one warning line and the graph runs on.
        cpus: CPUs the loop processes are pinned to; empty: every CPU.
        lock_memory: The loop processes lock their memory (``mlockall``).
        compose: ``control`` runs controller, allocator and estimator in one process
            (``uvms_bringup.composed``); None: one process per node.
        real_time_factor: Real time: simulated seconds per wall second (the simulator's
            ``real_time_factor``); below 1 for a machine too small for the graph.

    Returns:
        0 when the simulator reached the duration and every node stopped, 130 after a stop
        request (whatever the mission did: its failure is on stderr), 1 when a node ended
        by itself with an error (named on stderr), 3
        (``EXIT_MISSION_FAILED``) when the scenario's mission failed (``mission failed:
        CODE (message)`` on stderr) and no node did.

    Raises:
        ScenarioError: A scenario override names no parameter of its node or has the wrong
            type (checked before any process starts: a node would ignore it silently).
        LaunchError: A node cannot be started (missing parameter file or executable).
    """
    ros_environment_defaults()
    extra: dict[str, dict[str, Any]] = {}
    if hardware is not None:
        if scenario is None:
            raise LaunchError('--hardware needs a scenario (its robot, its mission)')
        scenario = hardware_scenario(scenario, hardware)
    if scenario is not None:
        scenario = _check_overrides(scenario.with_changes(robot=robot), namespace, config)
    elif robot is not None:
        extra = {spec.name: {'robot_name': robot}
                 for spec in graph_nodes(record=True, foxglove=True) if spec.takes_robot}
    if real_time_factor != 1.0:
        extra.setdefault(SIMULATOR.name, {})['real_time_factor'] = float(real_time_factor)
    scheduling = launch_scheduling(rt_priority, cpus, lock_memory)
    own_stop = None
    if stop is None:
        from uvms_common.stop_event import StopEvent

        stop = own_stop = StopEvent()
    try:
        with tempfile.TemporaryDirectory(prefix='uvms_launch_') as parameters_dir:
            plans = plan_launch(scenario, mode, Path(parameters_dir), duration_s=duration_s,
                                output_path=output_path, namespace=namespace, config=config,
                                log_level='warn' if quiet else None, foxglove=foxglove,
                                extra_overrides=extra, hardware=hardware,
                                scheduling=scheduling, compose=compose)
            stats = Path(parameters_dir) / 'stats'
            reports = Path(parameters_dir) / 'stop_reports'  # what each bridge put back
            reports.mkdir()
            launcher = Launcher(plans, env={**os.environ, process_stats.ENV: str(stats),
                                            STOP_REPORT_ENV: str(reports)})
            line = describe_scheduling(scheduling, plans)
            # On the robot no simulator ends the run: it runs until Ctrl-C or a failure.
            plant = hardware is None or hardware.twins
            return run_launch(launcher, stop, mode, duration_s if plant else None, quiet,
                              line, CostWatch(stats), put_back=None if hardware is None else
                              (reports, list(hardware.bridges)))
    finally:
        if own_stop is not None:
            own_stop.restore()


def _check_overrides(scenario: Scenario, namespace: str, config: Path | None) -> Scenario:
    """The scenario's overrides checked and typed as ``uvms run`` does (ints on floats)."""
    from uvms_bringup.declared import check_scenario_overrides
    from uvms_bringup.node_factory import GraphError

    try:
        return check_scenario_overrides(scenario, config=config, namespace=namespace)
    except GraphError as exc:
        raise LaunchError(str(exc)) from exc


def run_launch(launcher: Launcher, stop: StopRequest, mode: str, duration_s: float | None,
               quiet: bool, scheduling: str, costs: CostWatch,
               put_back: tuple[Path, list[str]] | None = None) -> int:
    """Start, watch and stop a launch; report its outcome, and what each process cost.

    Args:
        launcher: The processes, not started yet.
        stop: Polled for a stop request (SIGINT, SIGTERM).
        mode: ``realtime`` or ``lockstep``, for the launch line.
        duration_s: Simulated duration after which the simulator's exit 0 is the normal
            end; None: the run goes on until stopped or a failure.
        quiet: Report only errors and the closing line.
        scheduling: The loop processes' scheduling, worded for the launch line.
        costs: Where the processes' costs are measured.
        put_back: The folder the bridges report their put-back to and their names: the
            closing line says what each put back (``uvms_hardware.stop_report``); None: no
            bridges.

    Returns:
        The exit status of ``launch_graph``.
    """
    costs.started_ns = time.monotonic_ns()
    launcher.start()
    if not quiet:
        started = ', '.join(f'{p.plan.label} (pid {p.popen.pid})' for p in launcher.processes)
        composed = [(composed_nodes(p.plan), LOOP_FLAG in p.plan.command)
                    for p in launcher.processes]
        layout = '; '.join(f'{names} in one {"real-time loop" if looped else "process"}'
                           for names, looped in composed if names)
        until = f'until {duration_s:g} s simulated or Ctrl-C' if duration_s else 'until Ctrl-C'
        launcher.report(f'uvms launch: {mode} graph, {layout or "one process per node"}: '
                        f'{started}{scheduling}; running {until}')
    told: list[NodeProcess] = []

    def tell_failed_job(process: NodeProcess) -> None:
        """The mission failed: say what failed on a line of its own, once."""
        if process.status == EXIT_MISSION_FAILED and process not in told:
            told.append(process)
            outcome = (read_outcome(process.plan.outcome_file)
                       if process.plan.outcome_file is not None else None)
            launcher.report(outcome.line() if outcome is not None else
                            f'mission failed: {process.name} wrote no outcome; its log says why')

    def poll() -> None:
        line = costs.poll([p.popen.pid for p in launcher.processes])
        if line is not None and not quiet:
            launcher.report(line)

    try:
        # Without a duration the simulator never finishes: its exit, even with 0 (a signal
        # sent to it alone), ends the launch as a failure naming it.
        outcome, process = launcher.wait_for_exit(
            stop, SIMULATOR.name if duration_s else None, tell_failed_job, poll,
            end_reached=lambda: process_stats.read(costs.directory,
                                                   process_stats.END_REACHED) is not None)
    finally:
        costs.end([p.popen.pid for p in launcher.processes])
        launcher.stop()
    if not quiet and costs.first_step_s is not None:
        for line in costs.table([(p.name, p.popen.pid) for p in launcher.processes]):
            launcher.report(line)
    for job in launcher.failed_jobs():
        tell_failed_job(job)  # a mission that failed as the run ended
    for other in launcher.unclean_stops():
        # After a node failed, the others were stopped because of it, some still starting
        # (a Python stopped while it imports its site module exits 1): the failure is named
        # below; their status says nothing more.
        if other is not process and outcome != 'failed':
            launcher.report(f'uvms launch: error: node {other.name!r} {end_line(other)} '
                            'while stopping')
    told_back = ('' if put_back is None else
                 '; ' + stop_summary(read_stop_reports(put_back[0]), put_back[1]))
    if outcome == 'failed' and process is not None:
        launcher.report(f'uvms launch: error: node {process.name!r} ({process.plan.label}) '
                        f'{end_line(process)}; stopped the other nodes{told_back}')
        return EXIT_FAILURE
    unclean = bool(launcher.unclean_stops())
    mission = '; the mission failed' if told else ''
    # The closing line is printed with --quiet too: it is the one summary of the launch.
    if outcome == 'stopped':
        launcher.report(f'uvms launch: interrupted; every node stopped{mission}{told_back}')
        return EXIT_INTERRUPTED  # a stop asked for is 130, as a shell expects after Ctrl-C
    launcher.report(f'uvms launch: the simulator reached {duration_s or 0.0:g} s; '
                    f'every node stopped{mission}{told_back}')
    if unclean:
        return EXIT_FAILURE
    return EXIT_MISSION_FAILED if told else EXIT_OK
