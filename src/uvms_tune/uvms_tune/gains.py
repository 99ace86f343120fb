"""From searched gains to controller parameters and back, and their stability before any run.

A candidate is a mapping of the tune file's gain names to numbers. ``controller_values``
turns it into controller parameters over a base (the robot's hand-tuned gains): a list
parameter (``impedance.inertia_kg``, ``hybrid.position_kp``) takes the value on every entry,
and the impedance's natural frequency ω_n and damping ratio ζ give K = P ω_n² and
B_d = 2 ζ P ω_n (per axis, with P the inertia in effect). ``stability`` runs the sampled-loop
check of ``gain_stability`` (paper eq. 24, 29-39) on the result.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from uvms_description.robots import robot_parameters
from uvms_tune.control_api import (
    CONTROLLER_PARAMETER_SPECS,
    ControllerParameters,
    ControlParameterError,
    loop_radii,
)
from uvms_tune.tune_file import DERIVED, GainRange

_SPEC_NAMES = {spec.name for spec in CONTROLLER_PARAMETER_SPECS}
_OMEGA, _ZETA = 'impedance.natural_frequency_rad_s', 'impedance.damping_ratio'


def spec_defaults() -> dict[str, Any]:
    """The controller's documented defaults (its parameter specs), flat dotted names."""
    return {spec.name: spec.default for spec in CONTROLLER_PARAMETER_SPECS}


def hand_tuned(robot: str) -> dict[str, Any]:
    """Robot ``robot``'s hand-tuned controller parameters (robots/NAME/controller.yaml)."""
    return {key: item.value for key, item in robot_parameters(robot, 'controller').items()
            if key in _SPEC_NAMES}


def controller_values(candidate: Mapping[str, float], base: Mapping[str, Any]) -> dict[str, Any]:
    """The controller parameters a candidate sets, over ``base`` (only those it changes).

    Args:
        candidate: Tune-file gain name to value.
        base: Flat controller parameters the candidate starts from (defaults, hand-tuned).
    """
    merged = {**spec_defaults(), **base}
    values: dict[str, Any] = {}
    for name, value in candidate.items():
        if name in DERIVED:
            continue
        current = merged[name]
        values[name] = ([float(value)] * len(current) if isinstance(current, list)
                        else float(value))
    if _OMEGA in candidate or _ZETA in candidate:
        inertia = values.get('impedance.inertia_kg', merged['impedance.inertia_kg'])
        omega_now, zeta_now = impedance_figures(merged)
        omega = float(candidate.get(_OMEGA, omega_now))
        zeta = float(candidate.get(_ZETA, zeta_now))
        values['impedance.stiffness_n_m'] = [_round(p * omega ** 2) for p in inertia]
        values['impedance.damping_n_s_m'] = [_round(2.0 * zeta * p * omega) for p in inertia]
    return values


def _round(value: float) -> float:
    """``value`` to 12 significant digits: 3000, not 3000.0000000000005, in a parameter file."""
    return float(f'{value:.12g}')


def impedance_figures(values: Mapping[str, Any]) -> tuple[float, float]:
    """ω_n = sqrt(K/P) (rad/s) and ζ = B_d / (2 sqrt(K P)) of the first axis of ``values``."""
    p = float(values['impedance.inertia_kg'][0])
    k = float(values['impedance.stiffness_n_m'][0])
    b = float(values['impedance.damping_n_s_m'][0])
    return math.sqrt(k / p), b / (2.0 * math.sqrt(k * p))


def as_candidate(values: Mapping[str, Any], gains: tuple[GainRange, ...]) -> dict[str, float]:
    """The searched gains of a full parameter set, clipped into their ranges (a baseline).

    A list parameter gives its first entry; ω_n and ζ come from P, K and B_d's first axis.
    """
    merged = {**spec_defaults(), **values}
    omega, zeta = impedance_figures(merged)
    candidate = {}
    for gain in gains:
        if gain.name == _OMEGA:
            value = omega
        elif gain.name == _ZETA:
            value = zeta
        else:
            current = merged[gain.name]
            value = float(current[0] if isinstance(current, list) else current)
        candidate[gain.name] = min(max(value, gain.low), gain.high)
    return candidate


@dataclass(frozen=True)
class Stability:
    """The sampled-loop check of one parameter set.

    Attributes:
        margin: 1 - the largest spectral radius of its loops (> 0: stable).
        loop: The loop with the largest radius, or the parameter refusal's message.
    """

    margin: float
    loop: str

    @property
    def stable(self) -> bool:
        """All loops have ρ < 1 (the null space may sit at 1: a zero gain)."""
        return self.margin > -1e-9


def stability(values: Mapping[str, Any], period_s: float,
              max_stiffness_n_m: float | None) -> Stability:
    """Check a controller parameter set as the controller does before it takes gains.

    Args:
        values: Flat controller parameters (defaults fill the rest).
        period_s: The control period T (s).
        max_stiffness_n_m: Stiffest wall to hold (N/m); None: the parameters'
            ``stability.max_environment_stiffness_n_m``.

    The task-space inertia is isotropic here (the controller checks again with its own M̃);
    a value the parameter specs refuse is unstable with margin -1 and the refusal as loop.
    """
    try:
        params = ControllerParameters.from_flat_dict(values)
    except ControlParameterError as exc:
        return Stability(-1.0, f'refused: {exc}')
    stiffness = (params.max_environment_stiffness if max_stiffness_n_m is None
                 else max(max_stiffness_n_m, params.max_environment_stiffness))
    radii = loop_radii(params, period_s, stiffness)
    worst = max(radii, key=lambda radius: radius.radius - radius.limit)
    return Stability(float(worst.limit - worst.radius), worst.loop)
