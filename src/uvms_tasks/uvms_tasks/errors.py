"""Exception types of uvms_tasks."""

from __future__ import annotations


class TaskError(Exception):
    """Base class of every error raised by uvms_tasks."""


class TaskFileError(TaskError, ValueError):
    """A task or mission file cannot be read or does not follow the schema (one line)."""


class TaskGoalError(TaskError, ValueError):
    """A task cannot become a goal (a half circle without its start position)."""


class TaskClientError(TaskError, RuntimeError):
    """The action server is unavailable, refused a goal or did not answer in time."""
