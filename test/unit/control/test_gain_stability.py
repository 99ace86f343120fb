"""Stability of the sampled loops decides which gains the controller takes (issue 28, item 7)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from uvms_control.core.errors import ControlParameterError
from uvms_control.core.law.gain_stability import (
    check_gain_stability,
    loop_radii,
    null_space_radius,
    spectral_radius,
)
from uvms_control.core.law.task_space import task_space_model_from_terms
from uvms_control.core.parameters import ControllerParameters

from uvms_model import UvmsModel

ROBOTS = Path(__file__).resolve().parents[3] / 'src' / 'uvms_description' / 'robots'
T = 0.002  # 500 Hz, the shipped control rate
K_E_MAX = 1.0e5  # the paper's stiffest wall
Q_WORK = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.477, -1.511])


def flat(tree: dict[str, Any], prefix: str = '') -> dict[str, Any]:
    """Flat dotted names of a nested parameter dict."""
    out: dict[str, Any] = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            out.update(flat(value, f'{prefix}{key}.'))
        else:
            out[f'{prefix}{key}'] = value
    return out


def shipped_gains(robot: str) -> ControllerParameters:
    """The controller gains of a robot folder (controller.yaml; safety, pilot limits aside)."""
    text = (ROBOTS / robot / 'controller.yaml').read_text()
    values = flat(yaml.safe_load(text)['/**/controller']['ros__parameters'])
    return ControllerParameters.from_flat_dict(
        {k: v for k, v in values.items() if not k.startswith(('safety.', 'pilot.'))})


def paper_task_inertia() -> np.ndarray:
    """M̃ of the paper robot at its working pose (point A), strongly anisotropic."""
    model = UvmsModel()
    terms = model.task_space_terms(Q_WORK, np.zeros(9))
    return task_space_model_from_terms(terms).M_tilde


@pytest.mark.parametrize('robot', ['paper_uvms', 'bluerov2_alpha5'])
@pytest.mark.parametrize('inertia', ['isotropic', 'paper robot at point A'])
def test_shipped_gains_of_both_robots_are_stable(robot: str, inertia: str) -> None:
    """Each robot's gains pass at 500 Hz on a 1e5 N/m wall, with either task-space inertia."""
    M = None if inertia == 'isotropic' else paper_task_inertia()
    check_gain_stability(shipped_gains(robot), T, K_E_MAX, M)
    radii = loop_radii(shipped_gains(robot), T, K_E_MAX, M)
    assert len(radii) == 5 and all(r.radius < 1.0 for r in radii)


@pytest.mark.parametrize(('change', 'named'), [
    ({'impedance.inertia_kg': [0.01] * 3}, 'impedance.inertia_kg'),
    ({'hybrid.force_kp': 1000.0}, 'hybrid.force_kp'),
    ({'impedance.stiffness_n_m': [1.0e9] * 3}, 'impedance.stiffness_n_m'),
], ids=['inertia-0.01kg', 'force-kp-1000', 'stiffness-1e9'])
def test_gains_of_an_unstable_sampled_loop_are_refused(change: dict[str, Any],
                                                       named: str) -> None:
    """The issue's three gain sets make a sampled loop diverge: refused, the gain named."""
    params = ControllerParameters.from_flat_dict(change)
    with pytest.raises(ControlParameterError, match=named) as error:
        check_gain_stability(params, T, K_E_MAX)
    assert 'spectral radius' in str(error.value)


def test_tiny_target_inertia_has_the_issue_radius() -> None:
    """P = 0.01 kg gives ρ ≈ 199 at 500 Hz in free motion (the review's figure), default 0.993."""
    tiny = ControllerParameters.from_flat_dict({'impedance.inertia_kg': [0.01] * 3})
    assert loop_radii(tiny, T, K_E_MAX)[0].radius == pytest.approx(199.6, abs=0.1)
    assert loop_radii(ControllerParameters.from_flat_dict(), T, K_E_MAX)[0].radius == \
        pytest.approx(0.9927, abs=1e-4)


def continuous_rate(params: ControllerParameters, stiffness: float) -> float:
    """Largest real part of the continuous hybrid loop along n and along the wall (1/s).

    Along n: ẍ = -K_fp K_e x + K_fi I - K_fv y, İ = -K_e x, τ ẏ = K_e ẋ - y (the dirty
    derivative); along the wall: ẍ = -K_pv ẋ - K_pp x (eq. 37).
    """
    kp, ki, kd = params.force_kp, params.force_ki, params.force_kd
    tau = 1.0 / (2.0 * np.pi * params.force_derivative_cutoff_hz)
    normal = np.array([[0.0, 1.0, 0.0, 0.0],
                       [-kp * stiffness, 0.0, ki, -kd],
                       [-stiffness, 0.0, 0.0, 0.0],
                       [0.0, stiffness / tau, 0.0, -1.0 / tau]])
    k, d = params.position_kp[1, 1], params.position_kd[1, 1]
    tangential = np.array([[0.0, 1.0], [-k, -d]])
    return max(float(np.max(np.linalg.eigvals(A).real)) for A in (normal, tangential))


@pytest.mark.parametrize('stiffness', [1.0e4, 1.0e5])
def test_sampled_hybrid_loop_tends_to_the_continuous_one_for_short_periods(
        stiffness: float) -> None:
    """For T -> 0, ρ(T) -> exp(T max Re λ) of the continuous PID/PD loops (independent oracle)."""
    params = ControllerParameters.from_flat_dict()
    period = 1e-5
    hybrid = loop_radii(params, period, stiffness)[2]
    assert hybrid.loop.startswith('blend W = 0 ')
    expected = np.exp(period * continuous_rate(params, stiffness))
    assert hybrid.radius == pytest.approx(expected, abs=1e-7)


def test_null_space_radius_of_an_undamped_or_fast_coordinate() -> None:
    """Zero gains leave a coordinate marginal (ρ = 1, accepted); K_n = 1e4 at 500 Hz diverges."""
    assert null_space_radius(0.0, 0.0, T) == pytest.approx(1.0)
    assert null_space_radius(4.0, 4.0, T) < 1.0
    assert null_space_radius(1.0e4, 1.0e4, T) > 1.0
    params = ControllerParameters.from_flat_dict({'null_space.damping_1_s': [1.0e4] * 9})
    with pytest.raises(ControlParameterError, match='null_space'):
        check_gain_stability(params, T, K_E_MAX)


def test_spectral_radius_of_a_rotation_is_one() -> None:
    """ρ is the largest |eigenvalue|, complex ones included."""
    assert spectral_radius(np.array([[0.0, -1.0], [1.0, 0.0]])) == pytest.approx(1.0)
