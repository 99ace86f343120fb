"""Navigation sensor parameters: IMU with AHRS, DVL, depth sensor, USBL position fix.

Each group is a frozen dataclass whose fields carry a description with the unit and the
valid range (as ``uvms_model.parameters``); ``NAVIGATION_PARAMETER_SPECS`` lists them under
flat dotted names (``navigation.imu.gyro_noise_density``) for ROS declarations. A robot's
figures are its ``navigation.yaml`` (docs/robots.md gives the source of every value). The
defaults are the BlueROV2 class figures of that file.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from uvms_model.errors import ParameterError
from uvms_model.parameter_fields import _coerce, _Group, _kind, _param
from uvms_model.parameters import ParameterSpec, _to_ros

PREFIX = 'navigation'
"""Parameter name prefix of every navigation sensor parameter."""


@dataclass(frozen=True)
class ImuParameters(_Group):
    """MEMS IMU (angular rate, specific force) and its AHRS orientation output."""

    _group = 'navigation.imu'

    rate_hz: float = _param(200.0, 'Output rate of the IMU (Hz).', 1.0, 10000.0)
    gyro_noise_density: float = _param(
        7.0e-5, 'Gyro white noise density (rad/s/sqrt(Hz)); ICM-20602: 4 mdps/sqrt(Hz).',
        0.0, 1.0)
    gyro_bias_random_walk: float = _param(
        3.88e-5, 'Gyro bias random walk (rad/s^2/sqrt(Hz)) driving a first-order '
        'Gauss-Markov bias.', 0.0, 1.0)
    gyro_bias_time_constant_s: float = _param(
        1000.0, 'Gyro bias correlation time (s).', 1.0, 1.0e7)
    accel_noise_density: float = _param(
        9.8e-4, 'Accelerometer white noise density (m/s^2/sqrt(Hz)); ICM-20602: 100 '
        'ug/sqrt(Hz).', 0.0, 10.0)
    accel_bias_random_walk: float = _param(
        0.006, 'Accelerometer bias random walk (m/s^3/sqrt(Hz)).', 0.0, 10.0)
    accel_bias_time_constant_s: float = _param(
        300.0, 'Accelerometer bias correlation time (s).', 1.0, 1.0e7)
    roll_pitch_sigma_rad: float = _param(
        0.0087, 'AHRS roll and pitch error, standard deviation (rad).', 0.0, 1.0)
    yaw_sigma_rad: float = _param(
        0.052, 'AHRS yaw error, standard deviation (rad); a magnetometer near thrusters.',
        0.0, 3.0)
    ahrs_time_constant_s: float = _param(
        10.0, 'Correlation time of the AHRS errors (first-order Gauss-Markov) (s).',
        0.01, 1.0e6)


@dataclass(frozen=True)
class DvlParameters(_Group):
    """Doppler velocity log: bottom-track velocity in its own frame."""

    _group = 'navigation.dvl'

    position_m: tuple[float, ...] = _param(
        (0.0, 0.0, 0.0), 'DVL origin in base_link_frd (m).', -100.0, 100.0, length=3)
    orientation_rpy: tuple[float, ...] = _param(
        (0.0, 0.0, 0.0), 'DVL frame orientation relative to base_link_frd: roll, pitch, yaw '
        '(rad).', -7.0, 7.0, length=3)
    sigma_base_m_s: float = _param(
        0.005, 'Velocity noise std at rest, a in sigma = a + b |v| (m/s).', 0.0, 10.0)
    sigma_per_speed: float = _param(
        0.01, 'Velocity noise std per speed, b in sigma = a + b |v| (-).', 0.0, 1.0)
    min_altitude_m: float = _param(
        0.05, 'Smallest altitude with bottom lock (m).', 0.0, 1000.0)
    max_altitude_m: float = _param(
        50.0, 'Largest altitude with bottom lock (m).', 0.0, 10000.0)
    max_speed_m_s: float = _param(
        2.0, 'Largest speed the DVL measures (m/s); faster is invalid.', 0.0, 100.0)
    rate_altitude_breaks_m: tuple[float, ...] = _param(
        (0.6, 3.0, 14.0, 36.0), 'Altitudes (m) where the output rate changes, ascending.',
        0.0, 10000.0)
    rate_by_altitude_hz: tuple[float, ...] = _param(
        (15.0, 10.0, 5.5, 7.5, 3.0), 'Output rate (Hz) below the first break, between '
        'breaks, and above the last (one more value than breaks).', 0.1, 1000.0)

    def _check(self) -> None:
        breaks = self.rate_altitude_breaks_m
        if len(self.rate_by_altitude_hz) != len(breaks) + 1:
            msg = (f'{self._group}.rate_by_altitude_hz has {len(self.rate_by_altitude_hz)} '
                   f'values, expected {len(breaks) + 1} (one more than rate_altitude_breaks_m)')
            raise ParameterError(msg)
        if any(b <= a for a, b in itertools.pairwise(breaks)):
            raise ParameterError(f'{self._group}.rate_altitude_breaks_m = {list(breaks)!r} must '
                                 'ascend')
        if self.max_altitude_m <= self.min_altitude_m:
            raise ParameterError(f'{self._group}.max_altitude_m = {self.max_altitude_m!r} must '
                                 f'exceed min_altitude_m = {self.min_altitude_m!r}')


@dataclass(frozen=True)
class DepthParameters(_Group):
    """Pressure depth sensor (Bar30 class): depth + per-run bias + white noise."""

    _group = 'navigation.depth'

    rate_hz: float = _param(20.0, 'Output rate (Hz).', 0.1, 10000.0)
    sigma_m: float = _param(0.01, 'White noise std (m).', 0.0, 100.0)
    bias_max_m: float = _param(
        0.05, 'Per-run bias drawn uniformly in [-bias_max_m, bias_max_m] (m).', 0.0, 100.0)


@dataclass(frozen=True)
class PositionFixParameters(_Group):
    """Acoustic (USBL class) position fix in map_ned, optional."""

    _group = 'navigation.position_fix'

    enabled: bool = _param(False, 'Whether the position fix is measured and published.')
    rate_hz: float = _param(1.0, 'Output rate (Hz).', 0.01, 100.0)
    sigma_horizontal_m: float = _param(0.1, 'North and east noise std (m).', 0.0, 1000.0)
    sigma_vertical_m: float = _param(0.1, 'Down noise std (m).', 0.0, 1000.0)


@dataclass(frozen=True)
class NavigationSwitch(_Group):
    """Whether the simulator measures and publishes the navigation sensors."""

    _group = 'navigation'

    enabled: bool = _param(
        False, 'Whether the simulator measures and publishes imu, dvl, depth (and '
        'position_fix); off keeps recordings as they were.')


@dataclass(frozen=True)
class WorldParameters(_Group):
    """What of the world the navigation sensors see."""

    _group = 'world'

    seabed_depth_m: float = _param(
        0.0, 'Depth of a flat seabed in map_ned (m, z down); 0 for no seabed (no DVL bottom '
        'lock).', 0.0, 12000.0)


_GROUPS: dict[str, type[_Group]] = {
    'world': WorldParameters,
    'navigation': NavigationSwitch,
    'navigation.imu': ImuParameters,
    'navigation.dvl': DvlParameters,
    'navigation.depth': DepthParameters,
    'navigation.position_fix': PositionFixParameters,
}


@dataclass(frozen=True)
class NavigationParameters:
    """Every navigation sensor parameter, grouped as in a robot's ``navigation.yaml``.

    ``world.seabed_depth_m`` and ``navigation.enabled`` belong to the run (a scenario sets
    them), the other groups to the robot (its ``navigation.yaml``).
    """

    world: WorldParameters = field(default_factory=WorldParameters)
    switch: NavigationSwitch = field(default_factory=NavigationSwitch)
    imu: ImuParameters = field(default_factory=ImuParameters)
    dvl: DvlParameters = field(default_factory=DvlParameters)
    depth: DepthParameters = field(default_factory=DepthParameters)
    position_fix: PositionFixParameters = field(default_factory=PositionFixParameters)

    @classmethod
    def from_flat_dict(cls, values: Mapping[str, object]) -> NavigationParameters:
        """Build from flat dotted names (``navigation.dvl.sigma_base_m_s``); others default.

        Raises:
            ParameterError: An unknown name, a wrong type or length, a value out of range.
        """
        grouped: dict[str, dict[str, Any]] = {group: {} for group in _GROUPS}
        kinds = {spec.name: _kind(_default(spec.name)) for spec in NAVIGATION_PARAMETER_SPECS}
        for name, value in values.items():
            if name not in kinds:
                raise ParameterError(f'unknown parameter {name!r}; known: {sorted(kinds)!r}')
            group, key = name.rsplit('.', 1)
            grouped[group][key] = _coerce(name, kinds[name], value)
        built = {group: _GROUPS[group](**kwargs) for group, kwargs in grouped.items()}
        return cls(*(built[group] for group in _GROUPS))  # type: ignore[arg-type]

    def to_flat_dict(self) -> dict[str, Any]:
        """Flat dotted names to ROS-typed values; the inverse of ``from_flat_dict``."""
        flat: dict[str, Any] = {}
        for group, params in zip(_GROUPS, (self.world, self.switch, self.imu, self.dvl,
                                           self.depth, self.position_fix), strict=True):
            for item in dataclasses.fields(params):  # type: ignore[arg-type]
                flat[f'{group}.{item.name}'] = _to_ros(getattr(params, item.name))
        return flat


def _default(name: str) -> Any:
    group, key = name.rsplit('.', 1)
    return next(f.default for f in dataclasses.fields(_GROUPS[group])  # type: ignore[arg-type]
                if f.name == key)


def _specs() -> list[ParameterSpec]:
    return [ParameterSpec(f'{group}.{item.name}', _to_ros(item.default),
                          item.metadata['description'], item.metadata['min'],
                          item.metadata['max'])
            for group, cls in _GROUPS.items()
            for item in dataclasses.fields(cls)]  # type: ignore[arg-type]


NAVIGATION_PARAMETER_SPECS: list[ParameterSpec] = _specs()
"""Every navigation parameter as (name, default, description, min, max)."""
