"""Errors of uvms_pilot."""

from __future__ import annotations


class PilotError(ValueError):
    """An option, robot or input that the pilot tools refuse; one line says why."""


class MappingError(PilotError):
    """A gamepad mapping file that cannot be used; the message names the file and the field."""
