"""Declare parameter specs on a node, with descriptors that carry units, ranges and choices.

Every node of ours declares its parameters from specs (name, default, description with the
unit, valid range): the simulator's, the model's, the controller's and the allocator's. This
module turns a spec into the ``ParameterDescriptor`` that ``ros2 param describe`` shows
(read-only unless the spec says ``read_only = False``; an integer or floating-point range for
a scalar with both bounds; "one of: ..." for a string with choices) and declares it, taking
the default from the robot's folder when it has one. Each node names its own error.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import Any, Protocol

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import ParameterException
from rclpy.node import Node

from uvms_common.robot_parameters import robot_default
from uvms_description.robots import RobotParameter

__all__ = ['Spec', 'declare_specs', 'parameter_descriptor', 'valid_text']


class Spec(Protocol):
    """What a parameter spec provides (may add ``read_only`` and ``choices``)."""

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


def _bounds_text(lo: float | None, hi: float | None) -> str:
    return f'[{"-inf" if lo is None else lo}, {"inf" if hi is None else hi}]'


def parameter_descriptor(spec: Spec) -> ParameterDescriptor:
    """The descriptor of ``spec``: description, read-only flag, range or choices."""
    descriptor = ParameterDescriptor(description=spec.description,
                                     read_only=getattr(spec, 'read_only', True))
    lo, hi = spec.min_value, spec.max_value
    default = spec.default
    choices = getattr(spec, 'choices', ())
    scalar = not isinstance(default, (bool, str, list, tuple))
    if choices:
        descriptor.additional_constraints = 'one of: ' + ', '.join(choices)
    elif scalar and lo is not None and hi is not None:
        if isinstance(default, int):
            descriptor.integer_range = [IntegerRange(from_value=int(lo), to_value=int(hi), step=1)]
        else:
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=float(lo), to_value=float(hi), step=0.0)
            ]
    elif lo is not None or hi is not None:
        descriptor.additional_constraints = f'each value in {_bounds_text(lo, hi)}'
    return descriptor


def valid_text(spec: Spec) -> str:
    """The valid type and range of a spec, for error messages."""
    lo, hi = spec.min_value, spec.max_value
    kind = type(spec.default).__name__
    if isinstance(spec.default, (list, tuple)):
        kind = 'list of floats'
    bounds = f' in {_bounds_text(lo, hi)}' if lo is not None or hi is not None else ''
    return f'a {kind}{bounds}: {spec.description}'


def declare_specs(
    node: Node, specs: Iterable[Spec], robot: Mapping[str, RobotParameter] | None,
    error: Callable[[Spec, ParameterException], Exception],
) -> dict[str, Any]:
    """Declare each spec with its descriptor; return name -> value (lists as Python lists).

    Values come from the parameter files and overrides given to the node, else from the
    robot's files (``robot``, see ``uvms_common.robot_parameters``), else the spec's default.

    Raises:
        Exception: ``error(spec, exc)`` for a value of the wrong type or outside a declared
            range (the node's own error class, naming the parameter).
    """
    values: dict[str, Any] = {}
    for spec in specs:
        default = list(spec.default) if isinstance(spec.default, tuple) else spec.default
        default = robot_default(robot or {}, spec.name, default)
        try:
            value = node.declare_parameter(spec.name, default, parameter_descriptor(spec)).value
        except ParameterException as exc:
            raise error(spec, exc) from exc
        values[spec.name] = (
            list(value) if not isinstance(value, (str, bool, int, float)) else value
        )
    return values
