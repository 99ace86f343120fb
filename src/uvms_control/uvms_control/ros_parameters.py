"""Declare parameter specs on a node, with descriptors that carry units and ranges."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any, Protocol

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from uvms_common.robot_parameters import robot_default

from uvms_control.core.errors import ControlParameterError
from uvms_description.robots import RobotParameter


class Spec(Protocol):
    """What a parameter spec provides (uvms_model's and uvms_control's specs both do)."""

    @property
    def name(self) -> str: ...  # noqa: D102

    @property
    def default(self) -> Any: ...  # noqa: D102

    @property
    def description(self) -> str: ...  # noqa: D102

    @property
    def min_value(self) -> float | None: ...  # noqa: D102

    @property
    def max_value(self) -> float | None: ...  # noqa: D102


def _descriptor(spec: Spec) -> ParameterDescriptor:
    descriptor = ParameterDescriptor(description=spec.description,
                                     read_only=getattr(spec, 'read_only', True))
    lo, hi = spec.min_value, spec.max_value
    default = spec.default
    scalar = not isinstance(default, (bool, str, list, tuple))
    if scalar and lo is not None and hi is not None:
        if isinstance(default, int):
            descriptor.integer_range = [IntegerRange(from_value=int(lo), to_value=int(hi), step=1)]
        else:
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=float(lo), to_value=float(hi), step=0.0)
            ]
    elif lo is not None or hi is not None:
        descriptor.additional_constraints = (
            f'each value in [{"-inf" if lo is None else lo}, {"inf" if hi is None else hi}]'
        )
    return descriptor


def _valid_text(spec: Spec) -> str:
    """The valid type and range of a spec, for error messages."""
    lo, hi = spec.min_value, spec.max_value
    kind = type(spec.default).__name__
    if isinstance(spec.default, (list, tuple)):
        kind = 'list of floats'
    bounds = ''
    if lo is not None or hi is not None:
        bounds = f' in [{"-inf" if lo is None else lo}, {"inf" if hi is None else hi}]'
    return f'a {kind}{bounds}: {spec.description}'


def declare_parameters(
    node: Node, specs: Iterable[Spec], robot: Mapping[str, RobotParameter] | None = None
) -> dict[str, Any]:
    """Declare each spec read-only with its description and range; return name -> value.

    Values come from the parameter files and overrides given to the node, else from the
    robot's files (``robot``, see ``uvms_common.robot_parameters``), else the spec's default;
    lists come back as Python lists.

    Raises:
        ControlParameterError: if a value has the wrong type or is outside a declared range.
    """
    values: dict[str, Any] = {}
    for spec in specs:
        default = list(spec.default) if isinstance(spec.default, tuple) else spec.default
        default = robot_default(robot or {}, spec.name, default)
        try:
            value = node.declare_parameter(spec.name, default, _descriptor(spec)).value
        except ParameterException as error:
            raise ControlParameterError(spec.name, str(error), _valid_text(spec)) from error
        values[spec.name] = (
            list(value) if not isinstance(value, (str, bool, int, float)) else value
        )
    return values
