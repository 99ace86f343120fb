"""What the nodes declare: scenario overrides and sweep axes checked against it before a run.

The nodes are built once in a throwaway context with their parameter files only, to read
each declared parameter's name and type; a scenario key no node declares, or a value of
another type, then stops the run before it starts, with the file, the key and the type.

The throwaway context is kept away from every running graph: it joins ROS domain
``CHECK_DOMAIN_ID``, which no graph of ours uses, and holds one participant for the whole
check (a small keeper node keeps it alive while the checked nodes come and go). Fast DDS
2.14 can livelock destroying a participant while its discovery callbacks run
(``DomainParticipant::set_listener`` spinning; eProsima/Fast-DDS#6513): a participant
created and destroyed per checked node, in the domain of a running test's graph, hung a
whole test run in ``destroy_node`` that way.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import rclpy
import rclpy.logging
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions
from uvms_scenarios.scenario import ParameterValue, Scenario, ScenarioError

from uvms_bringup.launch_helpers import (
    DEFAULT_NAMESPACE,
    RECORDER,
    NodeSpec,
    config_dir,
    graph_nodes,
)
from uvms_bringup.node_factory import GraphError, make_node

#: ROS domain of the throwaway context: the last of the default port mapping (0-232), which
#: no graph of ours joins (sweeps take 215-231 and 101-1, tests 1-200, bench_scenarios
#: 200-214).
CHECK_DOMAIN_ID = 232

#: Parameter types as a scenario or parameter file writes them (in error messages).
TYPE_NAMES = {
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
    specs = specs if specs is not None else graph_nodes(record=True, estimator=True)
    config = config if config is not None else config_dir()
    to_check = [spec for spec in specs if spec.name in scenario.overrides and spec is not RECORDER]
    if not to_check:
        return scenario
    checked = {node: dict(values) for node, values in scenario.overrides.items()}
    with _throwaway_context() as context:
        for spec in to_check:
            # The throwaway node's start-up lines would read as the run's own (e.g. "lockstep
            # trigger" before a real-time launch): only its warnings and errors are shown.
            logger = f'{namespace.strip("/").replace("/", ".")}.{spec.name}'.lstrip('.')
            level = rclpy.logging.get_logger_level(logger)
            rclpy.logging.set_logger_level(logger, rclpy.logging.LoggingSeverity.WARN)
            try:
                node = _throwaway_node(scenario, spec, config, namespace, context)
                try:
                    for name, value in scenario.overrides[spec.name].items():
                        checked[spec.name][name] = _check_override(
                            scenario, spec.name, node, name, value)
                finally:
                    node.destroy_node()
            finally:
                rclpy.logging.set_logger_level(logger, level)
    return replace(scenario, overrides=checked)


@contextmanager
def _quiet_start(spec: NodeSpec, namespace: str) -> Iterator[None]:
    """Only the warnings and errors of a throwaway node: its start-up lines are not the run's."""
    logger = f'{namespace.strip("/").replace("/", ".")}.{spec.name}'.lstrip('.')
    level = rclpy.logging.get_logger_level(logger)
    rclpy.logging.set_logger_level(logger, rclpy.logging.LoggingSeverity.WARN)
    try:
        yield
    finally:
        rclpy.logging.set_logger_level(logger, level)


@contextmanager
def _throwaway_context() -> Iterator[Context]:
    """A context in ``CHECK_DOMAIN_ID`` whose one participant lives until the block ends."""
    context = Context()
    rclpy.init(args=[], context=context, domain_id=CHECK_DOMAIN_ID,
               signal_handler_options=SignalHandlerOptions.NO)
    keeper = None
    try:
        keeper = Node('uvms_declared_check', context=context, enable_rosout=False,
                      start_parameter_services=False)
        yield context
    finally:
        if keeper is not None:
            keeper.destroy_node()
        rclpy.try_shutdown(context=context)


def _throwaway_node(scenario: Scenario, spec: NodeSpec, config: Path, namespace: str,
                    context: Context) -> Node:
    """The node of ``spec`` built for the check: with the scenario's robot and overrides.

    The overrides go in because a robot may need them to start at all (an initial pose its
    arm reaches); if the node refuses them (an override of the wrong type), it is built
    without them, so that ``_check_override`` names the key; if it cannot start without
    them either, the first error is raised.
    """
    robot: dict[str, ParameterValue] = (
        {'robot_name': scenario.robot} if scenario.robot is not None and spec.takes_robot
        else {})
    try:
        return make_node(spec, {**scenario.overrides[spec.name], **robot}, config, namespace,
                         context)
    except GraphError as first:
        try:
            return make_node(spec, robot, config, namespace, context)
        except GraphError:
            raise first from None


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
        expected = TYPE_NAMES.get(declared_type, declared_type.name)
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
    specs = specs if specs is not None else graph_nodes(record=False, estimator=True)
    config = config if config is not None else config_dir()
    declared: dict[str, dict[str, Parameter.Type]] = {}
    with _throwaway_context() as context:
        for spec in specs:
            with _quiet_start(spec, namespace):
                node = make_node(spec, {}, config, namespace, context)
            try:
                declared[spec.name] = {
                    name: parameter.type_
                    for name, parameter in node.get_parameters_by_prefix('').items()
                }
            finally:
                node.destroy_node()
    return declared
