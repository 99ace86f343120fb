"""Exception types of uvms_thrusters."""

from __future__ import annotations

from uvms_common.parameter_spec import ParameterValueError


class ThrusterError(Exception):
    """Base class of every error raised by uvms_thrusters."""


class ThrusterParameterError(ThrusterError, ParameterValueError):
    """An allocator, thruster or fault parameter is outside its valid range.

    The message names the parameter, the offending value and the valid range (the format of
    ``uvms_control``'s ControlParameterError), so that a node can stop at start-up with an
    actionable error.
    """


class ThrusterInputError(ThrusterError, ValueError):
    """A runtime input (a generalized force command) is malformed or not finite."""
