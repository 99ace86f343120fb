"""What one step of the unified force controller gives: the command and its internals."""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


class Phase(enum.IntEnum):
    """Task phase (values of uvms_msgs/ControllerState.PHASE_*)."""

    FREE_MOTION = 0
    CONTACT_TRANSITION = 1
    CONSTRAINED = 2


@dataclass(slots=True)
class ControllerResult:
    """Output and internals of one controller step (task-space vectors in map_ned).

    Attributes:
        tau_b: generalized force in body form (6 + n,): vehicle force (N) and moment (N m) in
            base_link_frd, then joint torques (N m).
        tau: generalized force in generalized coordinates (6 + n,), eq. 26 (+ null space).
        W: fuzzy weight in [0, 1], 1 = impedance.
        X: end-effector position (m).
        X_d: reference position (m).
        X_dot: end-effector velocity (m/s).
        X_dot_d: reference velocity (m/s).
        F_e: contact force exerted on the environment (N).
        F_d: desired contact force (N).
        F_c: blended task-space command (N), eq. 2.
        F_IP: impedance law output (N), eq. 31.
        F_H: hybrid law output (N), eq. 35.
        v_e: velocity along the environment normal, positive toward it (m/s).
        force_ratio: n·F_e over the force set-point (-).
        phase: task phase.
        M_hat: inertia estimate M̂ = s M̃ (kg), eq. 29.
        zeta_hat: bias estimate ζ̂ = ζ̃ (N), eq. 29.
    """

    tau_b: FloatArray
    tau: FloatArray
    W: float
    X: FloatArray
    X_d: FloatArray
    X_dot: FloatArray
    X_dot_d: FloatArray
    F_e: FloatArray
    F_d: FloatArray
    F_c: FloatArray
    F_IP: FloatArray
    F_H: FloatArray
    v_e: float
    force_ratio: float
    phase: Phase
    M_hat: FloatArray
    zeta_hat: FloatArray
