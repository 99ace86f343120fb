"""The paper's performance metrics of a run: pure functions on numpy arrays, and RunMetrics.

The metric functions are pure: numpy arrays in, numbers out. The contact force along the wall
normal is the x component of ``F_e`` in ``map_ned`` (the wall is a plane normal to x), signed
so that pushing towards the desired force is positive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from uvms_analysis.series import BoolArray, FloatArray, Run

#: Band around F_d within which the force counts as settled (fraction of |F_d|).
SETTLING_BAND = 0.05
#: Shortest stay inside the band that counts as settled (s); shorter stays are crossings.
SETTLING_MIN_HOLD_S = 0.2
#: Window after first contact in which the impact peak is taken (s).
IMPACT_WINDOW_S = 0.5
#: Samples before this time are excluded from the free-motion tracking error (s): the start-up
#: transient of the controller is not tracking performance.
TRACKING_START_S = 1.0
#: Normal force above which the end effector counts as in contact when a recording has no
#: ground-truth contact topic (N); well above the 0.1 N sensor noise of Case II.
CONTACT_FORCE_THRESHOLD_N = 1.0


# --------------------------------------------------------------------------------------------
# Pure metrics on arrays
# --------------------------------------------------------------------------------------------


def contact_intervals(in_contact: BoolArray) -> list[tuple[int, int]]:
    """Index ranges ``[start, stop)`` of the runs of consecutive in-contact samples.

    Example: ``contact_intervals(np.array([0, 1, 1, 0, 1], bool)) == [(1, 3), (4, 5)]``.
    """
    flags = np.concatenate(([False], np.asarray(in_contact, dtype=bool), [False]))
    edges = np.flatnonzero(np.diff(flags.astype(np.int8)))
    return [(int(start), int(stop)) for start, stop in zip(edges[::2], edges[1::2], strict=True)]


def first_contact_time(t: FloatArray, in_contact: BoolArray) -> float | None:
    """Time of the first in-contact sample (s), None if the run never touches."""
    hits = np.flatnonzero(in_contact)
    return float(t[hits[0]]) if hits.size else None


def contact_duration(t: FloatArray, in_contact: BoolArray) -> float:
    """Total time in contact (s).

    Each interval lasts from its first in-contact sample to the first sample after it that is
    out of contact (or to the last sample if the run ends in contact).
    """
    total = 0.0
    for start, stop in contact_intervals(in_contact):
        end = stop if stop < len(t) else len(t) - 1
        total += float(t[end] - t[start])
    return total


def peak(
    t: FloatArray, values: FloatArray, t_from: float = -math.inf, t_to: float = math.inf
) -> tuple[float, float] | None:
    """Largest value in the window ``t_from <= t <= t_to`` and its time: ``(t_peak, value)``.

    Returns None if no sample lies in the window.
    """
    mask = (t >= t_from) & (t <= t_to)
    if not mask.any():
        return None
    index = int(np.flatnonzero(mask)[np.argmax(values[mask])])
    return float(t[index]), float(values[index])


def overshoot_percent(peak_value: float, reference: float) -> float:
    """Percent overshoot of a peak over a set-point: ``max(0, 100 (peak - ref) / |ref|)``."""
    if reference == 0.0:
        raise ValueError('overshoot is undefined for a zero reference')
    return max(0.0, 100.0 * (peak_value - reference) / abs(reference))


def settling_time(
    t: FloatArray,
    values: FloatArray,
    reference: float,
    t_start: float,
    t_end: float,
    band: float = SETTLING_BAND,
    min_hold_s: float = SETTLING_MIN_HOLD_S,
) -> float | None:
    """Time from ``t_start`` until ``values`` stay within ``±band·|reference|`` up to ``t_end``.

    The settling instant is the earliest sample in ``[t_start, t_end]`` from which every
    sample up to ``t_end`` is inside the band. Returns None (not settled) if the sample at
    ``t_end`` is outside the band or the final stay is shorter than ``min_hold_s``.
    """
    window = np.flatnonzero((t >= t_start) & (t <= t_end))
    if window.size == 0:
        return None
    inside = np.abs(values[window] - reference) <= band * abs(reference)
    if not inside[-1]:
        return None
    outside = np.flatnonzero(~inside)
    first_settled = window[outside[-1] + 1] if outside.size else window[0]
    if t[window[-1]] - t[first_settled] < min_hold_s:
        return None
    return float(t[first_settled] - t_start)


def last_time_in_band(
    t: FloatArray,
    values: FloatArray,
    reference: float,
    t_start: float,
    t_end: float,
    band: float = SETTLING_BAND,
) -> float | None:
    """Last time in ``[t_start, t_end]`` at which ``values`` lie within ``±band·|reference|``.

    This ends the constrained phase: after it the end effector releases the wall and the
    force leaves the band for good. None if the force is never in the band.
    """
    mask = (t >= t_start) & (t <= t_end) & (np.abs(values - reference) <= band * abs(reference))
    hits = np.flatnonzero(mask)
    return float(t[hits[-1]]) if hits.size else None


def rms(values: FloatArray) -> float:
    """Root mean square of the samples (NaN for no samples)."""
    values = np.asarray(values, dtype=np.float64)
    return float(np.sqrt(np.mean(values**2))) if values.size else math.nan


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


def compute_metrics(run: Run, force_source: ForceSource = 'auto') -> RunMetrics:
    """All metrics of a run (see RunMetrics); force metrics are None for a run without contact."""
    values: dict[str, Any] = {'name': run.name}
    if run.path is not None:
        values['file'] = str(run.path)
    f_d = desired_normal_force(run)
    values['desired_force'] = f_d
    force = normal_force(run, force_source)
    if force is not None:
        values['force_source'] = force.source
        values.update(_force_metrics(force, None if f_d is None else abs(f_d)))
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
    return RunMetrics(**values)


def _force_metrics(force: NormalForce, f_d: float | None) -> dict[str, Any]:
    """Contact timing and force-response metrics of a normal force signal."""
    t, f = force.t, force.force
    intervals = contact_intervals(force.in_contact)
    values: dict[str, Any] = {'contact_count': len(intervals)}
    t_contact = first_contact_time(t, force.in_contact)
    if t_contact is None:
        return values
    values['first_contact_time'] = t_contact
    values['contact_duration'] = contact_duration(t, force.in_contact)
    overall = peak(t, f)
    impact = peak(t, f, t_contact, t_contact + IMPACT_WINDOW_S)
    values['peak_force'] = None if overall is None else overall[1]
    values['impact_peak_force'] = None if impact is None else impact[1]
    if f_d is None or f_d == 0.0:
        return values
    if overall is not None:
        values['overshoot'] = overshoot_percent(overall[1], f_d)
    # The constrained phase runs from first contact to the end of the last contact interval,
    # minus the release, where the force falls out of the band for good.
    last_stop = intervals[-1][1]
    t_contact_end = float(t[min(last_stop, len(t) - 1)])
    t_end = last_time_in_band(t, f, f_d, t_contact, t_contact_end)
    if t_end is None:
        return values
    t_settle = settling_time(t, f, f_d, t_contact, t_end)
    values['settling_time'] = t_settle
    if t_settle is not None:
        settled = (t >= t_contact + t_settle) & (t <= t_end)
        values['force_rms_error'] = rms(f[settled] - f_d)
    return values


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
