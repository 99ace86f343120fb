"""Holding the arm in joint space while no task runs: for experiments that move the vehicle.

The controller's hold is the end effector's position in ``map_ned`` (the hold point, eq. 29):
when something else moves the vehicle (an identification plan's planned thrusts,
docs/identification.md "Why the vehicle tumbles") the arm reaches for the world-fixed point,
its shifting weight and reaction torques tilt the vehicle, past the tracking limit into the
retreat and the safe hold. With ``arm.hold_in_joint_space`` the controller instead holds each
joint where it was when the hold began, by a joint PD on the model's bias (the joint rows of
C_b w + D_b w + G_b of eq. 8, so the arm's weight and buoyancy, its Coriolis and drag terms
are cancelled and the PD only corrects the rest):

    tau_j = K_p (q_hold - q) - K_d q_dot + bias_j(q, w)

and commands the vehicle nothing (its rows zero: the plan's thrusts are the experiment). The
hold point follows the end effector meanwhile, so the task-space checks (the tracking limit)
see no error; a task sent starts from where the arm is, and the next hold begins where the
task left the joints.
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
                      bias_arm: FloatArray, kp: float, kd: float) -> FloatArray:
    """Joint torques (N m) holding the arm at ``q_hold`` (rad): PD plus the model's bias (eq. 8).

    >>> joint_hold_torque(np.array([1.0]), np.array([0.9]), np.array([0.5]), np.array([2.0]),
    ...                   20.0, 2.0).round(6)
    array([3.])
    """
    return kp * (q_hold - q_arm) - kd * q_arm_dot + bias_arm


class JointHold:
    """The joint-space hold of the arm: where it holds, and the torques that hold it there.

    Args:
        kp: Joint stiffness (N m/rad), every joint.
        kd: Joint damping (N m s/rad), every joint.

    Raises:
        ControlParameterError: A negative or non-finite gain.
    """

    def __init__(self, kp: float, kd: float) -> None:
        for name, value in (('arm.joint_hold_kp', kp), ('arm.joint_hold_kd', kd)):
            if not (np.isfinite(value) and value >= 0.0):
                raise ControlParameterError(name, value, '[0, inf)')
        self.kp, self.kd = float(kp), float(kd)
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
        tau_b = np.zeros(q_arr.size)
        tau_b[6:] = joint_hold_torque(self.q_hold, q_arr[6:], w_arr[6:],
                                      model.bias_body(q_arr, w_arr)[6:], self.kp, self.kd)
        return tau_b


def joint_hold_from(node: Mapping[str, Any]) -> JointHold | None:
    """The controller node's ``arm.hold_in_joint_space`` and gains: a hold, or None (off)."""
    if not node['arm.hold_in_joint_space']:
        return None
    return JointHold(float(node['arm.joint_hold_kp']), float(node['arm.joint_hold_kd']))
