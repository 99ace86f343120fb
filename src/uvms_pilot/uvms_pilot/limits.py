"""The pilot limits the input tools scale their demand by (the speed gear's 100 %).

The controller clips every twist to the robot's own pilot limits whatever arrives; these are
what full stick or a held key asks for. Until the robot folder carries the pilot limits (the
controller's loader, issue 51 item 1), the input tools use ``DEFAULT_LIMITS``: a BlueROV2
Heavy's gentle pool speeds and the controller's streamed-target speed for the arm.
"""

from __future__ import annotations

from uvms_pilot.command import PilotLimits

#: Surge, sway 0.3 m/s and heave 0.2 m/s, yaw 0.3 rad/s (17 deg/s); the end effector at
#: 0.05 m/s (controller.yaml safety.max_target_speed_m_s); the jaw at 0.01 m/s.
DEFAULT_LIMITS = PilotLimits(vehicle_m_s=(0.3, 0.3, 0.2), yaw_rad_s=0.3, ee_m_s=0.05,
                             jaw_m_s=0.01)
