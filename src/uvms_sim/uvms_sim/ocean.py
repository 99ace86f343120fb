"""The simulator's ocean-current parameters ``ocean.current.*``: specs, ranges, validation.

The process itself is ``uvms_model.ocean_current`` (pure); the plant applies it
(``Plant.set_current``); ``uvms_sim.ocean_node`` declares these parameters on the simulator
node, applies run-time changes and publishes ``ocean/current``. Pure: no rclpy.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from uvms_model.ocean_current import CURRENT_RANGES, CurrentParameters

from uvms_model import ParameterError
from uvms_sim.errors import SimParameterError
from uvms_sim.parameters import ParameterSpec

PREFIX = 'ocean.current.'

_DESCRIPTIONS = {
    'mean_speed_m_s': 'Mean speed of the ocean current (m/s); 0 with sigma_m_s 0: still water.',
    'direction_rad': 'Mean direction the water flows toward in map_ned, from north toward east '
                     '(rad).',
    'vertical_angle_rad': 'Mean vertical angle of the flow, positive down (rad).',
    'sigma_m_s': 'Stationary standard deviation of the speed (m/s) (Gauss-Markov process).',
    'direction_sigma_rad': 'Stationary standard deviation of the direction (rad).',
    'vertical_angle_sigma_rad': 'Stationary standard deviation of the vertical angle (rad).',
    'time_constant_s': 'Correlation time T of speed, direction and vertical angle (s).',
    'max_speed_m_s': 'Upper clip of the speed (m/s).',
}

OCEAN_PARAMETERS: tuple[ParameterSpec, ...] = tuple(
    ParameterSpec(PREFIX + item.name, float(item.default), _DESCRIPTIONS[item.name],
                  *CURRENT_RANGES[item.name])
    for item in dataclasses.fields(CurrentParameters)
)
"""The ``ocean.current.*`` parameters of the simulator, defaults from CurrentParameters."""


def current_parameters(values: Mapping[str, Any]) -> CurrentParameters:
    """CurrentParameters from ``ocean.current.*`` values (missing names: defaults).

    Raises:
        SimParameterError: A value is not a number or out of its range, named.
    """
    fields = {}
    for spec in OCEAN_PARAMETERS:
        value = values.get(spec.name, spec.default)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise SimParameterError(f'parameter {spec.name!r} = {value!r}: expected a number; '
                                    f'valid: {spec.range_text()}')
        fields[spec.name[len(PREFIX):]] = float(value)
    try:
        return CurrentParameters(**fields)
    except ParameterError as exc:
        raise SimParameterError(f'invalid parameter {exc}') from exc
