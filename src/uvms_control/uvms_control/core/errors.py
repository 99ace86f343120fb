"""Exception types of uvms_control."""

from __future__ import annotations


class ControlError(Exception):
    """Base class of every error raised by uvms_control."""


class ControlParameterError(ControlError, ValueError):
    """A controller or allocator parameter is outside its valid range.

    The message names the parameter, the offending value and the valid range, so that a node
    can stop at start-up with an actionable error.
    """

    def __init__(self, name: str, value: object, valid: str) -> None:
        message = f'parameter {name!r} = {value!r} is invalid: expected {valid}'
        super().__init__(message)
        self.name = name
        self.value = value
        self.valid = valid


class ControlInputError(ControlError, ValueError):
    """A runtime input (state, measurement or command) is malformed or not finite."""
