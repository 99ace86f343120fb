"""Holding the arm in joint space while no task runs: for experiments that move the vehicle.

The controller's hold is the end effector's position in ``map_ned`` (the hold point, eq. 29):
when something else moves the vehicle (an identification plan's planned thrusts,
docs/identification.md "Why the vehicle tumbles") the arm reaches for the world-fixed point,
its shifting weight and reaction torques tilt the vehicle, past the tracking limit into the
retreat and the safe hold. With ``arm.hold_in_joint_space`` the controller instead holds each
joint where it was when the hold began, by computed torque on the model (eq. 8's arm rows: the
arm's mass matrix M_a, the joint rows of the bias C_b w + D_b w + G_b, so the arm's weight and
buoyancy, its Coriolis and drag terms are cancelled and the PD only corrects the rest):

    tau_j = M_a (w_n^2 (q_hold - q) - 2 zeta w_n q_dot) + bias_j(q, w)

(a plain joint PD diverged on the Alpha 5 in 11 ms: its wrist's inertia is so small that
any useful damping gain is unstable at a 2 ms period; scaled by M_a the loop is the same
second-order one on every joint), and commands the vehicle nothing (its rows zero: the plan's
thrusts are the experiment). The hold point follows the end effector meanwhile, so the
task-space checks (the tracking limit) see no error; a task sent starts from where the arm
is, and the next hold begins where the task left the joints.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from uvms_control.core.errors import ControlParameterError
from uvms_model import UvmsModel

FloatArray = npt.NDArray[np.float64]

__all__ = ['JointHold', 'joint_hold_from', 'joint_hold_torque']


def joint_hold_torque(q_hold: FloatArray, q_arm: FloatArray, q_arm_dot: FloatArray,
                      mass_arm: FloatArray, bias_arm: FloatArray, omega_rad_s: float,
                      damping_ratio: float) -> FloatArray:
    """Joint torques (N m) holding the arm at ``q_hold`` (rad): computed torque (eq. 8).

    >>> joint_hold_torque(np.array([1.0]), np.array([0.9]), np.array([0.5]), np.eye(1) * 0.5,
    ...                   np.array([2.0]), 10.0, 1.0).round(6)
    array([2.])
    """
    acceleration = omega_rad_s ** 2 * (q_hold - q_arm) - 2.0 * damping_ratio * omega_rad_s \
        * q_arm_dot
    return mass_arm @ acceleration + bias_arm


class JointHold:
    """The joint-space hold of the arm: where it holds, and the torques that hold it there.

    Args:
        frequency_hz: The hold's natural frequency on every joint (Hz).
        damping_ratio: Its damping ratio (1: critically damped).

    Raises:
        ControlParameterError: A frequency or damping ratio not above 0, or not finite.
    """

    def __init__(self, frequency_hz: float, damping_ratio: float) -> None:
        for name, value in (('arm.joint_hold_frequency_hz', frequency_hz),
                            ('arm.joint_hold_damping_ratio', damping_ratio)):
            if not (np.isfinite(value) and value > 0.0):
                raise ControlParameterError(name, value, '(0, inf)')
        self.omega_rad_s = 2.0 * np.pi * float(frequency_hz)
        self.damping_ratio = float(damping_ratio)
        #: The joint positions held (rad); None until the next hold begins.
        self.q_hold: FloatArray | None = None

    def release(self) -> None:
        """A task runs: the next hold begins where the joints are then."""
        self.q_hold = None

    def torque_b(self, model: UvmsModel, q: npt.ArrayLike, w: npt.ArrayLike) -> FloatArray:
        """Generalized body force (6 + n,): vehicle rows 0, the joints held (`joint_hold_torque`).

        Args:
            model: The controller's model (the bias of eq. 8).
            q: Generalized coordinates (6 + n,).
            w: Quasi-velocities (6 + n,), the joint rates last.
        """
        q_arr = np.asarray(q, dtype=np.float64)
        w_arr = np.asarray(w, dtype=np.float64)
        if self.q_hold is None:
            self.q_hold = q_arr[6:].copy()
        mass, bias = model.mass_and_bias_body(q_arr, w_arr)  # one pass of eq. 8's terms
        tau_b = np.zeros(q_arr.size)
        tau_b[6:] = joint_hold_torque(self.q_hold, q_arr[6:], w_arr[6:], mass[6:, 6:],
                                      bias[6:], self.omega_rad_s, self.damping_ratio)
        return tau_b


def joint_hold_from(node: Mapping[str, Any]) -> JointHold | None:
    """The controller node's ``arm.hold_in_joint_space`` and gains: a hold, or None (off)."""
    if not node['arm.hold_in_joint_space']:
        return None
    return JointHold(float(node['arm.joint_hold_frequency_hz']),
                     float(node['arm.joint_hold_damping_ratio']))
