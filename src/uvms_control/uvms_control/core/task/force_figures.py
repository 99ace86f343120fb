"""Contact-force figures of a force trace: one definition for task results and `uvms report`.

Pure functions on numpy arrays: contact intervals, peak, settling time and RMS force error.
``force_figures`` is the one function that turns a trace (t, normal force, contact flags) and
its set-point F_d into the figures; the ContactTask result (``contact_task.TaskFigures``) and
``uvms_analysis.metrics`` (``uvms report``) both call it, so a task's result and its report
row agree to the digit. It lives in the controller's core because the analysis package may
import the controller, not the other way round (docs/architecture.md, package dependencies).
Definitions: docs/figures.md#metrics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Band around F_d within which the force counts as settled (fraction of |F_d|).
SETTLING_BAND = 0.05
#: Shortest stay inside the band that counts as settled (s); shorter stays are crossings.
SETTLING_MIN_HOLD_S = 0.2
#: Window after first contact in which the impact peak is taken (s).
IMPACT_WINDOW_S = 0.5


def contact_intervals(in_contact: BoolArray) -> list[tuple[int, int]]:
    """Index ranges ``[start, stop)`` of the runs of consecutive in-contact samples.

    >>> contact_intervals(np.array([0, 1, 1, 0, 1], bool))
    [(1, 3), (4, 5)]
    """
    flags = np.concatenate(([False], np.asarray(in_contact, dtype=bool), [False]))
    edges = np.flatnonzero(np.diff(flags.astype(np.int8)))
    return [(int(start), int(stop)) for start, stop in zip(edges[::2], edges[1::2], strict=True)]


def first_contact_time(t: FloatArray, in_contact: BoolArray) -> float | None:
    """Time of the first in-contact sample (s), None if the trace never touches."""
    hits = np.flatnonzero(in_contact)
    return float(t[hits[0]]) if hits.size else None


def contact_duration(t: FloatArray, in_contact: BoolArray) -> float:
    """Total time in contact (s).

    Each interval lasts from its first in-contact sample to the first sample after it that is
    out of contact (or to the last sample if the trace ends in contact).
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


@dataclass(frozen=True)
class ForceFigures:
    """The contact-force figures of a trace; None where a figure does not apply.

    Attributes:
        contact_count: Number of separate contact intervals (1 = no bounce).
        first_contact_time: Time of the first in-contact sample (s).
        contact_duration: Total time in contact (s), see ``contact_duration``.
        peak_force: Largest normal force of the trace (N); None without contact.
        impact_peak_force: Largest normal force within ``IMPACT_WINDOW_S`` of first contact (N).
        overshoot: Overshoot of the peak over F_d (%), 0 if the peak stays below F_d.
        settling_time: From first contact until the force stays within ``SETTLING_BAND`` of
            F_d up to the release (s); None if it never settles.
        force_rms_error: RMS of F - F_d from settling to the release (N): the release is the
            last sample within the band, after which the force leaves it for good.
    """

    contact_count: int = 0
    first_contact_time: float | None = None
    contact_duration: float | None = None
    peak_force: float | None = None
    impact_peak_force: float | None = None
    overshoot: float | None = None
    settling_time: float | None = None
    force_rms_error: float | None = None


def force_figures(
    t: FloatArray, force: FloatArray, in_contact: BoolArray, f_d: float | None
) -> ForceFigures:
    """The contact-force figures of a trace against the set-point ``f_d``.

    Args:
        t: Time of each sample (s), increasing.
        force: Normal force at each sample (N), signed so that F_d is positive.
        in_contact: Contact flag of each sample.
        f_d: Force set-point (N, > 0); None or 0: no set-point (no overshoot, settling, RMS).

    Returns:
        The figures; contact timing and peaks are None for a trace without contact.

    Example: a force that steps to 100 N at first contact settles at once:

    >>> t = np.arange(0.0, 1.0, 0.01)
    >>> f = np.where(t >= 0.5, 100.0, 0.0)
    >>> figures = force_figures(t, f, f > 1.0, 100.0)
    >>> figures.settling_time, figures.force_rms_error, round(figures.first_contact_time, 2)
    (0.0, 0.0, 0.5)
    """
    intervals = contact_intervals(in_contact)
    t_contact = first_contact_time(t, in_contact)
    if t_contact is None:
        return ForceFigures(contact_count=len(intervals))
    overall = peak(t, force)
    impact = peak(t, force, t_contact, t_contact + IMPACT_WINDOW_S)
    figures: dict[str, Any] = {
        'contact_count': len(intervals),
        'first_contact_time': t_contact,
        'contact_duration': contact_duration(t, in_contact),
        'peak_force': None if overall is None else overall[1],
        'impact_peak_force': None if impact is None else impact[1],
    }
    if f_d is None or f_d == 0.0:
        return ForceFigures(**figures)
    if overall is not None:
        figures['overshoot'] = overshoot_percent(overall[1], f_d)
    # The constrained phase runs from first contact to the end of the last contact interval,
    # minus the release, where the force falls out of the band for good.
    last_stop = intervals[-1][1]
    t_contact_end = float(t[min(last_stop, len(t) - 1)])
    t_end = last_time_in_band(t, force, f_d, t_contact, t_contact_end)
    if t_end is None:
        return ForceFigures(**figures)
    t_settle = settling_time(t, force, f_d, t_contact, t_end)
    figures['settling_time'] = t_settle
    if t_settle is not None:
        settled = (t >= t_contact + t_settle) & (t <= t_end)
        figures['force_rms_error'] = rms(force[settled] - f_d)
    return ForceFigures(**figures)
