"""The whole node graph in one process: build it from the parameter files and run it.

``run_graph`` builds simulator, controller, thruster allocator (and recorder when there is
an output file) in the namespace ``/uvms``, each from its ROS 2 parameter files
(``--params-file``) plus the scenario's overrides (``parameter_overrides``), exactly as a
launch file would configure separate processes. Lockstep runs spin a
SingleThreadedExecutor until the simulator has reached the scenario's duration in
simulated time; real-time runs spin on wall-clock timers until the duration or Ctrl-C
(single-threaded by default, see ``run_graph``).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import rclpy
import rclpy.logging
from rclpy.context import Context
from rclpy.executors import Executor, ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from uvms_bringup.declared import check_scenario_overrides
from uvms_bringup.launch_helpers import (
    DEFAULT_NAMESPACE,
    RECORDER,
    SIMULATOR,
    config_dir,
    graph_nodes,
    mission_wait,
    node_parameters,
    parameters_file_text,
    uses_estimator,
)
from uvms_bringup.node_factory import GraphError, make_node
from uvms_common.node_main import StopEvent, make_executor
from uvms_scenarios.scenario import ParameterValue, Scenario
from uvms_tasks.mission_node import MissionNode

from uvms_run.bars import RunBar
from uvms_run.stall_watch import StallWatch, stall_limit_s

#: Longest wall-clock wait for any callback before the lockstep loop checks on the graph (s).
_SPIN_TIMEOUT_S = 0.5
#: Wall-clock time given to the last messages to reach the recorder after the run (s).
_DRAIN_S = 0.1


@dataclass
class RunResult:
    """Outcome of a run.

    Attributes:
        sim_time_s: Simulated time reached (s).
        wall_time_s: Wall-clock time of the run, start-up excluded (s).
        output_path: MCAP file written, if any.
        lockstep_timeouts: Steps the simulator took without the command of its step.
        interrupted: True if Ctrl-C stopped the run.
    """

    sim_time_s: float
    wall_time_s: float
    output_path: Path | None = None
    lockstep_timeouts: int = 0
    interrupted: bool = False

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.sim_time_s / self.wall_time_s if self.wall_time_s > 0.0 else float('inf')


@dataclass
class Graph:
    """The nodes of one run, built but not spinning.

    Attributes:
        context: The rclpy context the nodes live in.
        nodes: Node name to node, in start order.
        mode: ``lockstep`` or ``realtime``.
        duration_s: Simulated duration (s); 0 runs until stopped.
        output_path: MCAP file the recorder writes, if it runs.
    """

    context: Context
    nodes: dict[str, Node] = field(default_factory=dict)
    mode: str = 'lockstep'
    duration_s: float = 0.0
    output_path: Path | None = None

    @property
    def simulator(self) -> Any:
        """The simulator node (``uvms_sim.simulator_node.SimulatorNode``)."""
        return self.nodes[SIMULATOR.name]

    def destroy(self) -> None:
        """Destroy every node (the recorder closes its file) and shut the context down."""
        errors = []
        for node in reversed(list(self.nodes.values())):
            try:
                node.destroy_node()
            except Exception as exc:
                errors.append(f'{node.get_name()}: {exc}')
        self.nodes.clear()
        rclpy.try_shutdown(context=self.context)
        if errors:
            raise GraphError('while shutting the graph down: ' + '; '.join(errors))


def build_graph(
    scenario: Scenario | None,
    mode: str = 'lockstep',
    *,
    output_path: str | Path | None = None,
    duration_s: float | None = None,
    namespace: str = DEFAULT_NAMESPACE,
    config: Path | None = None,
    extra_overrides: Mapping[str, Mapping[str, ParameterValue]] | None = None,
    foxglove: tuple[str, int] | None = None,
    robot: str | None = None,
) -> Graph:
    """Build the nodes of the graph in a fresh rclpy context.

    Args:
        scenario: The scenario, or None for the parameter files' defaults.
        mode: ``lockstep`` or ``realtime``.
        output_path: MCAP file to record to; None runs without recorder.
        duration_s: Simulated duration; None takes the scenario's (0: forever).
        namespace: Namespace of the nodes.
        config: Directory of robot.yaml and controller.yaml (``config_dir()`` if None).
        extra_overrides: Further parameters per node name (tests, benchmarks).
        foxglove: Host and port of a Foxglove live view (the ``foxglove_server`` node);
            None runs without it.
        robot: Robot folder (``robot_name`` of the nodes that take it); None: the
            scenario's ``robot:``, else the nodes' default (paper_uvms).

    Raises:
        ScenarioError: A scenario override names no parameter of its node, or has the
            wrong type; the message names the file, key and expected type.
        GraphError: A node cannot be built (invalid parameter file value, ...).
    """
    config = config if config is not None else config_dir()
    if duration_s is None:
        duration_s = scenario.duration_s if scenario is not None else 0.0
    specs = graph_nodes(record=output_path is not None, foxglove=foxglove is not None,
                        estimator=uses_estimator(scenario))
    if scenario is not None:
        scenario = check_scenario_overrides(scenario.with_changes(robot=robot), specs, config,
                                            namespace)
    overrides = {
        spec.name: {
            **node_parameters(spec, scenario, mode, duration_s,
                              None if output_path is None else str(output_path), foxglove,
                              robot),
            **mission_wait(spec, scenario is not None and bool(scenario.mission)),
            **(extra_overrides or {}).get(spec.name, {}),
        }
        for spec in specs
    }
    context = Context()
    # No rclpy signal handlers: they would shut the context down under running callbacks;
    # the caller's StopEvent (uvms run) or KeyboardInterrupt ends run_graph instead.
    rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    graph = Graph(context=context, mode=mode, duration_s=duration_s,
                  output_path=None if output_path is None else Path(output_path))
    try:
        for spec in specs:
            if spec is RECORDER:
                overrides[spec.name].update(_recorder_run_parameters(graph))
            graph.nodes[spec.name] = make_node(spec, overrides[spec.name], config, namespace,
                                                context)
        if scenario is not None and scenario.mission:
            # The scenario's goals go through the controller's ContactTask action, as a
            # user's would; their start times are on /clock, so lockstep stays deterministic.
            graph.nodes['mission'] = MissionNode(
                scenario.mission, namespace=namespace, context=context)
    except BaseException:
        graph.destroy()
        raise
    return graph


def run_graph(
    graph: Graph,
    *,
    progress: RunBar | None = None,
    on_spin: Callable[[Graph], None] | None = None,
    threads: int = 1,
    stop: StopEvent | None = None,
    executor_kind: str | None = None,
) -> RunResult:
    """Spin the graph until its duration (simulated time), a stop signal or Ctrl-C.

    One single-threaded executor spins every node (``make_executor``: the EventsExecutor
    unless ``UVMS_EXECUTOR`` or ``executor_kind`` say otherwise); lockstep is one chain of
    callbacks and deterministic either way. In one Python process the callbacks share the
    interpreter lock, so ``threads`` > 1 (a MultiThreadedExecutor, real time only) is an
    option, not the default.

    Args:
        graph: A graph from ``build_graph``.
        progress: Progress bar to update, if any.
        on_spin: Called after every executor turn (tests and benchmarks).
        threads: Threads of a MultiThreadedExecutor for real time; 1 spins single-threaded.
        stop: Set by SIGINT/SIGTERM (``uvms run``); the run then ends as interrupted.
        executor_kind: ``events`` or ``single``; None: ``UVMS_EXECUTOR`` or ``events``.

    Raises:
        GraphError: A node raised (e.g. the simulation diverged); the recording is closed
            up to that point.
    """
    sim = graph.simulator
    executor: Executor
    if threads > 1 and graph.mode == 'realtime':
        executor = MultiThreadedExecutor(num_threads=threads, context=graph.context)
    else:
        executor = make_executor(executor_kind, graph.context)
    for node in graph.nodes.values():
        executor.add_node(node)
    output_path = graph.output_path
    interrupted = False
    stall = StallWatch(stall_limit_s(sim.get_parameter('startup.timeout_s').value,
                                     sim.get_parameter('lockstep_timeout_s').value))
    start = time.monotonic()
    try:
        while not sim.finished:
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt
            executor.spin_once(timeout_sec=_SPIN_TIMEOUT_S)
            stalled = stall.check(sim.sim_time_ns, time.monotonic())
            if stalled is not None:
                raise RuntimeError(stalled)
            if progress is not None:
                progress.update_to(sim.sim_time_ns * 1e-9)
            if on_spin is not None:
                on_spin(graph)
        wall_s = time.monotonic() - start
        deadline = time.monotonic() + _DRAIN_S
        while time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)
    except (KeyboardInterrupt, ExternalShutdownException):
        interrupted = True
        wall_s = time.monotonic() - start
    except Exception as exc:
        name = type(exc).__name__
        msg = f'the run stopped at t = {sim.sim_time_ns * 1e-9:.3f} s (simulated): {name}: {exc}'
        raise GraphError(msg) from exc
    finally:
        if progress is not None:
            progress.update_to(sim.sim_time_ns * 1e-9)
            progress.close()
        timeouts = sim.timeouts
        sim_time_s = sim.sim_time_ns * 1e-9
        executor.shutdown()
        graph.destroy()
    return RunResult(sim_time_s, wall_s, output_path, timeouts, interrupted)


def run_scenario(
    scenario: Scenario,
    mode: str = 'lockstep',
    *,
    output_path: str | Path | None = None,
    duration_s: float | None = None,
    progress: bool = False,
) -> RunResult:
    """Build and run the graph of a scenario (the ``uvms run`` and ``uvms launch`` path)."""
    graph = build_graph(scenario, mode, output_path=output_path, duration_s=duration_s)
    bar = RunBar(graph.duration_s) if progress and graph.duration_s > 0.0 else None
    return run_graph(graph, progress=bar)


def _recorder_run_parameters(graph: Graph) -> dict[str, ParameterValue]:
    """The recorder's ``run.parameters``: every node's parameters as a parameter file."""
    values = {
        node.get_fully_qualified_name(): {
            name: _plain(parameter.value)
            for name, parameter in node.get_parameters_by_prefix('').items()
        }
        for node in graph.nodes.values()
    }
    return {'run.parameters': parameters_file_text(values)}


def _plain(value: Any) -> Any:
    """A parameter value as plain YAML-able Python (arrays become lists)."""
    if isinstance(value, bool | int | float | str) or value is None:
        return value
    return [_plain(item) for item in value]
