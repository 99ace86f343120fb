"""Fields of the parameter groups: description, unit and range as metadata, and validation."""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Mapping
from dataclasses import field
from typing import Any

from uvms_model.errors import ParameterError


def _param(
    default: Any,
    description: str,
    min_value: float | None = None,
    max_value: float | None = None,
    *,
    length: int | None = None,
    multiple_of: int | None = None,
) -> Any:
    """Build a dataclass field carrying the description, range and list length of a parameter.

    Args:
        default: Default value (float, int, bool, str, or a tuple of floats or strings).
        description: What the parameter is, with its unit.
        min_value: Inclusive lower bound (of every element for lists); None for no bound.
        max_value: Inclusive upper bound (of every element for lists); None for no bound.
        length: Required list length; None for scalars or lists of free length.
        multiple_of: For lists of free length, the length must be a positive multiple of it.

    Returns:
        A ``dataclasses.field`` with the metadata ``_validate_field`` reads.
    """
    return field(
        default=default,
        metadata={
            'description': description,
            'min': min_value,
            'max': max_value,
            'length': length,
            'multiple_of': multiple_of,
        },
    )


def _kind(default: Any) -> str:
    """ROS parameter kind of a default value: bool, int, float, str, float_list or str_list."""
    if isinstance(default, bool):
        return 'bool'
    if isinstance(default, int):
        return 'int'
    if isinstance(default, float):
        return 'float'
    if isinstance(default, str):
        return 'str'
    if isinstance(default, tuple) and default and isinstance(default[0], str):
        return 'str_list'
    return 'float_list'


def _is_real(value: object) -> bool:
    """True for int and float values (and numpy scalars), False for bool and anything else."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _range_text(lo: float | None, hi: float | None) -> str:
    """Human-readable inclusive range ``[lo, hi]``."""
    lo_text = '-inf' if lo is None else repr(lo)
    hi_text = 'inf' if hi is None else repr(hi)
    return f'[{lo_text}, {hi_text}]'


def _coerce(name: str, kind: str, value: object) -> Any:
    """Convert a ROS-typed value to the dataclass field type, or raise naming the parameter."""
    if kind == 'bool':
        if not isinstance(value, bool):
            raise ParameterError(f'{name} = {value!r} must be a bool')
        return value
    if kind == 'int':
        if isinstance(value, bool) or not isinstance(value, int):
            raise ParameterError(f'{name} = {value!r} must be an int')
        return int(value)
    if kind == 'float':
        if not _is_real(value):
            raise ParameterError(f'{name} = {value!r} must be a number')
        return float(value)  # type: ignore[arg-type]
    if kind == 'str':
        if not isinstance(value, str):
            raise ParameterError(f'{name} = {value!r} must be a string')
        return value
    if isinstance(value, (str, bytes)) or not hasattr(value, '__iter__'):
        raise ParameterError(f'{name} = {value!r} must be a list')
    items = list(value)  # type: ignore[call-overload, unused-ignore]
    if kind == 'str_list':
        if not all(isinstance(item, str) for item in items):
            raise ParameterError(f'{name} = {value!r} must be a list of strings')
        return tuple(items)
    if not all(_is_real(item) for item in items):
        raise ParameterError(f'{name} = {value!r} must be a list of numbers')
    return tuple(float(item) for item in items)


def _validate_field(name: str, value: Any, metadata: Mapping[str, Any]) -> None:
    """Check finiteness, list length and range of one field value; raise ParameterError."""
    lo, hi = metadata['min'], metadata['max']
    length, multiple_of = metadata['length'], metadata['multiple_of']
    if isinstance(value, tuple):
        if length is not None and len(value) != length:
            raise ParameterError(
                f'{name} has {len(value)} elements, expected {length}: {list(value)!r}'
            )
        if multiple_of is not None and (not value or len(value) % multiple_of != 0):
            raise ParameterError(
                f'{name} has {len(value)} elements, expected a positive multiple of '
                f'{multiple_of}: {list(value)!r}'
            )
        numbers = [item for item in value if not isinstance(item, str)]
    elif isinstance(value, (bool, str)):
        numbers = []
    else:
        numbers = [value]
    for number in numbers:
        if not math.isfinite(number):
            raise ParameterError(f'{name} = {value!r} must be finite')
        if (lo is not None and number < lo) or (hi is not None and number > hi):
            raise ParameterError(f'{name} = {value!r} is out of range {_range_text(lo, hi)}')


class _Group:
    """Mixin: validate every field of a parameter group against its metadata after init."""

    _group: str = ''

    def __post_init__(self) -> None:
        for item in dataclasses.fields(self):  # type: ignore[arg-type]
            _validate_field(f'{self._group}.{item.name}', getattr(self, item.name), item.metadata)
        self._check()

    def _check(self) -> None:
        """Cross-field checks of the group; overridden where needed."""
