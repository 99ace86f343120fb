"""Declare the allocator node's parameter specs (``uvms_common.parameter_declaration``)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from rclpy.exceptions import ParameterException
from rclpy.node import Node
from uvms_common.parameter_declaration import Spec, declare_specs, valid_text

from uvms_description.robots import RobotParameter
from uvms_thrusters.errors import ThrusterParameterError


def _thruster_error(spec: Spec, exc: ParameterException) -> ThrusterParameterError:
    return ThrusterParameterError(spec.name, str(exc), valid_text(spec))


def declare_parameters(
    node: Node, specs: Iterable[Spec], robot: Mapping[str, RobotParameter] | None = None
) -> dict[str, Any]:
    """Declare each spec with its description and range; return name -> value.

    Values come from the parameter files and overrides given to the node, else from the
    robot's files (``robot``), else the spec's default; lists come back as Python lists.

    Raises:
        ThrusterParameterError: if a value has the wrong type or is outside a declared range.
    """
    return declare_specs(node, specs, robot, _thruster_error)
