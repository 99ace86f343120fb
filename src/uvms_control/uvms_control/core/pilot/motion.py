"""Pilot velocities to references: deadman, rate limits, and the integrated pose of the vehicle.

The pilot commands velocities; the controller follows positions. ``PilotMotion`` turns the
one into the other without a jump: each commanded velocity slews toward its target at most at
the robot's pilot acceleration, a target older than the deadman is zero, and the references
integrate the slewed velocities from where they were when the pilot took over. The vehicle
reference is its pose η = [x, y, z, φ, θ, ψ] in map_ned (the posture the controller's null
space holds, ``UnifiedForceController.set_vehicle_reference``); the end effector's is its
position X_d = p + R(η) r, with r its offset from the vehicle in base_link_frd, so the arm
rides along with the vehicle and the pilot moves it relative to the vehicle (Fossen 2011,
eq. 2.40 for η̇ from the body twist).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from uvms_model.kinematics import euler_rate_matrix, rot_ned_from_body

from uvms_control.core.pilot.inputs import PilotTwist
from uvms_control.core.pilot.limits import PilotLimits

FloatArray = npt.NDArray[np.float64]

_ZERO = PilotTwist((0.0, 0.0, 0.0))


@dataclass(frozen=True)
class PilotReference:
    """What the controller follows while the pilot drives (map_ned, SI).

    Attributes:
        eta: vehicle pose [x, y, z, φ, θ, ψ] (m, rad).
        eta_dot: its rate (m/s, Euler-angle rates rad/s).
        X_d: end-effector position (m).
        X_dot_d: its velocity (m/s).
        jaw_speed_m_s: the jaw's commanded speed (m/s, + opens).
    """

    eta: FloatArray
    eta_dot: FloatArray
    X_d: FloatArray
    X_dot_d: FloatArray
    jaw_speed_m_s: float


def _slew(current: FloatArray, target: FloatArray, max_step: float) -> FloatArray:
    """Move current toward target by at most max_step (Euclidean)."""
    step = target - current
    norm = float(np.linalg.norm(step))
    if norm <= max_step:
        return target.copy()
    result: FloatArray = current + step * (max_step / norm)
    return result


class PilotMotion:
    """Deadman, rate limits and integration of the pilot's velocities.

    Args:
        limits: the robot's pilot limits (accelerations, deadman).
    """

    def __init__(self, limits: PilotLimits) -> None:
        self.limits = limits
        self._vehicle = _ZERO
        self._ee = _ZERO
        self._jaw = 0.0
        self._t_vehicle = self._t_ee = self._t_jaw = -math.inf
        #: Time of the last message that asked for motion (s); -inf: none.
        self.last_motion_s = -math.inf
        self.nu = np.zeros(6)  # slewed body twist [v (m/s), ω (rad/s)], base_link_frd
        self.r_dot = np.zeros(3)  # slewed end-effector velocity relative to the vehicle, body
        self.jaw_speed_m_s = 0.0
        self.eta = np.zeros(6)
        self.r = np.zeros(3)
        self.started = False

    def start(self, eta: FloatArray, X_d: FloatArray) -> None:
        """Take over from the vehicle pose eta and the end-effector position X_d (map_ned).

        The slewed velocities carry over (a take-over while still moving does not jump).
        """
        self.eta = np.array(eta, dtype=np.float64)
        rot = rot_ned_from_body(*self.eta[3:])
        self.r = rot.T @ (np.asarray(X_d, dtype=np.float64) - self.eta[:3])
        self.started = True

    def command_vehicle(self, t_s: float, twist: PilotTwist) -> None:
        """A checked vehicle twist received at t_s (s)."""
        self._vehicle, self._t_vehicle = twist, t_s
        if not twist.is_zero:
            self.last_motion_s = t_s

    def command_ee(self, t_s: float, twist: PilotTwist) -> None:
        """A checked end-effector velocity received at t_s (s)."""
        self._ee, self._t_ee = twist, t_s
        if not twist.is_zero:
            self.last_motion_s = t_s

    def command_jaw(self, t_s: float, speed_m_s: float) -> None:
        """A checked jaw speed (m/s) received at t_s (s)."""
        self._jaw, self._t_jaw = speed_m_s, t_s
        if speed_m_s != 0.0:
            self.last_motion_s = t_s

    def stop(self) -> None:
        """Zero every target now (hold, a task's take-over); the velocities slew down to zero."""
        self._vehicle, self._ee, self._jaw = _ZERO, _ZERO, 0.0
        self._t_vehicle = self._t_ee = self._t_jaw = -math.inf
        self.last_motion_s = -math.inf

    def driving(self, t_s: float) -> bool:
        """A message asked for motion within the deadman before t_s."""
        return t_s - self.last_motion_s <= self.limits.deadman_s

    @property
    def moving(self) -> bool:
        """A slewed velocity is not zero yet."""
        return bool(self.nu.any() or self.r_dot.any() or self.jaw_speed_m_s != 0.0)

    def step(self, t_s: float, dt_s: float) -> PilotReference:
        """Slew the velocities toward their live targets, integrate over dt_s (s), at t_s (s)."""
        limits = self.limits
        deadman = limits.deadman_s
        vehicle = self._vehicle if t_s - self._t_vehicle <= deadman else _ZERO
        ee = self._ee if t_s - self._t_ee <= deadman else _ZERO
        jaw = self._jaw if t_s - self._t_jaw <= deadman else 0.0
        rot = rot_ned_from_body(*self.eta[3:])
        self.nu[:3] = _slew(self.nu[:3], np.array(vehicle.linear),
                            limits.vehicle_acceleration_m_s2 * dt_s)
        self.nu[3:] = _slew(self.nu[3:], np.array(vehicle.angular),
                            limits.vehicle_angular_acceleration_rad_s2 * dt_s)
        ee_body = np.array(ee.linear) if ee.in_body else rot.T @ np.array(ee.linear)
        self.r_dot = _slew(self.r_dot, ee_body, limits.ee_acceleration_m_s2 * dt_s)
        jaw_step = limits.jaw_speed_m_s / 0.1 * dt_s  # full jaw speed in 0.1 s
        self.jaw_speed_m_s += max(-jaw_step, min(jaw_step, jaw - self.jaw_speed_m_s))
        eta_dot = np.concatenate((rot @ self.nu[:3],
                                  euler_rate_matrix(*self.eta[3:5]) @ self.nu[3:]))
        if dt_s > 0.0:
            self.eta = self.eta + eta_dot * dt_s
            self.r = self.r + self.r_dot * dt_s
            rot = rot_ned_from_body(*self.eta[3:])
        omega_ned = rot @ self.nu[3:]
        offset = rot @ self.r
        X_dot_d = eta_dot[:3] + np.cross(omega_ned, offset) + rot @ self.r_dot
        return PilotReference(self.eta.copy(), eta_dot, self.eta[:3] + offset, X_dot_d,
                              self.jaw_speed_m_s)
