"""Tests of the reference generators (paper sec. 5.1-5.2, Fig. 7)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from uvms_control.core.errors import ControlParameterError
from uvms_control.core.law.reference import (
    ForcePhase,
    ForceSetpoint,
    HalfCircleReference,
    quintic_time_scaling,
)

X0 = np.array([1.7, 0.1, 0.2])


def numerical_derivative(f, t: float, h: float = 1e-5) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Central difference of f at t."""
    return (np.asarray(f(t + h)) - np.asarray(f(t - h))) / (2.0 * h)


@pytest.mark.parametrize('sigma', [0.1, 0.37, 0.5, 0.82])
def test_quintic_derivatives_match_finite_differences(sigma: float) -> None:
    """ds/dσ and d²s/dσ² of the quintic are its derivatives."""
    ds = numerical_derivative(lambda x: quintic_time_scaling(x)[0], sigma)
    dds = numerical_derivative(lambda x: quintic_time_scaling(x)[1], sigma)
    assert quintic_time_scaling(sigma)[1] == pytest.approx(float(ds), rel=1e-7)
    assert quintic_time_scaling(sigma)[2] == pytest.approx(float(dds), rel=1e-6, abs=1e-8)


def test_half_circle_starts_at_rest_at_the_start_point() -> None:
    """X_d(0) = X0 with zero velocity and acceleration (paper sec. 5.1)."""
    ref = HalfCircleReference(radius=0.1, duration=10.0, start_delay=0.0)
    x_d, v_d, a_d = ref.evaluate(0.0, X0)
    np.testing.assert_allclose(x_d, X0)
    np.testing.assert_allclose(v_d, 0.0, atol=1e-15)
    np.testing.assert_allclose(a_d, 0.0, atol=1e-15)


def test_half_circle_passes_toward_the_wall_then_down() -> None:
    """Half way it is r along +x (toward the wall) and r down; it ends 2 r down, at rest."""
    ref = HalfCircleReference(radius=0.1, duration=10.0, start_delay=1.0)
    middle, _, _ = ref.evaluate(6.0, X0)
    end, v_end, a_end = ref.evaluate(11.0, X0)
    np.testing.assert_allclose(middle, X0 + np.array([0.1, 0.0, 0.1]), atol=1e-12)
    np.testing.assert_allclose(end, X0 + np.array([0.0, 0.0, 0.2]), atol=1e-12)
    np.testing.assert_allclose(v_end, 0.0, atol=1e-15)
    np.testing.assert_allclose(a_end, 0.0, atol=1e-15)


@pytest.mark.parametrize('t', [1.3, 4.0, 6.2, 9.9])
def test_half_circle_stays_on_the_circle(t: float) -> None:
    """|X_d - c| = r with c = X0 + r d, in the plane spanned by n and d."""
    ref = HalfCircleReference(radius=0.1, duration=10.0, start_delay=1.0)
    x_d, _, _ = ref.evaluate(t, X0)
    centre = X0 + np.array([0.0, 0.0, 0.1])
    assert float(np.linalg.norm(x_d - centre)) == pytest.approx(0.1, rel=1e-12)
    assert x_d[1] == pytest.approx(X0[1])


@pytest.mark.parametrize('t', [1.3, 4.0, 6.2, 9.9])
def test_half_circle_velocity_and_acceleration_are_derivatives(t: float) -> None:
    """Ẋ_d and Ẍ_d match finite differences of X_d and Ẋ_d."""
    ref = HalfCircleReference(radius=0.1, duration=10.0, start_delay=1.0)
    _, v_d, a_d = ref.evaluate(t, X0)
    np.testing.assert_allclose(
        v_d, numerical_derivative(lambda s: ref.evaluate(s, X0)[0], t), atol=1e-9
    )
    np.testing.assert_allclose(
        a_d, numerical_derivative(lambda s: ref.evaluate(s, X0)[1], t), atol=1e-8
    )


def test_sweep_parallel_to_the_wall_normal_is_rejected() -> None:
    """A diameter along n gives no circle: the parameter error names the sweep direction."""
    with pytest.raises(ControlParameterError, match=r'reference\.sweep_direction'):
        HalfCircleReference(toward=(1.0, 0.0, 0.0), sweep=(2.0, 0.0, 0.0))


def run_setpoint(setpoint: ForceSetpoint, samples: list[tuple[float, float, float, float, float]]):  # type: ignore[no-untyped-def]
    """Feed (t, f_normal, x_normal, x_d_normal) samples; return the outputs."""
    return [setpoint.update(*sample) for sample in samples]


