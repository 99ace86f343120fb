"""Parameter specs of the control nodes and their validation against them (pure: no rclpy).

A `ParameterSpec` is one ROS parameter: name, default, description with its unit, range and
read-only flag. The controller (``uvms_control.core.parameter_specs``) and the thruster
allocator (``uvms_thrusters.parameter_specs``) list theirs; `merged_values` checks values
against a list and raises the package's own `ParameterValueError` subclass, whose message
names the parameter, the offending value and the valid range.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import NamedTuple

ParameterValue = float | int | bool | str | list[float]


class ParameterSpec(NamedTuple):
    """One ROS parameter: name, default, description with unit, range, read-only flag."""

    name: str
    default: ParameterValue
    description: str
    min_value: float | None = None
    max_value: float | None = None
    read_only: bool = True


#: The trigger modes of the allocator (the controller adds 'odometry').
TRIGGER_MODES = ('lockstep', 'timer')


class ParameterValueError(ValueError):
    """A parameter is outside its valid range.

    The message names the parameter, the offending value and the valid range, so that a node
    can stop at start-up with an actionable error.
    """

    def __init__(self, name: str, value: object, valid: str) -> None:
        message = f'parameter {name!r} = {value!r} is invalid: expected {valid}'
        super().__init__(message)
        self.name = name
        self.value = value
        self.valid = valid


#: Builds the error of a bad value from (name, value, what is valid).
ErrorType = Callable[[str, object, str], ParameterValueError]


def merged_values(specs: Sequence[ParameterSpec], values: Mapping[str, object],
                  error: ErrorType = ParameterValueError) -> dict[str, object]:
    """Defaults overridden by ``values``; unknown names and out-of-range numbers raise.

    Raises:
        ParameterValueError: ``error(name, value, valid)``, for an unknown name, a wrong type
            or a value out of range.
    """
    known = {spec.name: spec for spec in specs}
    merged: dict[str, object] = {spec.name: spec.default for spec in specs}
    for name, value in values.items():
        if name not in known:
            raise error(
                name, value, f'one of the known parameters {sorted(known)}'
            )
        merged[name] = value
    for name, spec in known.items():
        value = merged[name]
        kind = type(spec.default)
        if kind is bool:
            if not isinstance(value, bool):
                raise error(name, value, 'a bool')
        elif kind is str:
            if not isinstance(value, str):
                raise error(name, value, 'a string')
        elif kind is float:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise error(name, value, 'a number')
        elif kind is list:
            if isinstance(value, (str, bytes)) or not hasattr(value, '__iter__'):
                raise error(name, value, 'a list of numbers')
            items = list(value)
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in items):
                raise error(name, value, 'a list of numbers')
            merged[name] = [float(v) for v in items]
        numbers: list[float] = []
        current = merged[name]
        if isinstance(current, list):
            numbers = [float(v) for v in current]
        elif isinstance(current, (int, float)) and not isinstance(current, bool):
            numbers = [float(current)]
        for number in numbers:
            if not math.isfinite(number):
                raise error(name, current, 'finite values')
            lo, hi = spec.min_value, spec.max_value
            if (lo is not None and number < lo) or (hi is not None and number > hi):
                raise error(
                    name,
                    current,
                    f'values in [{"-inf" if lo is None else lo}, {"inf" if hi is None else hi}]',
                )
    return merged
