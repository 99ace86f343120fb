"""Tests of the contact-task goal checks and result figures (core/contact_task.py)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from uvms_control.core.task.contact_task import (
    ContactTaskGoal,
    SafetyLimits,
    TaskCode,
    TaskFigures,
    TaskGoalError,
    validate_goal,
)

X = np.array([1.7, 0.0, 0.1])  # end effector at acceptance (m)
THRESHOLD_N = 5.0
LIMITS = SafetyLimits(max_contact_force_n=400.0, max_path_distance_m=1.5)
GOAL = ContactTaskGoal(
    path=np.array([[1.7, 0.0, 0.1], [1.75, 0.0, 0.15], [1.7, 0.0, 0.2]]),
    times=np.array([0.0, 2.0, 4.0]),
    velocities=None,
    accelerations=None,
    normal=np.array([2.0, 0.0, 0.0]),
    force_n=100.0,
    force_ramp_s=1.0,
)


@pytest.mark.parametrize(
    'goal',
    [
        GOAL,
        replace(GOAL, force_n=0.0, force_ramp_s=0.0),
        replace(GOAL, velocities=np.zeros((3, 3)),
                accelerations=np.array([[1.0, 1.0, 1.0], [0.1, 0.0, 0.1], [0.0, 0.0, 0.0]])),
        replace(GOAL, start_time_s=12.0),
    ],
)
def test_valid_goal_is_accepted(goal: ContactTaskGoal) -> None:
    """A well-formed goal passes, also motion only (force_n = 0, no ramp) or with derivatives."""
    validate_goal(goal, X, LIMITS, THRESHOLD_N)


@pytest.mark.parametrize(
    ('changes', 'field'),
    [
        ({'path': np.array([[1.7, 0.0, 0.1]]), 'times': np.array([0.0])}, 'path'),
        ({'path': np.array([[1.7, 0.0, 0.1], [math.nan, 0.0, 0.1], [1.7, 0.0, 0.2]])}, 'path'),
        ({'path': np.array([[1.7, 0.0], [1.8, 0.0], [1.7, 0.1]])}, 'path'),
        ({'times': np.array([0.0, 2.0])}, 'time_from_start_s'),
        ({'times': np.array([0.0, math.inf, 4.0])}, 'time_from_start_s'),
        ({'times': np.array([-0.5, 2.0, 4.0])}, 'time_from_start_s[0]'),
        ({'times': np.array([0.0, 2.0, 2.0])}, 'time_from_start_s[2]'),
        ({'velocities': np.zeros((2, 3))}, 'velocity'),
        ({'accelerations': np.full((3, 3), math.inf)}, 'acceleration'),
        ({'normal': np.zeros(3)}, 'normal'),
        ({'normal': np.array([1.0, 0.0])}, 'normal'),
        ({'force_n': -1.0}, 'force_n'),
        ({'force_n': math.nan}, 'force_n'),
        ({'force_n': 401.0}, 'force_n'),
        ({'force_n': THRESHOLD_N}, 'force_n'),
        ({'force_n': 2.0}, 'force_n'),
        ({'force_ramp_s': 0.0}, 'force_ramp_s'),
        ({'start_time_s': math.nan}, 'header.stamp'),
        (
            {'path': np.array([[1.7, 0.0, 0.1], [1.7, 0.0, 1.7], [1.7, 0.0, 0.2]])},
            'path[1]',
        ),
    ],
)
def test_invalid_goal_names_its_field(changes: dict[str, object], field: str) -> None:
    """Each malformed, unsafe or out-of-reach goal is refused naming the field it got wrong."""
    goal = replace(GOAL, **changes)  # type: ignore[arg-type]
    with pytest.raises(TaskGoalError) as info:
        validate_goal(goal, X, LIMITS, THRESHOLD_N)
    assert info.value.field == field
    assert str(info.value).startswith(f'{field} = ')


DT = 0.01  # control period of the synthetic force signal (s)


def press(k: int) -> tuple[float, bool]:
    """A synthetic press on F_d = 100 N: (n·F_e (N), F_d at its set-point) at step k.

    No contact before 1 s; a rise from 10 to 89 N until 2 s (F_d ramping); 120 N of overshoot
    until 2.5 s; then 102 and 98 N in turn (2 N off) until 4 s; released (no force) after.
    """
    if k < 100:
        return 0.0, False
    if k < 200:
        return 10.0 + 0.8 * (k - 100), False
    if k < 250:
        return 120.0, True
    if k < 400:
        return (102.0 if k % 2 == 0 else 98.0), True
    return 0.0, False


def run_figures(force_n: float, signal) -> TaskFigures:  # type: ignore[no-untyped-def]
    """Feed 5 s of the signal to the figures, one period at a time."""
    figures = TaskFigures(force_n)
    for k in range(500):
        f_normal, at_setpoint = signal(k)
        figures.update(k * DT, DT, f_normal, f_normal >= THRESHOLD_N, at_setpoint)
    return figures


def test_figures_of_a_press_have_their_known_values() -> None:
    """Contact 3 s from 1 s, peak 120 N, settled 1.5 s after contact, RMS error 2 N after it."""
    result = run_figures(100.0, press).result(TaskCode.SUCCEEDED, 'path done')
    assert (result.code, result.message) == (TaskCode.SUCCEEDED, 'path done')
    assert result.contact_time_s == pytest.approx(3.0)
    assert result.peak_force_n == 120.0
    assert result.settling_time_s == pytest.approx(1.5)
    assert result.rms_force_error_n == pytest.approx(2.0)


def test_overshoot_before_settling_is_not_in_the_rms_error() -> None:
    """The RMS error counts from settling: 20 N of overshoot before it leave it at 2 N."""
    figures = run_figures(100.0, press)
    result = figures.result(TaskCode.SUCCEEDED, '')
    assert figures.first_contact_s == pytest.approx(1.0)
    assert figures.first_contact_s + result.settling_time_s == pytest.approx(2.5)
    assert result.rms_force_error_n == pytest.approx(2.0)


def test_force_that_never_settles_has_no_settling_time_or_rms() -> None:
    """A force that stays 10 % off F_d never settles: settling time and RMS error are NaN.

    In contact from the first to the last sample: 4.99 s (contact time runs from sample to
    sample, as in `uvms report`).
    """
    result = run_figures(100.0, lambda k: (110.0, k >= 100)).result(TaskCode.CANCELED, '')
    assert result.contact_time_s == pytest.approx(4.99)
    assert math.isnan(result.settling_time_s)
    assert math.isnan(result.rms_force_error_n)


def test_motion_only_task_counts_contact_but_no_force_error() -> None:
    """force_n = 0: contact time and peak are kept; there is no set-point to settle on."""
    result = run_figures(0.0, press).result(TaskCode.SUCCEEDED, '')
    assert result.contact_time_s == pytest.approx(3.0)
    assert result.peak_force_n == 120.0
    assert math.isnan(result.settling_time_s)
    assert math.isnan(result.rms_force_error_n)


def test_force_settled_during_the_ramp_has_a_settling_time_shorter_than_the_ramp() -> None:
    """Settling is from first contact until the force stays within 5 % of force_n, ramp or not.

    The force is within 1 N of 100 N from 0.1 s after first contact while F_d still ramps
    (1 s): settled 0.1 s after contact, not bounded below by force_ramp_s.
    """
    ramp_s = 1.0

    def quick(k: int) -> tuple[float, bool]:
        t = k * DT
        if t < 1.0:
            return 0.0, False
        if t < 1.1 - 1e-9:
            return 50.0, False
        return (100.5 if k % 2 else 99.5), t >= 1.0 + ramp_s

    result = run_figures(100.0, quick).result(TaskCode.SUCCEEDED, '')
    assert result.settling_time_s == pytest.approx(0.1)
    assert result.settling_time_s < ramp_s
    assert result.rms_force_error_n == pytest.approx(0.5)


def test_figures_hold_every_step_of_a_long_task() -> None:
    """Samples beyond the first capacity are kept: a task longer than 20 s at 500 Hz."""
    figures = TaskFigures(100.0)
    steps = 3 * TaskFigures.INITIAL_CAPACITY
    for k in range(steps):
        figures.update(k * 0.002, 0.002, 100.0 if k >= 10 else 0.0, k >= 10, k >= 10)
    result = figures.result(TaskCode.SUCCEEDED, '')
    assert result.contact_time_s == pytest.approx((steps - 1 - 10) * 0.002)
    assert (result.start_s, result.end_s) == (0.0, pytest.approx((steps - 1) * 0.002))
    assert result.settling_time_s == 0.0