def test_force_setpoint_is_zero_before_contact() -> None:
    """Without contact force the desired force stays zero (free motion)."""
    setpoint = ForceSetpoint(150.0, 2.0, 5.0)
    out = run_setpoint(setpoint, [(0.01 * k, 1.0, 1.7, 1.75, 0.0) for k in range(100)])
    assert all(s.f_d == 0.0 and s.phase == ForcePhase.IDLE for s in out)


def test_force_setpoint_ramps_smoothly_from_the_contact_force() -> None:
    """After contact F_d rises from the measured force to the set-point, Ḟ_d = 0 at both ends."""
    setpoint = ForceSetpoint(150.0, 2.0, 5.0)
    first = setpoint.update(1.0, 8.0, 1.78, 1.79, 0.01)
    middle = setpoint.update(2.0, 60.0, 1.78, 1.79, 0.01)
    end = setpoint.update(3.0, 150.0, 1.78, 1.79, 0.01)
    assert (first.f_d, first.f_d_dot, first.f_d_ddot) == (8.0, 0.0, 0.0)
    assert middle.f_d == pytest.approx((8.0 + 150.0) / 2.0)
    assert middle.f_d_dot == pytest.approx(1.875 * (150.0 - 8.0) / 2.0)
    assert (end.f_d, end.f_d_dot) == (150.0, 0.0)


def test_force_setpoint_derivatives_match_finite_differences() -> None:
    """Ḟ_d and F̈_d of the ramp are the derivatives of F_d (they feed eq. 39)."""
    setpoint = ForceSetpoint(150.0, 2.0, 5.0)
    setpoint.update(1.0, 5.0, 1.78, 1.79, 0.01)
    h = 1e-5
    values = {t: setpoint.update(t, 100.0, 1.78, 1.79, 0.01) for t in (1.7 - h, 1.7, 1.7 + h)}
    f_dot = (values[1.7 + h].f_d - values[1.7 - h].f_d) / (2 * h)
    f_ddot = (values[1.7 + h].f_d_dot - values[1.7 - h].f_d_dot) / (2 * h)
    assert values[1.7].f_d_dot == pytest.approx(f_dot, rel=1e-6)
    assert values[1.7].f_d_ddot == pytest.approx(f_ddot, rel=1e-5)


def test_force_setpoint_holds_while_the_reference_trails_at_contact() -> None:
    """A reference just behind the end effector when contact starts does not release."""
    setpoint = ForceSetpoint(150.0, 1.0, 5.0)
    out = run_setpoint(setpoint, [(0.001 * k, 6.0 + k, 1.7776, 1.7774, 0.02) for k in range(50)])
    assert all(s.phase == ForcePhase.RAMP_UP for s in out)


def test_force_setpoint_releases_when_the_reference_leaves_the_surface() -> None:
    """Once n·X_d falls behind the contact point, F_d ramps to zero and the phase ends."""
    setpoint = ForceSetpoint(150.0, 1.0, 5.0)
    setpoint.update(0.0, 6.0, 1.78, 1.80, 0.01)
    setpoint.update(2.0, 150.0, 1.78, 1.79, 0.01)
    release = setpoint.update(3.0, 150.0, 1.78, 1.77, -0.01)
    half = setpoint.update(3.5, 80.0, 1.78, 1.76, -0.01)
    done = setpoint.update(4.0, 10.0, 1.78, 1.75, -0.01)
    assert release.phase == ForcePhase.RELEASE
    assert release.f_d == 150.0
    assert half.f_d == pytest.approx(75.0)
    assert done.f_d == 0.0
    assert setpoint.phase == ForcePhase.IDLE


def test_force_setpoint_rearms_only_after_the_force_drops() -> None:
    """After a release, a new ramp needs the force to fall below half the threshold first."""
    setpoint = ForceSetpoint(150.0, 1.0, 5.0)
    setpoint.update(0.0, 6.0, 1.78, 1.80, 0.01)
    setpoint.update(1.0, 150.0, 1.78, 1.77, -0.01)
    setpoint.update(2.5, 8.0, 1.78, 1.75, -0.01)
    still_touching = setpoint.update(2.6, 8.0, 1.78, 1.75, -0.01)
    setpoint.update(2.7, 1.0, 1.70, 1.75, -0.01)
    new_contact = setpoint.update(2.8, 8.0, 1.80, 1.85, 0.01)
    assert still_touching.phase == ForcePhase.IDLE
    assert new_contact.phase == ForcePhase.RAMP_UP


@pytest.mark.parametrize(
    ('args', 'name'),
    [
        ((0.0, 1.0, 5.0), 'force_n'),
        ((150.0, -1.0, 5.0), 'force_ramp_s'),
        ((150.0, 1.0, 200.0), 'force.contact_threshold_n'),
        ((150.0, math.nan, 5.0), 'force_ramp_s'),
    ],
)
def test_invalid_force_setpoint_parameters_name_the_parameter(
    args: tuple[float, float, float], name: str
) -> None:
    """Non-positive set-point or ramp, or a threshold above the set-point, are rejected."""
    with pytest.raises(ControlParameterError, match=re.escape(name)):
        ForceSetpoint(*args)


