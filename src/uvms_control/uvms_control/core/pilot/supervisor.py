"""The task supervisor the controller node runs: a movable hold point, the arm's joint hold."""

from __future__ import annotations

import numpy.typing as npt

from uvms_control.core.law.controller_result import ControllerResult
from uvms_control.core.law.unified_controller import UnifiedForceController
from uvms_control.core.task.contact_task import SafetyLimits
from uvms_control.core.task.joint_hold import JointHold
from uvms_control.core.task.task_states import TaskEvent
from uvms_control.core.task.task_supervisor import TaskSupervisor


class PilotedSupervisor(TaskSupervisor):
    """A ``TaskSupervisor`` whose hold point a pilot may move (``PilotHandover``).

    Args:
        controller: The unified force controller.
        limits: The safety limits.
        joint_hold: While no goal runs, hold the arm in joint space instead of the end
            effector in map_ned (``core.task.joint_hold``); None: the end effector.
    """

    def __init__(self, controller: UnifiedForceController, limits: SafetyLimits,
                 joint_hold: JointHold | None = None) -> None:
        super().__init__(controller, limits)
        self.joint_hold = joint_hold

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

    def step(self, t: float, q: npt.ArrayLike, w: npt.ArrayLike, f_sensor: npt.ArrayLike,
             f_t: float | None = None) -> tuple[ControllerResult, list[TaskEvent]]:
        """``TaskSupervisor.step``; with a joint hold and no goal, its torques in tau_b.

        The hold point then follows the end effector (no tracking error while the vehicle
        is moved by something else); the step's internals stay the task law's.
        """
        result, events = super().step(t, q, w, f_sensor, f_t)
        hold = self.joint_hold
        if hold is None:
            return result, events
        if self.has_goal or self.releasing:
            hold.release()
            return result, events
        result.tau_b = hold.torque_b(self.controller.model, q, w)
        self.follow(result.X.tolist(), result.X_dot.tolist())
        return result, events
