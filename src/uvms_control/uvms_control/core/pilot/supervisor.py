"""The task supervisor with what a pilot needs: a movable hold point and its state, read."""

from __future__ import annotations

from uvms_control.core.task.task_supervisor import TaskSupervisor


class PilotedSupervisor(TaskSupervisor):
    """A ``TaskSupervisor`` whose hold point a pilot may move (``PilotHandover``)."""

    @property
    def has_goal(self) -> bool:
        """A goal runs (its retreat included) or waits for the first step."""
        return self._running is not None or bool(self._queued)

    @property
    def releasing(self) -> bool:
        """The hold point backs off from a contact after a task (``Release``)."""
        return self._release is not None

    def follow(self, X_d: list[float], X_dot_d: list[float]) -> None:
        """Move the hold point to X_d (m) at X_dot_d (m/s), map_ned, as a pilot drives.

        A streamed hold target (``set_target``) is dropped: it would pull the point back.
        """
        self._target = None
        self.controller.task.follow(X_d, X_dot_d)
