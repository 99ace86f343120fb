"""ROS 2 parameter files over a scenario: ``--params-file``, and a sweep's ``params_files``.

``--params-file`` of ``uvms run``, ``uvms launch`` and ``uvms sweep``, and a sweep file's
``params_files`` list (docs/sweeps.md), all apply here (a ``label`` names the file in errors).
It lives in uvms_sweep, the lowest package that needs it and can hold it: uvms_cli imports
uvms_sweep, not the other way, and uvms_bringup is at its size bound.

A file is a ROS 2 parameter YAML (``node_name: ros__parameters: ...``), as ``ros2 run
--ros-args --params-file`` takes it: a section applies to every node of the run whose fully
qualified name (``/uvms/controller``) its key matches, rcl's way (a key without a leading
``/`` is taken from the root, ``*`` stands for one name and ``**`` for any number of them:
``/**``, ``/**/controller``, ``/uvms/*``). Files apply in the order given, a later one
winning, and they win over the scenario's values; what the run mode sets (``use_sim_time``,
the simulator's ``mode`` and ``duration_s``, the loop triggers) still comes last.

Every name is checked against what the nodes declare before anything starts: a name in a
section for given nodes that one of them does not declare stops the run, naming the file,
the section and the closest names; a wildcard section's name only needs one node of the run
to declare it (the others ignore it, as ROS nodes do).
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import yaml
from rclpy.parameter import Parameter
from uvms_bringup.declared import TYPE_NAMES, as_declared_type, declared_parameters
from uvms_bringup.launch_helpers import (
    DEFAULT_NAMESPACE,
    RECORDER,
    NodeSpec,
    flat_parameters,
)
from uvms_scenarios.scenario import ParameterValue, Scenario, ScenarioError

#: The simulator's parameter that the scenario's ``seed`` sets (``Scenario.node_overrides``).
SEED_PARAMETER = 'sensor.seed'


def node_pattern(key: str) -> re.Pattern[str]:
    """The fully qualified node names a section key of a parameter file matches (rcl's rules).

    >>> bool(node_pattern('/**/controller').fullmatch('/uvms/controller'))
    True
    >>> bool(node_pattern('controller').fullmatch('/uvms/controller'))
    False
    """
    tokens = [token for token in key.strip().strip('/').split('/') if token]
    parts = []
    for token in tokens:
        if token == '**':
            parts.append('(?:/[^/]+)*')
        else:
            parts.append('/' + '[^/]*'.join(re.escape(piece) for piece in token.split('*')))
    return re.compile(''.join(parts) or '/')


def read_params_file(
    path: Path, label: str | None = None
) -> list[tuple[str, dict[str, Any]]]:
    """The sections of a parameter file: (node key, flat dotted parameter names to values).

    Args:
        path: The file.
        label: How errors name the file (``--params-file PATH`` if None).

    Raises:
        ScenarioError: The file is missing, not YAML, or not ``node: ros__parameters: {...}``;
            the message names the file and the section.
    """
    label = label if label is not None else f'--params-file {path}'
    try:
        document = yaml.safe_load(path.read_text(encoding='utf-8'))
    except OSError as exc:
        msg = f'{label}: cannot read it: {exc.strerror or exc}'
        raise ScenarioError(msg) from None
    except yaml.YAMLError as exc:
        msg = f'{label}: not YAML: {exc}'
        raise ScenarioError(msg) from None
    if not isinstance(document, dict) or not document:
        msg = (f'{label}: expected a ROS 2 parameter file, '
               "'node_name: {ros__parameters: {name: value}}'")
        raise ScenarioError(msg)
    sections = []
    for key, section in document.items():
        values = section.get('ros__parameters') if isinstance(section, dict) else None
        if not isinstance(values, dict):
            msg = f'{label}: section {key!r} has no ros__parameters mapping'
            raise ScenarioError(msg)
        sections.append((str(key), flat_parameters(values)))
    return sections


def apply_params_files(
    scenario: Scenario | None,
    files: Sequence[str | Path],
    specs: Sequence[NodeSpec],
    namespace: str = DEFAULT_NAMESPACE,
    declared: Mapping[str, Mapping[str, Parameter.Type]] | None = None,
    labels: Sequence[str] | None = None,
) -> Scenario | None:
    """The scenario with the files' parameters as its overrides (later files winning).

    Args:
        scenario: The run's scenario; None: a scenario of no overrides is made (named after
            nothing: the run is still the parameter files' own).
        files: The parameter files, in command-line order.
        specs: The nodes of the run (the recorder is left out: its parameters are the run's).
        namespace: Namespace of the nodes.
        declared: Node name to declared parameter types (``declared_parameters`` if None).
        labels: How errors name each file (``--params-file PATH`` if None), as ``files``.

    Returns:
        The scenario unchanged without files, else a copy with the overrides merged.

    Raises:
        ScenarioError: A file cannot be read, a name no matched node declares, a value of
            another type, or a section that matches no node of the run.
    """
    if not files:
        return scenario
    specs = [spec for spec in specs if spec is not RECORDER]
    if declared is None:
        declared = declared_parameters(specs, namespace=namespace)
    base = scenario if scenario is not None else Scenario(
        path=Path(files[0]), name='', description='', duration_s=0.0)
    merged = {node: dict(values) for node, values in base.overrides.items()}
    seed = base.seed
    names = {spec.name: f'/{namespace.strip("/")}/{spec.name}'.replace('//', '/')
             for spec in specs}
    if labels is None:
        labels = [f'--params-file {file}' for file in files]
    for file, label in zip(files, labels, strict=True):
        path = Path(file)
        for key, values in read_params_file(path, label):
            pattern = node_pattern(key)
            matched = [name for name, fq_name in names.items() if pattern.fullmatch(fq_name)]
            if not matched:
                msg = (f'{label}: section {key!r} matches no node of the run '
                       f'({", ".join(names.values())})')
                raise ScenarioError(msg)
            wildcard = '*' in key
            for name, value in values.items():
                takers = [node for node in matched if name in declared.get(node, {})]
                if not takers or (not wildcard and len(takers) < len(matched)):
                    missing = next(node for node in matched if name not in declared.get(node, {}))
                    raise ScenarioError(_unknown(label, key, missing, name, declared))
                for node in takers:
                    typed = _typed(label, key, name, value, declared[node][name])
                    if node == 'simulator' and name == SEED_PARAMETER:
                        seed = int(typed)  # type: ignore[arg-type]
                    else:
                        merged.setdefault(node, {})[name] = typed
    return replace(base, overrides=merged, seed=seed)


def _unknown(label: str, key: str, node: str, name: str,
             declared: Mapping[str, Mapping[str, Parameter.Type]]) -> str:
    """The error of a name the node does not declare, with the closest ones it does."""
    close = difflib.get_close_matches(name, list(declared.get(node, {})), n=3)
    hint = f'; did you mean {", ".join(close)}?' if close else ''
    return (f'{label}: section {key!r}: the {node} node has no parameter '
            f'{name!r}{hint}')


def _typed(label: str, key: str, name: str, value: Any,
           declared_type: Parameter.Type) -> ParameterValue:
    """The value in its declared type (integers as floats where floats are declared)."""
    value = as_declared_type(declared_type, value)
    try:
        given = Parameter(name, value=value).type_
    except TypeError:
        given = None
    if given != declared_type:
        expected = TYPE_NAMES.get(declared_type, declared_type.name)
        msg = (f'{label}: section {key!r}: {name}: expected {expected}, got '
               f'{type(value).__name__} {value!r}')
        raise ScenarioError(msg)
    return value  # type: ignore[no-any-return]

