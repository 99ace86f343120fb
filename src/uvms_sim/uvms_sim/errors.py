"""Exceptions of the simulator: each message names the bad value and its cause."""

from __future__ import annotations


class SimulationError(RuntimeError):
    """The simulation cannot go on; the message says why."""


class DivergenceError(SimulationError):
    """The plant state became non-finite or left its physical bounds; it is not integrated."""


class CommandError(ValueError):
    """An actuator command is malformed (wrong size, NaN or Inf, unknown joint names)."""


class SimParameterError(ValueError):
    """A simulator parameter is invalid; the message names the parameter, value and range."""


class StartupError(SimulationError):
    """The control loop did not close within ``startup.timeout_s``; names the silent node."""
