"""The physical side of the twins: PWM to thrust, motor current to joint torque.

A real vehicle turns the autopilot's PWM into thrust through its ESCs and propellers, and a
real arm turns a current setpoint into torque through its motors and gears. The twins stand
for those devices, so this module stands for that physics, from the same robot folder the
bridges read (no ROS)::

    thrusters = ThrusterTwin.for_robot('bluerov2_alpha5')
    thrust_n = thrusters.step(twin.servo_outputs_us(), voltage_v=16.0, dt_s=0.002)
    torques = joint_torques(arm.joint_commands(), arm.joint_torques_n_m(), state, limits)

PWM to thrust: Blue Robotics' published T200 curve (``t200_curve``, the same the bridge
inverts) gives the thrust each ESC is told to make, and the Healey model of the robot's
thrusters (``uvms_thrusters``, eq. 11-15) the thrust the propeller then makes. An output
with no pulse (0) is a stopped ESC: zero thrust.

Current to torque: a joint in Current mode makes I Kt N eta (``hardware_config.Drive``),
within the URDF's effort limit. How the arm's own servo follows a Velocity or Position
setpoint is not in Reach's documents, and a servo emulated here, stepped at this node's rate
(500 Hz, slower on a busy machine) on the light wrist links, went unstable (a joint at 50
rad/s within a second of the bridge's watchdog sending VELOCITY 0). So the twin makes no
torque in any mode but Current: the arm goes limp when the bridge stops driving it, which is
what the twin can honestly show; what the real arm does then is for the pool to tell.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from uvms_hardware.hardware_config import hardware_section, urdf_joint_limits
from uvms_hardware.reach_protocol import Mode
from uvms_hardware.t200_curve import T200Curve
from uvms_thrusters.robot_thrusters import robot_thrusters
from uvms_thrusters.thruster_dynamics import ThrusterBank


@dataclass
class ThrusterTwin:
    """The vehicle's ESCs and propellers: servo outputs (PWM) to actual thrusts (N)."""

    curve: T200Curve
    channels: tuple[int, ...]
    directions: tuple[float, ...]
    bank: ThrusterBank

    @classmethod
    def for_robot(cls, robot_name: str) -> ThrusterTwin:
        """From the robot folder: hardware.yaml's ardusub section, thrusters.yaml's model."""
        _, section = hardware_section(robot_name, 'ardusub')
        layout, model = robot_thrusters(robot_name)
        channels = tuple(int(c) for c in section['thruster_channels'])
        directions = tuple(float(d) for d in section['thruster_directions'])
        if len(channels) != layout.count or len(directions) != layout.count:
            raise ValueError(f'{robot_name} hardware.yaml ardusub: {len(channels)} channels '
                             f'and {len(directions)} directions for {layout.count} thrusters')
        return cls(T200Curve.from_section(section['t200']), channels, directions,
                   ThrusterBank(model, layout.count))

    def desired_thrust_n(self, outputs_us: Sequence[int], voltage_v: float) -> np.ndarray:
        """What each ESC is told: thrust along our positive direction (N); no pulse: none."""
        pwm = np.array([outputs_us[channel - 1] for channel in self.channels], float)
        thrust = self.curve.thrusts_from_pwm(pwm, voltage_v) * np.array(self.directions)
        return np.where(pwm > 0.0, thrust, 0.0)

    def step(self, outputs_us: Sequence[int], voltage_v: float, dt_s: float) -> np.ndarray:
        """Actual thrusts (N) after ``dt_s`` of the propellers' dynamics (eq. 11-15)."""
        return self.bank.step(self.desired_thrust_n(outputs_us, voltage_v), dt_s)


def effort_limits_n_m(robot_name: str) -> dict[str, float]:
    """The URDF's effort limit of each joint (N m; inf where the URDF gives none)."""
    return {joint: limits[3] if limits[3] > 0.0 else math.inf
            for joint, limits in urdf_joint_limits(robot_name).items()}


def joint_torques(commands: Mapping[str, tuple[Mode, float]],
                  current_torques: Mapping[str, float | None],
                  effort_limits: Mapping[str, float]) -> dict[str, float]:
    """Torque (N m) each arm joint makes: its Current-mode torque, else none (limp).

    Args:
        commands: joint -> (mode, setpoint) from the arm twin (rad, rad/s or mA).
        current_torques: joint -> torque of a Current-mode setpoint (I Kt N eta), else None.
        effort_limits: joint -> the URDF's effort limit (N m).
    """
    torques = {}
    for joint, (mode, _) in commands.items():
        torque = (current_torques.get(joint) or 0.0) if mode == Mode.CURRENT else 0.0
        limit = effort_limits.get(joint, math.inf)
        torques[joint] = float(np.clip(torque, -limit, limit))
    return torques
