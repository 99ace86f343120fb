"""Errors of uvms_identify."""

from __future__ import annotations


class IdentifyError(ValueError):
    """A recording, robot or option that the identification refuses; one line says why."""
