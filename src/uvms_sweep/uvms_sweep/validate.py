"""Check a sweep against the graph before it runs: base scenario, axis names and value types.

The sweep file's ``params_files`` and then ``uvms sweep --params-file``'s files apply over the
base scenario as ``uvms run --params-file`` applies them (``params_files``: every name checked
against what the nodes declare, the file and section named when wrong); the axes come over them.

Each axis must name a parameter its node declares (after robot.yaml and controller.yaml) and
give values of the declared type; integers on a float parameter are taken as floats. Ranges
are not checked here: a value outside a parameter's declared range fails its point at
start-up, which the sweep records as failed with the node's message.

``duration_warning`` warns (without stopping the sweep) when the duration ends before the
base scenario's force is reached, estimated before the run (``scenario.contact_estimate``).
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from rclpy.parameter import Parameter
from uvms_bringup.declared import as_declared_type, declared_parameters
from uvms_bringup.launch_helpers import graph_nodes, uses_estimator
from uvms_scenarios.scenario import (
    ParameterValue,
    Scenario,
    load_scenario,
    short_duration_warning,
)

from uvms_sweep.params_files import apply_params_files
from uvms_sweep.sweep_file import Axis, Sweep, SweepError

_TYPE_NAMES = {
    Parameter.Type.BOOL: 'bool',
    Parameter.Type.INTEGER: 'int',
    Parameter.Type.DOUBLE: 'float',
    Parameter.Type.STRING: 'str',
    Parameter.Type.BOOL_ARRAY: 'list of bool',
    Parameter.Type.INTEGER_ARRAY: 'list of int',
    Parameter.Type.DOUBLE_ARRAY: 'list of float',
    Parameter.Type.STRING_ARRAY: 'list of str',
}


def check_sweep(
    sweep: Sweep, params_files: Sequence[str | Path] = ()
) -> tuple[Sweep, Scenario]:
    """The sweep with its axis values in the declared types, and its base scenario.

    Args:
        sweep: The sweep as read.
        params_files: ``uvms sweep --params-file``'s files, applied after the sweep file's.

    Returns:
        The sweep, and the base scenario with the parameter files' values over its own (every
        point's request starts from these overrides, ``engine.point_request``).

    Raises:
        ScenarioError: The base scenario file is invalid (the message names its key), or a
            parameter file is: unreadable, a section matching no node, a name no node
            declares, a value of another type (the message names the file or the sweep
            file's key ``params_files[i]``, and the section).
        SweepError: An axis names no parameter of its node, or a value has another type;
            the message names the sweep file and the key ``axes.NODE.PARAMETER``.
        GraphError: A node cannot be built from its parameter files.
    """
    scenario = load_scenario(sweep.scenario_path)
    declared = declared_parameters()
    for node, overrides in scenario.overrides.items():
        for name, value in overrides.items():
            if node in declared:
                where = f'{scenario.path}: key {f"{node}.{name}"!r}'
                _coerce(declared[node], node, name, value, where)
    files = [*sweep.params_files, *params_files]
    labels = [*(f"{sweep.path}: key 'params_files[{i}]' ({file})"
                for i, file in enumerate(sweep.params_files)),
              *(f'--params-file {file}' for file in params_files)]
    specs = graph_nodes(record=False, estimator=uses_estimator(scenario))
    scenario = apply_params_files(scenario, files, specs, declared=declared,
                                  labels=labels) or scenario
    axes = tuple(_checked_axis(sweep, axis, declared) for axis in sweep.axes)
    return replace(sweep, axes=axes), scenario


def duration_warning(sweep: Sweep, scenario: Scenario) -> str | None:
    """A warning if each point's run ends before F_d is reached, else None.

    The first contact is estimated on the base scenario (``scenario.contact_estimate``: X_d
    reaching the wall); axes that move the wall or the start are not taken into account.
    Such points are marked ``ended before settling`` in the table (``table.ended_early``).
    """
    duration_s = scenario.duration_s if sweep.duration_s is None else sweep.duration_s
    why = short_duration_warning(scenario, duration_s)
    if why is None:
        return None
    return (f'{sweep.path}: duration_s: {why}; points that end in contact before the force '
            'settles are marked "ended before settling"')


def _checked_axis(
    sweep: Sweep, axis: Axis, declared: dict[str, dict[str, Parameter.Type]]
) -> Axis:
    """One axis with values converted to the declared type."""
    where = f'{sweep.path}: key {"axes." + axis.name!r}'
    values = tuple(
        _coerce(declared[axis.node], axis.node, axis.parameter, value, where)
        for value in axis.values
    )
    return replace(axis, values=values)


def _coerce(
    declared: dict[str, Parameter.Type],
    node: str,
    name: str,
    value: ParameterValue,
    where: str,
) -> ParameterValue:
    """A value in the declared type of ``node``'s parameter ``name``, or SweepError.

    Integers become floats for a float parameter, in sweep and scenario files alike
    (``declared.as_declared_type``).
    """
    if name not in declared:
        close = difflib.get_close_matches(name, list(declared), n=3)
        hint = f'; did you mean {", ".join(close)}?' if close else ''
        raise SweepError(f'{where}: the {node} node has no parameter {name!r}{hint}')
    expected = declared[name]
    value = as_declared_type(expected, value)
    if Parameter(name, value=value).type_ != expected:
        type_name = _TYPE_NAMES.get(expected, expected.name)
        raise SweepError(f'{where}: expected {type_name}, got {type(value).__name__} {value!r}')
    return value
