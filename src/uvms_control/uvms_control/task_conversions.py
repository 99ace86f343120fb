"""ContactTask messages to and from the task core's arrays (the only place they meet)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from geometry_msgs.msg import Point, PointStamped, Vector3

from uvms_control.conversions import stamp_ns
from uvms_control.core.law.unified_controller import ControllerResult
from uvms_control.core.task.contact_task import ContactTaskGoal, TaskGoalError, TaskResult
from uvms_control.core.task.task_supervisor import TaskProgress
from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ContactTaskRecord

#: The frame of every task quantity (earth-fixed NED); an empty frame_id means it too.
TASK_FRAMES = ('map_ned', '')


def _xyz(vectors: Sequence[Point | Vector3]) -> np.ndarray:
    return np.array([(v.x, v.y, v.z) for v in vectors], dtype=np.float64).reshape(-1, 3)


def contact_task_goal(msg: ContactTask.Goal) -> ContactTaskGoal:
    """A ContactTask goal as arrays (map_ned, SI); the stamp as the start time (s) or None.

    Raises:
        TaskGoalError: a frame other than map_ned (the field and value named).
    """
    frame = msg.header.frame_id
    if frame not in TASK_FRAMES:
        raise TaskGoalError('header.frame_id', repr(frame), 'must be map_ned (or empty)')
    start_ns = stamp_ns(msg.header.stamp)
    return ContactTaskGoal(
        path=_xyz(msg.path),
        times=np.array(msg.time_from_start_s, dtype=np.float64),
        velocities=_xyz(msg.velocity) if len(msg.velocity) else None,
        accelerations=_xyz(msg.acceleration) if len(msg.acceleration) else None,
        normal=np.array((msg.normal.x, msg.normal.y, msg.normal.z), dtype=np.float64),
        force_n=float(msg.force_n),
        force_ramp_s=float(msg.force_ramp_s),
        require_contact=bool(msg.require_contact),
        start_time_s=None if start_ns == 0 else start_ns * 1e-9,
    )


def contact_task_result(result: TaskResult) -> ContactTask.Result:
    """The action's result from the task core's."""
    return ContactTask.Result(
        error_code=int(result.code),
        error_string=result.message,
        contact_time_s=float(result.contact_time_s),
        peak_force_n=float(result.peak_force_n),
        rms_force_error_n=float(result.rms_force_error_n),
        settling_time_s=float(result.settling_time_s),
        transit_s=float(result.transit_s),
    )


def unit_normal(goal: ContactTaskGoal) -> np.ndarray:
    """The goal's normal as a unit vector, as the task supervisor normalizes it."""
    normal = np.asarray(goal.normal, dtype=np.float64)
    return normal / float(np.linalg.norm(normal))


def contact_task_record(goal_id: bytes, goal: ContactTaskGoal, result: TaskResult,
                        contact_threshold_n: float) -> ContactTaskRecord | None:
    """The record of a task that ended (controller/task_record); None if it ran no step."""
    if not (math.isfinite(result.start_s) and math.isfinite(result.end_s)):
        return None
    msg = ContactTaskRecord()
    msg.header.frame_id = 'map_ned'
    end_ns, start_ns = round(result.end_s * 1e9), round(result.start_s * 1e9)
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(end_ns, 1_000_000_000)
    msg.start.sec, msg.start.nanosec = divmod(start_ns, 1_000_000_000)
    msg.goal_id = list(goal_id)
    msg.force_n = float(goal.force_n)
    msg.normal.x, msg.normal.y, msg.normal.z = unit_normal(goal).tolist()
    msg.contact_threshold_n = float(contact_threshold_n)
    msg.error_code = int(result.code)
    return msg


def contact_task_feedback(progress: TaskProgress, step: ControllerResult) -> ContactTask.Feedback:
    """The action's feedback from the running task and the last controller step."""
    feedback = ContactTask.Feedback()
    feedback.phase = int(step.phase)
    feedback.weight = float(step.W)
    feedback.force_n = progress.force_n
    feedback.force_desired_n = progress.force_desired_n
    feedback.position.x, feedback.position.y, feedback.position.z = step.X.tolist()
    (feedback.position_desired.x, feedback.position_desired.y,
     feedback.position_desired.z) = step.X_d.tolist()
    feedback.progress = float(progress.progress)
    feedback.state = int(progress.state)
    feedback.transit_s = float(progress.transit_s)
    feedback.in_transit = bool(progress.in_transit)
    return feedback


def target_position(msg: PointStamped) -> list[float]:
    """A streamed hold target (m, map_ned).

    Raises:
        TaskGoalError: another frame, or a non-finite point.
    """
    if msg.header.frame_id not in TASK_FRAMES:
        raise TaskGoalError('header.frame_id', repr(msg.header.frame_id),
                            'must be map_ned (or empty)')
    point = [msg.point.x, msg.point.y, msg.point.z]
    if not all(math.isfinite(v) for v in point):
        raise TaskGoalError('point', point, 'must be finite')
    return point
