"""Build one node of the graph in process, from its parameter files and overrides."""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from pathlib import Path

from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from uvms_scenarios.scenario import ParameterValue

from uvms_bringup.launch_helpers import NodeSpec


class GraphError(RuntimeError):
    """The graph cannot be built or stopped with an error; the message names the node."""


def make_node(
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
    # A node whose __init__ fails half way (an invalid parameter) has destroyed its entities
    # by then (uvms_common.node_construction): left alive, its rcl node would keep its
    # /rosout publisher, and the next node of that name (the retry of uvms_bringup.declared,
    # the real run) would log "Publisher already registered for node name".
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
