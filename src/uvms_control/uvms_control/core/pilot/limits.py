"""The pilot limits of a robot: parameter specs, the values as one object, the loader.

The controller declares ``pilot.*`` (``PILOT_PARAMETER_SPECS``); a robot folder's
``controller.yaml`` gives its own values, and the input tools read the same values with
``load_pilot_limits`` (their speed gear scales them before they publish).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from uvms_common.parameter_spec import ParameterSpec

from uvms_control.core.errors import ControlParameterError

#: The deadman of the pilot interface (s): no pilot message for this long means zero velocity.
DEADMAN_S = 0.3

PILOT_PARAMETER_SPECS: list[ParameterSpec] = [
    ParameterSpec('pilot.max_vehicle_speed_m_s', [0.5, 0.5, 0.3],
                  'Largest vehicle body velocity a pilot may command, surge, sway, heave '
                  '(m/s, base_link_frd); a twist beyond it is scaled down whole.'),
    ParameterSpec('pilot.max_vehicle_rate_rad_s', [0.0, 0.0, 0.5],
                  'Largest vehicle body rate a pilot may command, roll, pitch, yaw (rad/s); '
                  '0 keeps that angle held.'),
    ParameterSpec('pilot.max_vehicle_acceleration_m_s2', 0.25,
                  'Rate limit of the commanded vehicle velocity (m/s^2): the pilot reference '
                  'never jumps.', 1e-3, 10.0),
    ParameterSpec('pilot.max_vehicle_angular_acceleration_rad_s2', 0.5,
                  'Rate limit of the commanded vehicle body rate (rad/s^2).', 1e-3, 20.0),
    ParameterSpec('pilot.max_ee_speed_m_s', [0.1, 0.1, 0.1],
                  'Largest end-effector velocity relative to the vehicle a pilot may command, '
                  'per axis of the frame it is given in (m/s).'),
    ParameterSpec('pilot.max_ee_acceleration_m_s2', 0.2,
                  'Rate limit of the commanded end-effector velocity (m/s^2).', 1e-3, 10.0),
    ParameterSpec('pilot.max_jaw_speed_m_s', 0.02,
                  'Largest jaw opening speed a pilot may command (m/s).', 0.0, 1.0),
    ParameterSpec('pilot.deadman_s', DEADMAN_S,
                  'No pilot message for this long means zero velocity, then hold; also the '
                  'oldest stamp a pilot message may carry (s).', 0.05, 2.0),
    ParameterSpec('pilot.refuse_during_contact', False,
                  'True: pilot input is refused while a task holds a contact (instead of '
                  'canceling the task, as a cancel does).'),
    ParameterSpec('pilot.script', '',
                  'Timed pilot commands played on the control clock (YAML text, '
                  "uvms_control.core.pilot.script; a scenario's pilot: key); empty: none."),
]


def _vector(values: Mapping[str, Any], name: str) -> tuple[float, float, float]:
    value = values[name]
    if not isinstance(value, Sequence) or len(value) != 3 or not all(
            isinstance(v, int | float) and math.isfinite(v) and v >= 0.0 for v in value):
        raise ControlParameterError(name, value, '3 finite values >= 0')
    return float(value[0]), float(value[1]), float(value[2])


@dataclass(frozen=True)
class PilotLimits:
    """What a pilot may command (SI units; names say which).

    Attributes:
        vehicle_speed_m_s: surge, sway, heave limits (m/s, base_link_frd).
        vehicle_rate_rad_s: roll, pitch, yaw rate limits (rad/s).
        vehicle_acceleration_m_s2: rate limit of the linear velocity (m/s^2).
        vehicle_angular_acceleration_rad_s2: rate limit of the body rates (rad/s^2).
        ee_speed_m_s: end-effector velocity limits per axis (m/s).
        ee_acceleration_m_s2: rate limit of the end-effector velocity (m/s^2).
        jaw_speed_m_s: jaw speed limit (m/s).
        deadman_s: silence that means zero velocity (s).
        refuse_during_contact: refuse pilot input while a task holds a contact.
    """

    vehicle_speed_m_s: tuple[float, float, float] = (0.5, 0.5, 0.3)
    vehicle_rate_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.5)
    vehicle_acceleration_m_s2: float = 0.25
    vehicle_angular_acceleration_rad_s2: float = 0.5
    ee_speed_m_s: tuple[float, float, float] = (0.1, 0.1, 0.1)
    ee_acceleration_m_s2: float = 0.2
    jaw_speed_m_s: float = 0.02
    deadman_s: float = DEADMAN_S
    refuse_during_contact: bool = False

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> PilotLimits:
        """From ``pilot.*`` values (missing names take the defaults of the specs).

        Raises:
            ControlParameterError: a limit that is not 3 finite values >= 0.
        """
        merged = {spec.name: spec.default for spec in PILOT_PARAMETER_SPECS} | dict(values)
        return cls(
            vehicle_speed_m_s=_vector(merged, 'pilot.max_vehicle_speed_m_s'),
            vehicle_rate_rad_s=_vector(merged, 'pilot.max_vehicle_rate_rad_s'),
            vehicle_acceleration_m_s2=float(merged['pilot.max_vehicle_acceleration_m_s2']),
            vehicle_angular_acceleration_rad_s2=float(
                merged['pilot.max_vehicle_angular_acceleration_rad_s2']),
            ee_speed_m_s=_vector(merged, 'pilot.max_ee_speed_m_s'),
            ee_acceleration_m_s2=float(merged['pilot.max_ee_acceleration_m_s2']),
            jaw_speed_m_s=float(merged['pilot.max_jaw_speed_m_s']),
            deadman_s=float(merged['pilot.deadman_s']),
            refuse_during_contact=bool(merged['pilot.refuse_during_contact']),
        )


def load_pilot_limits(robot: str) -> PilotLimits:
    """The pilot limits of a robot folder (its ``controller.yaml``; defaults where it is silent).

    Args:
        robot: a robot folder's name (``uvms_description``) or a path to one.

    Raises:
        RobotFolderError: the folder or its files cannot be read.
        ControlParameterError: a limit out of range.
    """
    from pathlib import Path

    from uvms_description.robots import robot_parameters

    path = Path(robot)
    values = (robot_parameters(path.name, 'controller', path.parent) if '/' in robot
              else robot_parameters(robot, 'controller'))
    return PilotLimits.from_parameters({name: item.value for name, item in values.items()
                                        if name.startswith('pilot.')})
