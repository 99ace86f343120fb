"""The contact tasks of a recording: the controller's task records as plain values.

The controller publishes one ``uvms_msgs/ContactTaskRecord`` on ``controller/task_record``
for each ContactTask that ran (docs/interfaces.md): its goal id, F_d, normal, contact
threshold and the stamps of its first and last control step. The action's goals and results
are services, not topics, so these records are how a recording tells its tasks apart;
``uvms_analysis.metrics.task_metrics`` computes a task's row of `uvms report` from the
controller states between the two stamps.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

TOPIC_TASK_RECORD = '/uvms/controller/task_record'


@dataclass(frozen=True)
class TaskRecord:
    """One contact task of a recording.

    Attributes:
        goal_id: The action goal's id, 32 hex digits.
        t_start: Time of the task's first control step (s, the run's time base).
        t_end: Time of its last control step (s, the run's time base).
        force_n: F_d of the goal (N); 0: motion only.
        normal: Unit force direction, map_ned (3,).
        contact_threshold_n: Normal force that counted as contact (N).
        error_code: How it ended (ContactTask result error_code).
    """

    goal_id: str
    t_start: float
    t_end: float
    force_n: float
    normal: FloatArray
    contact_threshold_n: float
    error_code: int


def _ns(stamp: Any) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def task_records(t: FloatArray, msgs: Sequence[Any]) -> tuple[TaskRecord, ...]:
    """ContactTaskRecord messages (stamped with their last step at ``t``) as TaskRecords."""
    return tuple(
        TaskRecord(
            goal_id=bytes(np.asarray(msg.goal_id, dtype=np.uint8)).hex(),
            t_start=float(t_end) - (_ns(msg.header.stamp) - _ns(msg.start)) * 1e-9,
            t_end=float(t_end),
            force_n=float(msg.force_n),
            normal=np.array([msg.normal.x, msg.normal.y, msg.normal.z], dtype=np.float64),
            contact_threshold_n=float(msg.contact_threshold_n),
            error_code=int(msg.error_code),
        )
        for t_end, msg in zip(t, msgs, strict=True)
    )
