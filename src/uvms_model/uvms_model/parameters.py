"""UVMS parameters that are not the robot's body: environment, switches, thrusters, sensor, wall.

The robot itself (masses, dimensions, mount point, joint axes, frames) is its URDF, and its
hydrodynamic parameters sit beside it (``uvms_description``); ``description.*`` says where
they are. Each group here is a frozen dataclass whose fields carry a description with the
unit and the valid range; ``PARAMETER_SPECS`` lists them under flat dotted names
(``contact.stiffness_n_m``) with ROS-parameter-typed defaults, and ``config/robot.yaml`` holds
the same values as a ROS 2 parameter file. ``docs/model.md`` gives the source or the reason of
every value.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from uvms_model.errors import ParameterError
from uvms_model.parameter_fields import _coerce, _Group, _kind, _param

ParameterValue = float | int | bool | str | list[float] | list[str]
"""A value a ROS 2 parameter can hold, as used here."""


class ParameterSpec(NamedTuple):
    """One parameter: flat dotted name, default, description with unit, and valid range."""

    name: str
    default: ParameterValue
    description: str
    min_value: float | None
    max_value: float | None


@dataclass(frozen=True)
class DescriptionParameters(_Group):
    """Where the robot description is: the URDF and the hydrodynamic parameters beside it.

    The URDF is the one source of the kinematics and inertia (masses, dimensions, mount
    point, joint axes, frames); the hydrodynamics file holds added-mass models, drag
    coefficients, buoyancy ratio and centre, keyed by link name. Empty: the files of the
    uvms_description package (``urdf/uvms.urdf``, ``config/hydrodynamics.yaml``).
    """

    _group = 'description'

    urdf_path: str = _param(
        '', "Path of the robot's URDF; empty for uvms_description's urdf/uvms.urdf."
    )
    hydrodynamics_path: str = _param(
        '',
        'Path of the hydrodynamic parameters (YAML keyed by link name); empty for '
        "uvms_description's config/hydrodynamics.yaml.",
    )


@dataclass(frozen=True)
class HydrodynamicsParameters(_Group):
    """Water, gravity and switches of the hydrodynamic effects (off: rigid bodies in vacuum)."""

    _group = 'hydrodynamics'

    water_density_kg_m3: float = _param(1025.0, 'Sea water density rho (kg/m^3).', 0.0, 2000.0)
    gravity_m_s2: float = _param(
        9.81, 'Gravitational acceleration g (m/s^2), +z of map_ned.', 0.0, 100.0
    )
    added_mass_enabled: bool = _param(True, 'Include added mass and its Coriolis terms.')
    drag_enabled: bool = _param(True, 'Include linear and quadratic drag of hull and links.')
    buoyancy_enabled: bool = _param(True, 'Include buoyancy of hull and links.')
    drag_strips_per_link: int = _param(
        12,
        'Gauss-Legendre strips per link for the cross-flow drag integral (-).',
        1,
        200,
    )


_DEFAULT_THRUSTER_POSITIONS = (
    # Horizontal, vectored at 45 deg at the corners (front right, front left, rear right,
    # rear left), then vertical (same order).
    0.35, 0.25, 0.0,
    0.35, -0.25, 0.0,
    -0.35, 0.25, 0.0,
    -0.35, -0.25, 0.0,
    0.25, 0.3, 0.0,
    0.25, -0.3, 0.0,
    -0.25, 0.3, 0.0,
    -0.25, -0.3, 0.0,
)  # fmt: skip
_S45 = math.sqrt(0.5)
_DEFAULT_THRUSTER_DIRECTIONS = (
    _S45, -_S45, 0.0,
    _S45, _S45, 0.0,
    _S45, _S45, 0.0,
    _S45, -_S45, 0.0,
    0.0, 0.0, 1.0,
    0.0, 0.0, 1.0,
    0.0, 0.0, 1.0,
    0.0, 0.0, 1.0,
)  # fmt: skip


@dataclass(frozen=True)
class ThrusterParameters(_Group):
    """Thruster layout for the configuration matrix E (paper eq. 9); the paper gives none."""

    _group = 'thrusters'

    positions_m: tuple[float, ...] = _param(
        _DEFAULT_THRUSTER_POSITIONS,
        'Thruster positions in base_link_frd (m), flat x, y, z per thruster; default: 4 '
        'horizontal vectored thrusters at the corners, 4 vertical ones.',
        -100.0,
        100.0,
        multiple_of=3,
    )
    directions: tuple[float, ...] = _param(
        _DEFAULT_THRUSTER_DIRECTIONS,
        'Unit thrust direction of each thruster in base_link_frd (-), flat, 3 per thruster; '
        'positive thrust pushes the vehicle along it.',
        -1.0,
        1.0,
        multiple_of=3,
    )
    max_thrust_n: tuple[float, ...] = _param(
        (200.0,) * 8,
        'Maximum thrust magnitude of each thruster (N).',
        0.0,
        1e6,
    )

    def _check(self) -> None:
        count = len(self.positions_m) // 3
        if count < 6:
            raise ParameterError(
                f'thrusters.positions_m describes {count} thrusters, expected at least 6 '
                '(paper sec. 3.3: p >= 6)'
            )
        if len(self.directions) != len(self.positions_m):
            raise ParameterError(
                f'thrusters.directions has {len(self.directions)} elements, expected '
                f'{len(self.positions_m)} (3 per thruster, as thrusters.positions_m)'
            )
        if len(self.max_thrust_n) != count:
            raise ParameterError(
                f'thrusters.max_thrust_n has {len(self.max_thrust_n)} elements, expected '
                f'{count} (one per thruster)'
            )
        for i in range(count):
            d = self.directions[3 * i : 3 * i + 3]
            norm = math.sqrt(sum(a * a for a in d))
            if abs(norm - 1.0) > 1e-3:
                raise ParameterError(
                    f'thrusters.directions: direction of thruster {i} = {list(d)!r} has norm '
                    f'{norm:.6g}, expected a unit vector'
                )
        positions = np.reshape(self.positions_m, (count, 3))
        directions = np.reshape(self.directions, (count, 3))
        wrenches = np.vstack((directions.T, np.cross(positions, directions).T))
        rank = int(np.linalg.matrix_rank(wrenches))
        if rank < 6:
            raise ParameterError(
                f'thrusters.positions_m and thrusters.directions give thrust wrenches of rank '
                f'{rank}, expected 6: the configuration matrix E (paper eq. 9) needs full row rank'
            )


@dataclass(frozen=True)
class SensorParameters(_Group):
    """Wrist force/torque sensor (JR3-like, paper sec. 5.2 Case II; DESIGN.md)."""

    _group = 'sensor'

    force_range_n: tuple[float, ...] = _param(
        (400.0, 400.0, 400.0),
        'Full-scale force range per sensor axis (N); 400 N leaves room for the 150 N '
        'set-point along any sensor axis.',
        1e-3,
        1e7,
        length=3,
    )
    torque_range_n_m: tuple[float, ...] = _param(
        (40.0, 40.0, 40.0),
        'Full-scale torque range per sensor axis (N m).',
        1e-3,
        1e7,
        length=3,
    )
    noise_fraction: float = _param(
        0.0,
        "Gaussian noise standard deviation as a fraction of each axis' range (-); Case II of "
        'the paper uses 0.001 (JR3: 0.1 % of range).',
        0.0,
        1.0,
    )
    cutoff_hz: float = _param(
        0.0,
        'First-order low-pass cut-off of the output (Hz); 0 disables the filter.',
        0.0,
        1e6,
    )
    seed: int = _param(0, 'Seed of the noise generator (-).', 0, 2**31 - 1)


@dataclass(frozen=True)
class ContactParameters(_Group):
    """Wall normal to map_ned x (paper sec. 5.1 and 5.2)."""

    _group = 'contact'

    wall_position_m: float = _param(
        1.7771, 'Initial wall position along map_ned x (m); paper sec. 5.1.', -1e4, 1e4
    )
    stiffness_n_m: float = _param(
        1e4, 'Wall stiffness K_e (N/m); paper Case I: 1e4 and 1e5.', 1.0, 1e10
    )
    damping_n_s_m: float = _param(
        0.0, "Wall damping (N s/m); the paper's wall is a pure spring.", 0.0, 1e8
    )
    wall_speed_m_s: float = _param(
        0.0,
        'Speed of the wall along +x of map_ned after the first contact (m/s); paper Case '
        'III: 0.05.',
        -100.0,
        100.0,
    )


_INTEGRATORS = ('rk4', 'semi_implicit_euler')


@dataclass(frozen=True)
class IntegrationParameters(_Group):
    """Fixed-step integrator of (q, w)."""

    _group = 'integration'

    method: str = _param('rk4', "Integrator: 'rk4' or 'semi_implicit_euler'.")

    def _check(self) -> None:
        if self.method not in _INTEGRATORS:
            raise ParameterError(
                f'integration.method = {self.method!r} must be one of {list(_INTEGRATORS)!r}'
            )


_GROUPS: dict[str, type[_Group]] = {
    'description': DescriptionParameters,
    'hydrodynamics': HydrodynamicsParameters,
    'thrusters': ThrusterParameters,
    'sensor': SensorParameters,
    'contact': ContactParameters,
    'integration': IntegrationParameters,
}


def _to_ros(value: Any) -> ParameterValue:
    """Convert a field value to its ROS parameter type (tuples become lists)."""
    if isinstance(value, tuple):
        return list(value)
    return value  # type: ignore[no-any-return]


@dataclass(frozen=True)
class UvmsParameters:
    """All parameters of the UVMS model, grouped as in ``config/robot.yaml``."""

    description: DescriptionParameters = field(default_factory=DescriptionParameters)
    hydrodynamics: HydrodynamicsParameters = field(default_factory=HydrodynamicsParameters)
    thrusters: ThrusterParameters = field(default_factory=ThrusterParameters)
    sensor: SensorParameters = field(default_factory=SensorParameters)
    contact: ContactParameters = field(default_factory=ContactParameters)
    integration: IntegrationParameters = field(default_factory=IntegrationParameters)

    @classmethod
    def from_flat_dict(cls, values: Mapping[str, object]) -> UvmsParameters:
        """Build parameters from flat dotted names; names not given keep their defaults.

        Args:
            values: Mapping such as ``{'contact.stiffness_n_m': 1e5, 'sensor.force_range_n':
                [400.0, 400.0, 400.0]}``, with ROS parameter types (lists for arrays).

        Returns:
            The validated parameters.

        Raises:
            ParameterError: For an unknown name, a wrong type or list length, or a value out
                of range; the message names the parameter and the valid range.
        """
        grouped: dict[str, dict[str, Any]] = {group: {} for group in _GROUPS}
        kinds = {spec.name: _kind(_field_default(spec.name)) for spec in PARAMETER_SPECS}
        for name, value in values.items():
            if name not in kinds:
                raise ParameterError(f'unknown parameter {name!r}; known: {sorted(kinds)!r}')
            group, key = name.split('.', 1)
            grouped[group][key] = _coerce(name, kinds[name], value)
        groups: dict[str, Any] = {
            group: _GROUPS[group](**kwargs) for group, kwargs in grouped.items()
        }
        return cls(**groups)

    def to_flat_dict(self) -> dict[str, ParameterValue]:
        """Flat dotted names to ROS-typed values; the inverse of ``from_flat_dict``."""
        flat: dict[str, ParameterValue] = {}
        for group in _GROUPS:
            params = getattr(self, group)
            for item in dataclasses.fields(params):
                flat[f'{group}.{item.name}'] = _to_ros(getattr(params, item.name))
        return flat

    def updated(self, values: Mapping[str, object]) -> UvmsParameters:
        """Copy with the given flat dotted names changed (validated as ``from_flat_dict``)."""
        return UvmsParameters.from_flat_dict({**self.to_flat_dict(), **values})

    def without_hydrodynamics(self) -> UvmsParameters:
        """Copy with added mass, drag and buoyancy off: rigid bodies under gravity only."""
        return self.updated(
            {
                'hydrodynamics.added_mass_enabled': False,
                'hydrodynamics.drag_enabled': False,
                'hydrodynamics.buoyancy_enabled': False,
            }
        )


def _field_default(name: str) -> Any:
    """Default value of the field behind a flat dotted name."""
    group, key = name.split('.', 1)
    for item in dataclasses.fields(_GROUPS[group]):  # type: ignore[arg-type]
        if item.name == key:
            return item.default
    raise ParameterError(f'unknown parameter {name!r}')  # pragma: no cover


def _build_specs() -> list[ParameterSpec]:
    """List every parameter with its ROS-typed default, description and range."""
    specs = []
    for group, cls in _GROUPS.items():
        for item in dataclasses.fields(cls):  # type: ignore[arg-type]
            specs.append(
                ParameterSpec(
                    name=f'{group}.{item.name}',
                    default=_to_ros(item.default),
                    description=item.metadata['description'],
                    min_value=item.metadata['min'],
                    max_value=item.metadata['max'],
                )
            )
    return specs


PARAMETER_SPECS: list[ParameterSpec] = _build_specs()
"""Every model parameter as (name, default, description, min, max), for ROS declarations."""
