"""The task supervisor's states, events and the running goal's record (no logic)."""

from __future__ import annotations

import enum
import math
from collections.abc import Hashable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from uvms_control.core.task.contact_task import ContactTaskGoal, TaskCode, TaskFigures, TaskResult

FloatArray = npt.NDArray[np.float64]


class TaskState(enum.IntEnum):
    """Where the running task is (values of ContactTask.Feedback.STATE_*)."""

    WAITING = 0
    FOLLOWING = 1
    RELEASING = 2
    RETREATING = 3
    SAFE_HOLD = 4


class SupervisorState(enum.IntEnum):
    """The supervisor's state, goal or no goal."""

    HOLD = 0
    WAITING = 1
    FOLLOWING = 2
    RELEASING = 3
    RETREATING = 4
    SAFE_HOLD = 5


TASK_STATE = {SupervisorState.WAITING: TaskState.WAITING,
               SupervisorState.FOLLOWING: TaskState.FOLLOWING,
               SupervisorState.RELEASING: TaskState.RELEASING,
               SupervisorState.RETREATING: TaskState.RETREATING,
               SupervisorState.SAFE_HOLD: TaskState.SAFE_HOLD}


@dataclass(frozen=True)
class TaskEvent:
    """A task that ended, with its result."""

    goal_id: Hashable
    result: TaskResult


@dataclass(frozen=True)
class TaskProgress:
    """The running task at the last step (the action's feedback).

    ``transit_s``: the duration of the transit to path[0] put before the goal's path (s; 0:
    none); ``in_transit``: the reference is on it now.
    """

    goal_id: Hashable
    state: TaskState
    progress: float
    force_n: float
    force_desired_n: float
    transit_s: float = 0.0
    in_transit: bool = False


@dataclass
class RunningTask:
    """The goal the supervisor runs, its unit normal, figures and transit (s)."""

    goal_id: Hashable
    goal: ContactTaskGoal
    normal: FloatArray
    figures: TaskFigures
    start_s: float | None = None
    transit_s: float = 0.0


def empty_result(code: TaskCode, message: str) -> TaskResult:
    """A result without figures (a goal that never ran)."""
    return TaskResult(code, message, 0.0, 0.0, math.nan, math.nan)
