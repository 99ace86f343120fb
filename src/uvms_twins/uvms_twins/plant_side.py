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
within the URDF's effort limit. Velocity mode is the device following its speed setpoint
(Reach's document: VELOCITY is a speed, clamped at the limit), so `ArmServo` follows it: a
PI loop on the speed (a PD on the integrated setpoint) whose gains come from each joint's
effective inertia where the arm is (`JointInertia`) and one bandwidth, so that every
joint, the 0.17 g m^2 wrist as the 30 g m^2 shoulder, responds alike and stays stable with
the twin's few milliseconds of loop delay. A fixed-gain servo tried earlier on the light wrist
links went unstable (50 rad/s within a second of a VELOCITY 0); limp instead, the arm flailed
after every trip of the bridge (2-17 rad/s, the wrist 130 turns in a minute, measured on the
twin stand) and tripped the bridge again the moment it was activated. How the real servo's
gains compare is not in the documents. Standby, Disable, Passive and Position make no torque
(limp): what the arm does there is not documented.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

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
                  effort_limits: Mapping[str, float],
                  servo_torques: Mapping[str, float] | None = None) -> dict[str, float]:
    """Torque (N m) each arm joint makes: Current mode's, Velocity mode's servo, else none.

    Args:
        commands: joint -> (mode, setpoint) from the arm twin (rad, rad/s or mA).
        current_torques: joint -> torque of a Current-mode setpoint (I Kt N eta), else None.
        effort_limits: joint -> the URDF's effort limit (N m).
        servo_torques: joint -> `ArmServo`'s torque in Velocity mode; None: limp there too.
    """
    torques = {}
    servo = servo_torques or {}
    for joint, (mode, _) in commands.items():
        torque = ((current_torques.get(joint) or 0.0) if mode == Mode.CURRENT
                  else servo.get(joint, 0.0) if mode == Mode.VELOCITY else 0.0)
        limit = effort_limits.get(joint, math.inf)
        torques[joint] = float(np.clip(torque, -limit, limit))
    return torques


#: Bandwidth of the twin arm's Velocity-mode servo (rad/s): 10 rad/s, a 0.1 s time constant,
#: keeps it stable with 40 ms of loop delay (a late node on a busy machine; 15 rad/s rang on).
SERVO_BANDWIDTH_RAD_S = 10.0


class JointInertia:
    """Each arm joint's effective inertia (kg m^2) where the arm is, from the simulator's model.

    1 / (M^-1)_ii of eq. 8's M_b(q_m) with the added mass: the inertia the joint's torque
    meets with every other coordinate free (the vehicle included), about 40 us a call.
    """

    def __init__(self, robot_name: str) -> None:
        from uvms_model.model import UvmsModel
        from uvms_model.parameters import UvmsParameters

        from uvms_description.robots import with_description_paths

        self._model = UvmsModel(UvmsParameters().updated(with_description_paths({},
                                                                                robot_name)))
        self.joint_names: tuple[str, ...] = self._model.joint_names

    def effective_kg_m2(self, positions: Mapping[str, float]) -> dict[str, float]:
        """{joint: effective inertia} at these joint positions (rad)."""
        q = np.zeros(self._model.n_dof)
        q[6:] = [positions.get(j, 0.0) for j in self.joint_names]
        inverse = np.linalg.inv(self._model.mass_matrix_body(q))
        return dict(zip(self.joint_names, (1.0 / np.diag(inverse)[6:]).tolist(), strict=True))


@dataclass
class ArmServo:
    """The arm devices' own speed loop in Velocity mode: torque toward the speed setpoint.

    tau = I (2 w (v_set - v) + w^2 (q_ref - q)), q_ref the setpoint integrated from where the
    joint was when it entered Velocity mode (so VELOCITY 0 holds the joint where it is, as a
    speed loop with integral action does), I the joint's effective inertia where the arm is
    (`JointInertia`), w the bandwidth (critically damped); q_ref stays within what the effort
    limit can pull back (no wind-up), and the torque within the effort limit.
    """

    inertia: JointInertia
    effort_limits_n_m: Mapping[str, float]
    bandwidth_rad_s: float = SERVO_BANDWIDTH_RAD_S
    _reference: dict[str, float] = field(default_factory=dict)

    def torques(self, commands: Mapping[str, tuple[Mode, float]],
                positions: Mapping[str, float], velocities: Mapping[str, float],
                dt_s: float) -> dict[str, float]:
        """Torque (N m) of each joint in Velocity mode after ``dt_s`` of plant time."""
        out: dict[str, float] = {}
        w = self.bandwidth_rad_s
        held = [j for j, (mode, _) in commands.items() if mode == Mode.VELOCITY]
        for joint in set(self._reference) - set(held):
            del self._reference[joint]
        if not held:
            return out
        inertias = self.inertia.effective_kg_m2(positions)
        for joint in (j for j in held if j in inertias):
            setpoint = commands[joint][1]
            q, v = positions[joint], velocities[joint]
            inertia = inertias[joint]
            limit = self.effort_limits_n_m.get(joint, math.inf)
            band = limit / (inertia * w * w)
            reference = self._reference.get(joint, q) + setpoint * dt_s
            reference = min(max(reference, q - band), q + band)
            self._reference[joint] = reference
            torque = inertia * (2.0 * w * (setpoint - v) + w * w * (reference - q))
            out[joint] = float(np.clip(torque, -limit, limit))
        return out
