"""The pilot limits the input tools scale their demand by: the robot folder's ``pilot.*``.

Read with the controller's own loader (``uvms_control.core.pilot.limits``), so full stick or
a held key at the top gear asks for exactly what the controller allows; the controller still
clips whatever arrives.
"""

from __future__ import annotations

from uvms_pilot.command import PilotLimits


def pilot_limits(robot: str) -> PilotLimits:
    """The input tools' limits of a robot folder (name, or a path with a /).

    Raises:
        ValueError: The folder cannot be read or a limit is out of range (the message says
            which: ``RobotFolderError``, ``ControlParameterError``).
    """
    from uvms_control.core.pilot.limits import load_pilot_limits

    limits = load_pilot_limits(robot)
    return PilotLimits(vehicle_m_s=limits.vehicle_speed_m_s,
                       yaw_rad_s=limits.vehicle_rate_rad_s[2],
                       ee_m_s=limits.ee_speed_m_s, jaw_m_s=limits.jaw_speed_m_s)
