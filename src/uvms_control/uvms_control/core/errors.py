"""Exception types of uvms_control."""

from __future__ import annotations

from uvms_common.parameter_spec import ParameterValueError


class ControlError(Exception):
    """Base class of every error raised by uvms_control."""


class ControlParameterError(ControlError, ParameterValueError):
    """A controller parameter is outside its valid range.

    The message names the parameter, the offending value and the valid range, so that a node
    can stop at start-up with an actionable error.
    """


class ControlInputError(ControlError, ValueError):
    """A runtime input (state, measurement or command) is malformed or not finite."""
