"""The paper's performance metrics of a run: pure functions on numpy arrays, and RunMetrics.

The metric functions are pure: numpy arrays in, numbers out. The force figures (contact time,
peak, settling, RMS error) come from ``uvms_control.core.task.force_figures.force_figures``, the
function the ContactTask result uses too (re-exported here). The contact force along the wall
normal is the x component of ``F_e`` in ``map_ned`` (the wall is a plane normal to x), signed
so that pushing towards the desired force is positive.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
import yaml
from uvms_control.core.task.force_figures import (  # noqa: F401 (re-exported: the metric functions)
    IMPACT_WINDOW_S,
    SETTLING_BAND,
    SETTLING_MIN_HOLD_S,
    contact_duration,
    contact_intervals,
    first_contact_time,
    force_figures,
    last_time_in_band,
    overshoot_percent,
    peak,
    rms,
    settling_time,
)

from uvms_analysis.series import BoolArray, FloatArray, Run
from uvms_analysis.tasks import TaskRecord
from uvms_description import DEFAULT_ROBOT

#: Samples before this time are excluded from the free-motion tracking error (s): the start-up
#: transient of the controller is not tracking performance.
TRACKING_START_S = 1.0
#: Tolerance of the match of a task record's stamps with the controller's samples (s): the
#: record's start time is rebuilt from ns stamps, far finer than a control period.
TASK_WINDOW_TOLERANCE_S = 1e-6
#: Normal force above which the end effector counts as in contact when a recording has no
#: ground-truth contact topic (N); well above the 0.1 N sensor noise of Case II.
CONTACT_FORCE_THRESHOLD_N = 1.0


# --------------------------------------------------------------------------------------------
# Pure metrics on arrays
# --------------------------------------------------------------------------------------------


def hold(t_query: FloatArray, t: FloatArray, values: npt.NDArray[Any]) -> npt.NDArray[Any]:
    """Zero-order hold: the latest sample of ``values`` at or before each query time.

    Queries before the first sample take the first sample.
    """
    index = np.searchsorted(t, t_query, side='right') - 1
    return np.asarray(values)[np.clip(index, 0, len(t) - 1)]


def rotation_angle_from(quaternion_0: FloatArray, quaternion: FloatArray) -> FloatArray:
    """Angle of the rotation from ``quaternion_0`` to each of ``quaternion`` (rad, in [0, π]).

    This is the attitude excursion independent of the Euler-angle convention:
    ``2 acos(|q0 · q|)`` for unit quaternions.
    """
    q0 = np.asarray(quaternion_0, dtype=np.float64)
    q = np.asarray(quaternion, dtype=np.float64).reshape(-1, 4)
    q0 = q0 / np.linalg.norm(q0)
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    angle: FloatArray = 2.0 * np.arccos(np.clip(np.abs(q @ q0), 0.0, 1.0))
    return angle


def max_norm_from_start(position: FloatArray) -> float:
    """Largest distance of a trajectory (n, 3) from its first point (m)."""
    position = np.asarray(position, dtype=np.float64)
    return float(np.max(np.linalg.norm(position - position[0], axis=1)))


def max_abs_or_none(values: FloatArray) -> float | None:
    """Largest absolute value, None for no samples."""
    return float(np.max(np.abs(values))) if np.size(values) else None


# --------------------------------------------------------------------------------------------
# Metrics of a run
# --------------------------------------------------------------------------------------------

ForceSource = Literal['auto', 'contact', 'controller']


@dataclass(frozen=True)
class RunMetrics:
    """Performance metrics of one run; None where a metric does not apply (n/a).

    Forces are the normal (x) component; position errors are ``X_d - X`` of the controller
    state; times are from the start of the recording.

    Attributes:
        name: Run name.
        file: The recording it was computed from, as given (None without a file): runs of
            one scenario share a name, so the file tells them apart.
        task: Goal id (32 hex digits) of the contact task these metrics are of; None: the
            whole run (a recording without task records).
        force_source: Which force the force metrics use: 'contact' (simulator ground truth)
            or 'controller' (measured F_e); None without a force signal.
        desired_force: Force set-point F_d (N): median of F_d,x while in contact.
        first_contact_time: Time of the first contact (s).
        contact_count: Number of separate contact intervals (1 = no bounce).
        contact_duration: Total time in contact (s).
        peak_force: Largest normal force of the run (N).
        overshoot: Overshoot of the peak over F_d (%), 0 if the peak stays below F_d.
        impact_peak_force: Largest normal force within 0.5 s of first contact (N).
        settling_time: From first contact until the force stays within 5 % of F_d (s).
        force_rms_error: RMS of F_e - F_d in the constrained phase after settling (N).
        max_error_y_contact: Largest |Y_d - Y| while in contact (m).
        max_error_z_contact: Largest |Z_d - Z| while in contact (m).
        max_error_y: Largest |Y_d - Y| over the run (m).
        max_error_z: Largest |Z_d - Z| over the run (m).
        tracking_error: Largest ``‖X_d - X‖`` out of contact after the first second (m).
        vehicle_displacement: Largest distance of the vehicle from its start position (m).
        vehicle_rotation: Largest attitude change from the start attitude (rad).
        current_speed: Mean speed of the ocean current (m/s), None in still water.
        current_speed_max: Largest speed of the ocean current (m/s), None in still water.
        saturation_scale_min: Smallest scale the allocator applied to the vehicle wrench to
            keep the thrusts within their limits (1: never saturated).
    """

    name: str
    file: str | None = None
    task: str | None = None
    robot: str | None = None
    force_source: str | None = None
    desired_force: float | None = None
    first_contact_time: float | None = None
    contact_count: int = 0
    contact_duration: float | None = None
    peak_force: float | None = None
    overshoot: float | None = None
    impact_peak_force: float | None = None
    settling_time: float | None = None
    force_rms_error: float | None = None
    max_error_y_contact: float | None = None
    max_error_z_contact: float | None = None
    max_error_y: float | None = None
    max_error_z: float | None = None
    tracking_error: float | None = None
    vehicle_displacement: float | None = None
    vehicle_rotation: float | None = None
    current_speed: float | None = None
    current_speed_max: float | None = None
    saturation_scale_min: float | None = None


@dataclass(frozen=True)
class NormalForce:
    """The normal contact force signal a run's force metrics use.

    Attributes:
        source: 'contact' (ground truth) or 'controller' (measured F_e).
        t: Time (s).
        force: Normal force (N), signed so that F_d is positive.
        in_contact: Contact flag per sample.
    """

    source: str
    t: FloatArray
    force: FloatArray
    in_contact: BoolArray


def desired_normal_force(run: Run) -> float | None:
    """Force set-point F_d,x (N): median of the controller's F_d,x while in contact.

    Without contact samples the median over the whole run; None without a controller state.
    """
    if run.controller is None or run.controller.t.size == 0:
        return None
    f_d = run.controller.F_d[:, 0]
    in_contact = controller_contact_mask(run)
    return float(np.median(f_d[in_contact] if in_contact.any() else f_d))


def controller_contact_mask(run: Run) -> BoolArray:
    """Contact flag at the controller's samples.

    From the ground truth (zero-order hold) if recorded, else ``|F_e,x|`` above 1 N.
    """
    if run.controller is None:
        return np.zeros(0, dtype=bool)
    if run.contact is not None and run.contact.t.size:
        return np.asarray(hold(run.controller.t, run.contact.t, run.contact.in_contact), bool)
    return np.asarray(np.abs(run.controller.F_e[:, 0]) > CONTACT_FORCE_THRESHOLD_N)


def normal_force(run: Run, source: ForceSource = 'auto') -> NormalForce | None:
    """The normal force signal: ground truth if recorded ('auto'), else the measured F_e.

    The sign is flipped when F_d,x < 0 so that the force towards the set-point is positive.
    """
    f_d = desired_normal_force(run)
    sign = -1.0 if f_d is not None and f_d < 0.0 else 1.0
    use_contact = source == 'contact' or (source == 'auto' and run.contact is not None)
    if use_contact:
        if run.contact is None or run.contact.t.size == 0:
            return None
        c = run.contact
        return NormalForce('contact', c.t, sign * c.force[:, 0], c.in_contact)
    if run.controller is None or run.controller.t.size == 0:
        return None
    ctrl = run.controller
    return NormalForce('controller', ctrl.t, sign * ctrl.F_e[:, 0], controller_contact_mask(run))


def run_robot(metadata: dict[str, dict[str, str]]) -> str | None:
    """The robot a recorded run used: ``robot_name`` of its parameters, None if not recorded.

    The simulator's if it has one, else any node's (all load the same robot folder). Node
    parameters recorded without any ``robot_name`` mean the nodes' default robot
    (``uvms_description.DEFAULT_ROBOT``): ``uvms launch`` and ``uvms run`` pass the name only
    when a scenario or ``--robot`` chooses one.
    """
    text = metadata.get('uvms', {}).get('parameters', '')
    try:
        nodes = yaml.safe_load(text) if text else None
    except yaml.YAMLError:
        return None
    if not isinstance(nodes, dict):
        return None
    names = sorted(nodes, key=lambda node: 'simulator' not in str(node))
    for node in names:
        section = nodes[node]
        values = section.get('ros__parameters') if isinstance(section, dict) else None
        if isinstance(values, dict) and values.get('robot_name'):
            return str(values['robot_name'])
    return DEFAULT_ROBOT if nodes else None


def compute_metrics(run: Run, force_source: ForceSource = 'auto') -> RunMetrics:
    """All metrics of a run (see RunMetrics); force metrics are None for a run without contact."""
    values: dict[str, Any] = {'name': run.name, 'robot': run_robot(run.metadata)}
    if run.path is not None:
        values['file'] = str(run.path)
    f_d = desired_normal_force(run)
    values['desired_force'] = f_d
    force = normal_force(run, force_source)
    if force is not None:
        values['force_source'] = force.source
        values.update(_force_metrics(force, None if f_d is None else abs(f_d)))
    values.update(_motion_metrics(run))
    return RunMetrics(**values)


def task_metrics(run: Run, task: TaskRecord, force_source: ForceSource = 'auto') -> RunMetrics:
    """The metrics of one contact task of a run: its samples from first to last step.

    F_d is the goal's force_n. With ``force_source`` 'auto' the force figures come from the
    simulator's ground truth along the task's normal when it was recorded, as the plots' and
    docs/results.md's do (one set of figures per run), else as 'controller': from the samples
    the task's result was computed from (the controller's F_e along the task's normal, contact
    at the controller's threshold) through the same ``force_figures``, so they equal the
    result's; 'contact' always takes the ground truth.
    Position and vehicle metrics are over the task's samples too.
    """
    part = run_window(run, task.t_start - TASK_WINDOW_TOLERANCE_S,
                      task.t_end + TASK_WINDOW_TOLERANCE_S)
    values: dict[str, Any] = {'name': run.name, 'task': task.goal_id,
                              'desired_force': task.force_n,
                              'robot': run_robot(run.metadata)}
    if run.path is not None:
        values['file'] = str(run.path)
    force = task_normal_force(part, task, force_source)
    if force is not None:
        values['force_source'] = force.source
        values.update(_force_metrics(force, task.force_n if task.force_n > 0.0 else None))
    values.update(_motion_metrics(part))
    return RunMetrics(**values)


def task_normal_force(run: Run, task: TaskRecord,
                      source: ForceSource = 'auto') -> NormalForce | None:
    """The normal force of a task: ground truth ('contact'; 'auto' when recorded), or its result's.

    The controller's force is ``normal @ F_e`` per sample, the product the task supervisor
    takes at each step, in contact at or above the task's threshold.
    """
    if source == 'auto' and run.contact is not None and run.contact.t.size:
        source = 'contact'
    if source == 'contact':
        if run.contact is None or run.contact.t.size == 0:
            return None
        c = run.contact
        return NormalForce('contact', c.t, c.force @ task.normal, c.in_contact)
    if run.controller is None or run.controller.t.size == 0:
        return None
    ctrl = run.controller
    force = np.array([float(task.normal @ f_e) for f_e in ctrl.F_e])
    return NormalForce('controller', ctrl.t, force, force >= task.contact_threshold_n)


def run_window(run: Run, t_from: float, t_to: float) -> Run:
    """The run cut to the samples with ``t_from <= t <= t_to`` (every series)."""
    cut: dict[str, Any] = {}
    for name in ('controller', 'contact', 'odometry', 'ee_pose', 'thrusters', 'current'):
        series = getattr(run, name)
        if series is not None:
            keep = (series.t >= t_from) & (series.t <= t_to)
            cut[name] = replace(series, **{f.name: getattr(series, f.name)[keep]
                                           for f in fields(series)})
    return replace(run, **cut)


def _motion_metrics(run: Run) -> dict[str, Any]:
    """Position errors of the end effector and the vehicle's excursion."""
    values: dict[str, Any] = {}
    if run.controller is not None and run.controller.t.size:
        values.update(_position_metrics(run))
    if run.odometry is not None and run.odometry.t.size:
        values['vehicle_displacement'] = max_norm_from_start(run.odometry.position)
        values['vehicle_rotation'] = float(
            np.max(rotation_angle_from(run.odometry.quaternion[0], run.odometry.quaternion))
        )
    if run.thrusters is not None and run.thrusters.t.size:
        values['saturation_scale_min'] = float(np.min(run.thrusters.saturation_scale))
    if run.current is not None and run.current.t.size:
        speed = np.linalg.norm(run.current.velocity, axis=1)
        values['current_speed'] = float(np.mean(speed))
        values['current_speed_max'] = float(np.max(speed))
    return values


def _force_metrics(force: NormalForce, f_d: float | None) -> dict[str, Any]:
    """Contact timing and force-response metrics of a normal force signal (``force_figures``)."""
    return asdict(force_figures(force.t, force.force, force.in_contact, f_d))


def _position_metrics(run: Run) -> dict[str, Any]:
    """Largest Y/Z errors (in contact and overall) and the free-motion tracking error."""
    assert run.controller is not None
    ctrl = run.controller
    error = ctrl.X_d - ctrl.X
    in_contact = controller_contact_mask(run)
    free = (~in_contact) & (ctrl.t >= TRACKING_START_S)
    return {
        'max_error_y': max_abs_or_none(error[:, 1]),
        'max_error_z': max_abs_or_none(error[:, 2]),
        'max_error_y_contact': max_abs_or_none(error[in_contact, 1]),
        'max_error_z_contact': max_abs_or_none(error[in_contact, 2]),
        'tracking_error': (
            float(np.max(np.linalg.norm(error[free], axis=1))) if free.any() else None
        ),
    }