def test_immediate_setpoint_ramps_from_zero_without_contact() -> None:
    """start_immediately (pure hybrid mode) ramps F_d from 0 at the first update, no contact."""
    setpoint = ForceSetpoint(150.0, 1.0, 5.0, start_immediately=True)
    first = setpoint.update(3.0, 0.0, 1.70, 1.70, 0.0)
    later = setpoint.update(4.0, 0.0, 1.70, 1.69, -0.01)
    assert (first.f_d, first.phase) == (0.0, ForcePhase.RAMP_UP)
    assert later.f_d == 150.0  # no contact point yet, so no release either


def test_release_ramps_from_the_current_force_to_zero_over_the_given_time() -> None:
    """release(t, 2 s) mid-ramp starts at the F_d of that instant, halves at 1 s, ends idle."""
    setpoint = ForceSetpoint(150.0, 1.0, 5.0, start_immediately=True)
    setpoint.update(0.0, 0.0, 1.70, 1.70, 0.0)
    f_at_release = setpoint.update(0.5, 0.0, 1.70, 1.70, 0.0).f_d
    setpoint.release(0.5, 2.0)
    start = setpoint.update(0.5, 0.0, 1.70, 1.70, 0.0)
    half = setpoint.update(1.5, 0.0, 1.70, 1.70, 0.0)
    done = setpoint.update(2.5, 0.0, 1.70, 1.70, 0.0)
    assert f_at_release == pytest.approx(75.0)
    assert (start.phase, start.f_d, start.f_d_dot) == (ForcePhase.RELEASE, f_at_release, 0.0)
    assert half.f_d == pytest.approx(f_at_release / 2.0)
    assert half.f_d_dot == pytest.approx(-1.875 * f_at_release / 2.0)
    assert done.f_d == 0.0
    assert setpoint.phase == ForcePhase.IDLE


def test_release_without_a_time_takes_the_ramp_time() -> None:
    """release(t) ramps down over ramp_time: half the set-point half a ramp later."""
    setpoint = ForceSetpoint(150.0, 2.0, 5.0, start_immediately=True)
    setpoint.update(0.0, 0.0, 1.70, 1.70, 0.0)
    setpoint.update(3.0, 0.0, 1.70, 1.70, 0.0)
    setpoint.release(3.0)
    assert setpoint.update(4.0, 0.0, 1.70, 1.70, 0.0).f_d == pytest.approx(75.0)
    assert setpoint.update(5.0, 0.0, 1.70, 1.70, 0.0).f_d == 0.0


def test_release_while_idle_does_nothing() -> None:
    """Without a ramp running there is nothing to release: F_d stays zero and idle."""
    setpoint = ForceSetpoint(150.0, 1.0, 5.0)
    setpoint.release(1.0, 0.5)
    sample = setpoint.update(1.2, 0.0, 1.70, 1.70, 0.0)
    assert (sample.f_d, sample.phase) == (0.0, ForcePhase.IDLE)


def test_a_task_taking_over_ramps_from_the_running_force() -> None:
    """start_force: a preempting task's set-point starts where the running one stood."""
    setpoint = ForceSetpoint(150.0, 1.0, 5.0, start_immediately=True, start_force=100.0)
    first = setpoint.update(0.0, 100.0, 1.0, 1.0, 0.0)
    assert first.f_d == 100.0 and first.f_d_dot == 0.0
    assert setpoint.update(1.0, 150.0, 1.0, 1.0, 0.0).f_d == pytest.approx(150.0)


@pytest.mark.parametrize('contact_first', [True, False])
def test_final_release_never_rearms(contact_first: bool) -> None:
    """release(final=True): F_d stays zero after the ramp, whatever contact follows.

    Also when released before any contact (a cancel while approaching): the back-off that then
    meets the surface must not ramp the force up (issue 28, finding 4).
    """
    fs = ForceSetpoint(magnitude=100.0, ramp_time=0.5, contact_threshold=5.0)
    if contact_first:
        fs.update(0.0, 10.0, 1.0, 1.0, 0.0)
        fs.update(1.0, 100.0, 1.0, 1.0, 0.0)
    fs.release(1.0, 0.5, final=True)
    samples = [fs.update(1.0 + 0.01 * k, force, 1.0, 1.0, 0.0).f_d
               for k, force in enumerate([100.0] * 60 + [0.0] * 20 + [50.0] * 100)]
    assert samples[-1] == 0.0 and fs.phase == ForcePhase.IDLE and fs.final
    assert all(f == 0.0 for f in samples[60:])
