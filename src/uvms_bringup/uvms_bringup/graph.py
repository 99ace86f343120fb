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

import difflib
import importlib
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import rclpy
import rclpy.logging
from rclpy.context import Context
from rclpy.executors import Executor, ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions
from uvms_common.node_main import StopEvent, make_executor
from uvms_tasks.mission_node import MissionNode

from uvms_bringup.bars import RunBar
from uvms_bringup.launch_helpers import (
    DEFAULT_NAMESPACE,
    RECORDER,
    SIMULATOR,
    NodeSpec,
    config_dir,
    graph_nodes,
    node_parameters,
    parameters_file_text,
)
from uvms_bringup.scenario import ParameterValue, Scenario, ScenarioError

#: Longest wall-clock wait for any callback before the lockstep loop checks on the graph (s).
_SPIN_TIMEOUT_S = 0.5
#: Wall-clock time given to the last messages to reach the recorder after the run (s).
_DRAIN_S = 0.1


class GraphError(RuntimeError):
    """The graph cannot be built or stopped with an error; the message names the node."""


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

    Raises:
        ScenarioError: A scenario override names no parameter of its node, or has the
            wrong type; the message names the file, key and expected type.
        GraphError: A node cannot be built (invalid parameter file value, ...).
    """
    config = config if config is not None else config_dir()
    if duration_s is None:
        duration_s = scenario.duration_s if scenario is not None else 0.0
    specs = graph_nodes(record=output_path is not None, foxglove=foxglove is not None)
    if scenario is not None:
        scenario = check_scenario_overrides(scenario, specs, config, namespace)
    overrides = {
        spec.name: {
            **node_parameters(spec, scenario, mode, duration_s,
                              None if output_path is None else str(output_path), foxglove),
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
            graph.nodes[spec.name] = _make_node(spec, overrides[spec.name], config, namespace,
                                                context)
        if scenario is not None and scenario.mission:
            # The scenario's goals go through the controller's ContactTask action, as a
            # user's would; their start times are on /clock, so lockstep stays deterministic.
            graph.nodes['mission'] = MissionNode(
                scenario.mission, namespace=namespace, context=context,
                parameter_overrides=[Parameter('use_sim_time', value=True)])
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
    start = time.monotonic()
    try:
        while not sim.finished:
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt
            executor.spin_once(timeout_sec=_SPIN_TIMEOUT_S)
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


def _make_node(
    spec: NodeSpec,
    overrides: Mapping[str, ParameterValue],
    config: Path,
    namespace: str,
    context: Context,
) -> Node:
    """Import a node class and build it with its parameter files and overrides."""
    try:
        module = importlib.import_module(spec.module)
        node_class = getattr(module, spec.class_name)
    except (ImportError, AttributeError) as exc:
        msg = f'node {spec.name!r}: cannot import {spec.module}.{spec.class_name}: {exc}'
        raise GraphError(msg) from exc
    cli_args = ['--ros-args']
    for file in spec.parameter_files:
        path = config / file
        if not path.is_file():
            msg = f'node {spec.name!r}: parameter file {path} does not exist'
            raise GraphError(msg)
        cli_args += ['--params-file', str(path)]
    try:
        node: Node = node_class(
            namespace=namespace,
            context=context,
            cli_args=cli_args if len(cli_args) > 1 else None,
            parameter_overrides=[Parameter(name, value=value)
                                 for name, value in overrides.items()],
        )
    except Exception as exc:
        msg = f'node {spec.name!r} could not start: {type(exc).__name__}: {exc}'
        raise GraphError(msg) from exc
    return node


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


_TYPE_NAMES = {
    Parameter.Type.BOOL: 'bool',
    Parameter.Type.INTEGER: 'int',
    Parameter.Type.DOUBLE: 'float (write a decimal point, e.g. 1.0e+4)',
    Parameter.Type.STRING: 'str',
    Parameter.Type.BOOL_ARRAY: 'list of bool',
    Parameter.Type.INTEGER_ARRAY: 'list of int',
    Parameter.Type.DOUBLE_ARRAY: 'list of float',
    Parameter.Type.STRING_ARRAY: 'list of str',
}


def check_scenario_overrides(
    scenario: Scenario,
    specs: Sequence[NodeSpec] | None = None,
    config: Path | None = None,
    namespace: str = DEFAULT_NAMESPACE,
) -> Scenario:
    """Check every scenario override against what its node declares, before the real run.

    The nodes are built once with their parameter files only, in a throwaway context, to
    read the declared names and types; the recorder is left out (it would open its file).
    Integers on a float parameter are taken as floats, as sweep files take them.

    Args:
        scenario: The scenario.
        specs: Nodes of the run (all, recorder included, if None).
        config: Directory of the parameter files (``config_dir()`` if None).
        namespace: Namespace of the nodes.

    Returns:
        The scenario with its overrides in the declared types.

    Raises:
        ScenarioError: An override names no parameter of its node or has another type;
            the message names the file, the key and the expected type.
        GraphError: A node cannot be built from its parameter files.
    """
    specs = specs if specs is not None else graph_nodes(record=True)
    config = config if config is not None else config_dir()
    to_check = [spec for spec in specs if spec.name in scenario.overrides and spec is not RECORDER]
    if not to_check:
        return scenario
    checked = {node: dict(values) for node, values in scenario.overrides.items()}
    context = Context()
    rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    try:
        for spec in to_check:
            # The throwaway node's start-up lines would read as the run's own (e.g. "lockstep
            # trigger" before a real-time launch): only its warnings and errors are shown.
            logger = f'{namespace.strip("/").replace("/", ".")}.{spec.name}'.lstrip('.')
            level = rclpy.logging.get_logger_level(logger)
            rclpy.logging.set_logger_level(logger, rclpy.logging.LoggingSeverity.WARN)
            try:
                node = _make_node(spec, {}, config, namespace, context)
                try:
                    for name, value in scenario.overrides[spec.name].items():
                        checked[spec.name][name] = _check_override(
                            scenario, spec.name, node, name, value)
                finally:
                    node.destroy_node()
            finally:
                rclpy.logging.set_logger_level(logger, level)
    finally:
        rclpy.try_shutdown(context=context)
    return replace(scenario, overrides=checked)


def _check_override(
    scenario: Scenario, node_name: str, node: Node, name: str, value: ParameterValue
) -> ParameterValue:
    """One override, declared by the node, in the declared type (integers become floats)."""
    key = f'{node_name}.{name}'
    if not node.has_parameter(name):
        declared = list(node.get_parameters_by_prefix('').keys())
        close = difflib.get_close_matches(name, declared, n=3)
        hint = f'; did you mean {", ".join(close)}?' if close else ''
        msg = f'{scenario.path}: key {key!r}: the {node_name} node has no parameter {name!r}{hint}'
        raise ScenarioError(msg)
    declared_type = node.get_parameter(name).type_
    value = as_declared_type(declared_type, value)
    given_type = Parameter(name, value=value).type_
    if declared_type != given_type:
        expected = _TYPE_NAMES.get(declared_type, declared_type.name)
        msg = (f'{scenario.path}: key {key!r}: expected {expected}, got '
               f'{type(value).__name__} {value!r}')
        raise ScenarioError(msg)
    return value


def as_declared_type(declared: Parameter.Type, value: ParameterValue) -> ParameterValue:
    """An integer (or list of numbers) as floats where ``declared`` is a float type.

    YAML writes ``3`` for three, and ROS would refuse it for a double parameter; scenario and
    sweep files both take it as ``3.0``. Other values are returned as they are.
    """
    if declared == Parameter.Type.DOUBLE and isinstance(value, int) and not isinstance(
        value, bool
    ):
        return float(value)
    if declared == Parameter.Type.DOUBLE_ARRAY and isinstance(value, list) and all(
        isinstance(item, int | float) and not isinstance(item, bool) for item in value
    ):
        return [float(item) for item in value]
    return value


def declared_parameters(
    specs: Sequence[NodeSpec] | None = None,
    config: Path | None = None,
    namespace: str = DEFAULT_NAMESPACE,
) -> dict[str, dict[str, Parameter.Type]]:
    """Every parameter each node declares after its parameter files, with its type.

    The nodes are built once in a throwaway context (as ``check_scenario_overrides`` does);
    sweeps use this to check their axes before any run.

    Args:
        specs: Nodes to read (simulator, controller and thruster allocator if None).
        config: Directory of the parameter files (``config_dir()`` if None).
        namespace: Namespace of the nodes.

    Returns:
        Node name to parameter name to declared type.

    Raises:
        GraphError: A node cannot be built from its parameter files.
    """
    specs = specs if specs is not None else graph_nodes(record=False)
    config = config if config is not None else config_dir()
    context = Context()
    rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    declared: dict[str, dict[str, Parameter.Type]] = {}
    try:
        for spec in specs:
            node = _make_node(spec, {}, config, namespace, context)
            try:
                declared[spec.name] = {
                    name: parameter.type_
                    for name, parameter in node.get_parameters_by_prefix('').items()
                }
            finally:
                node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return declared
