"""Ocean current: speed and direction as mean-reverting first-order Gauss-Markov processes.

Fossen (2011), Handbook of Marine Craft Hydrodynamics and Motion Control, sec. 8.3 models the
current speed V_c as a first-order Gauss-Markov process, V_c_dot + mu V_c = w, and the 3-D
current by its speed and two angles. Here each of the speed V, the horizontal direction beta
and the vertical angle alpha relaxes toward its mean x_bar with the time constant T
(mu = 1 / T) and is driven by white noise scaled so that its stationary standard deviation is
sigma. The process is discretized exactly (the Ornstein-Uhlenbeck transition over a step h):

    x_{k+1} = x_bar + e^{-h/T} (x_k - x_bar) + sigma sqrt(1 - e^{-2h/T}) n_k,  n_k ~ N(0, 1),

so that its mean x_bar, variance sigma^2 and lag-tau autocorrelation e^{-tau/T} do not depend
on the step (unlike an Euler step with unscaled noise). The speed is clipped to
[0, V_max]. The velocity of the water in map_ned (NED: x north, y east, z down) is

    v_c = V [cos(alpha) cos(beta), cos(alpha) sin(beta), sin(alpha)],

beta measured from north toward east, alpha positive downward (this is the direction of the
flow, where the water goes; Fossen's sec. 8.3 writes the 3-D current with angle of attack and
sideslip instead, which for alpha = 0 is the same horizontal current).
Pure numpy; seeded, so the same seed gives the same current.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import NDArray

from uvms_model.errors import ParameterError

FloatArray = NDArray[np.float64]

#: Added to the simulator's seed, so the current's noise is not the sensor's noise sequence.
CURRENT_SEED_STREAM = 30


@dataclass(frozen=True)
class CurrentParameters:
    """The ocean current's process (Fossen 2011, sec. 8.3); all zero means still water.

    Attributes:
        mean_speed_m_s: Mean speed V_bar (m/s), in [0, max_speed_m_s].
        direction_rad: Mean horizontal direction beta_bar of the flow in map_ned, from north
            toward east (rad), in [-2 pi, 2 pi].
        vertical_angle_rad: Mean vertical angle alpha_bar of the flow, positive down (rad),
            in [-pi/2, pi/2].
        sigma_m_s: Stationary standard deviation of the speed (m/s), in [0, 5].
        direction_sigma_rad: Stationary standard deviation of beta (rad), in [0, pi].
        vertical_angle_sigma_rad: Stationary standard deviation of alpha (rad), in [0, pi/2].
        time_constant_s: Correlation time T of the three processes (s), in [0.01, 1e6].
        max_speed_m_s: Upper clip V_max of the speed (m/s), in [0, 10].
    """

    mean_speed_m_s: float = 0.0
    direction_rad: float = 0.0
    vertical_angle_rad: float = 0.0
    sigma_m_s: float = 0.0
    direction_sigma_rad: float = 0.0
    vertical_angle_sigma_rad: float = 0.0
    time_constant_s: float = 60.0
    max_speed_m_s: float = 2.0

    def __post_init__(self) -> None:
        """Check every value against its range (ParameterError naming it)."""
        for item in fields(self):
            value = getattr(self, item.name)
            low, high = CURRENT_RANGES[item.name]
            if not (isinstance(value, int | float) and math.isfinite(value)
                    and low <= value <= high):
                raise ParameterError(
                    f'ocean.current.{item.name} = {value!r} out of range [{low:g}, {high:g}]')
        if self.mean_speed_m_s > self.max_speed_m_s:
            raise ParameterError(
                f'ocean.current.mean_speed_m_s = {self.mean_speed_m_s!r} exceeds '
                f'ocean.current.max_speed_m_s = {self.max_speed_m_s!r}')

    @property
    def enabled(self) -> bool:
        """False for still water: no mean speed and no speed noise."""
        return self.mean_speed_m_s > 0.0 or self.sigma_m_s > 0.0


#: Valid range [low, high] of each field of CurrentParameters.
CURRENT_RANGES: dict[str, tuple[float, float]] = {
    'mean_speed_m_s': (0.0, 10.0),
    'direction_rad': (-2.0 * math.pi, 2.0 * math.pi),
    'vertical_angle_rad': (-0.5 * math.pi, 0.5 * math.pi),
    'sigma_m_s': (0.0, 5.0),
    'direction_sigma_rad': (0.0, math.pi),
    'vertical_angle_sigma_rad': (0.0, 0.5 * math.pi),
    'time_constant_s': (0.01, 1.0e6),
    'max_speed_m_s': (0.0, 10.0),
}


def current_velocity_ned(speed: float, direction: float, vertical_angle: float) -> FloatArray:
    """v_c (3,) in map_ned (m/s) of speed V, direction beta (from north toward east), alpha.

    >>> current_velocity_ned(0.2, math.pi / 2, 0.0).round(12).tolist()
    [0.0, 0.2, 0.0]
    """
    horizontal = speed * math.cos(vertical_angle)
    return np.array([horizontal * math.cos(direction), horizontal * math.sin(direction),
                     speed * math.sin(vertical_angle)])


def gauss_markov_step(
    x: float, mean: float, sigma: float, decay: float, noise: float
) -> float:
    """One exact step x_bar + a (x - x_bar) + sigma sqrt(1 - a^2) n of the process (a = e^{-h/T}).

    >>> gauss_markov_step(1.0, 0.0, 0.0, 0.5, 3.0)
    0.5
    """
    return mean + decay * (x - mean) + sigma * math.sqrt(1.0 - decay * decay) * noise


class OceanCurrent:
    """The current as it evolves: speed, direction and vertical angle, stepped exactly.

    It starts at the means. ``configure`` replaces the parameters and restarts the process at
    the new means (a user who sets a new mean at run time sees it at once, not after T).

    Args:
        params: The process's parameters.
        seed: Seed of its noise (the simulator passes ``sensor.seed``: the scenario's seed).

    Example:
        >>> current = OceanCurrent(CurrentParameters(mean_speed_m_s=0.2, sigma_m_s=0.05), 1)
        >>> current.step(0.001)
        >>> bool(0.0 <= current.speed_m_s <= 2.0)
        True
    """

    def __init__(self, params: CurrentParameters | None = None, seed: int = 0) -> None:
        self._rng = np.random.default_rng([int(seed), CURRENT_SEED_STREAM])
        self.configure(params if params is not None else CurrentParameters())

    def configure(self, params: CurrentParameters) -> None:
        """Take new parameters; the process restarts at their means."""
        self.params = params
        self.speed_m_s = params.mean_speed_m_s
        self.direction_rad = params.direction_rad
        self.vertical_angle_rad = params.vertical_angle_rad
        self._velocity = current_velocity_ned(
            self.speed_m_s, self.direction_rad, self.vertical_angle_rad)

    @property
    def enabled(self) -> bool:
        """False in still water (the dynamics then take no current at all)."""
        return self.params.enabled

    @property
    def velocity_ned(self) -> FloatArray:
        """v_c (3,) in map_ned (m/s), a copy."""
        return self._velocity.copy()

    def step(self, h: float) -> None:
        """Advance the three processes by h seconds (three N(0, 1) draws, always)."""
        p = self.params
        if not p.enabled:
            return
        decay = math.exp(-h / p.time_constant_s)
        n_speed, n_direction, n_vertical = self._rng.standard_normal(3).tolist()
        speed = gauss_markov_step(self.speed_m_s, p.mean_speed_m_s, p.sigma_m_s, decay, n_speed)
        self.speed_m_s = min(max(speed, 0.0), p.max_speed_m_s)
        self.direction_rad = gauss_markov_step(
            self.direction_rad, p.direction_rad, p.direction_sigma_rad, decay, n_direction)
        self.vertical_angle_rad = gauss_markov_step(
            self.vertical_angle_rad, p.vertical_angle_rad, p.vertical_angle_sigma_rad, decay,
            n_vertical)
        self._velocity = current_velocity_ned(
            self.speed_m_s, self.direction_rad, self.vertical_angle_rad)
