"""Errors of uvms_tune."""

from __future__ import annotations


class TuneError(ValueError):
    """A tune file cannot be read or does not follow the schema; the message names the key."""
