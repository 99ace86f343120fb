"""Fixed-step integrators of the UVMS state (q, w): q_dot = B(q) w (eq. 4), w_dot of eq. 8.

The input tau_b (held by ``BodyDynamics.set_tau_b``) and the end-effector force are constant
over the step. An RK4 stage is a compiled kernel (Numba, ``uvms_model.jit``) between
Pinocchio's compiled calls: at 9-vectors, Python arithmetic and numpy calls would cost more
than the dynamics themselves.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from uvms_model.body_dynamics import BodyDynamics
from uvms_model.coordinates import N_DOF, mat_t_vec, q_dot_from_w, rotation
from uvms_model.jit import kernel
from uvms_model.kinematics import check_pitch

FloatArray = NDArray[np.float64]


class Rk4Integrator:
    """Classical fourth-order Runge-Kutta steps of (q, w) on one BodyDynamics and a workspace.

    Each stage is one compiled kernel (``rk4_stage_input``: the stage state, rotation,
    q_dot = B w and the body-frame gravity and end-effector force, written straight into the
    dynamics' posed state) and one ``BodyDynamics.accelerations_as_posed`` (Pinocchio's FK and
    ABA around the external-force kernel); ``rk4_combine`` sums the slopes. Not thread-safe.

    Args:
        dynamics: The body-form dynamics; tau_b is held by ``BodyDynamics.set_tau_b``.
        g: Gravitational acceleration (m/s^2), down in map_ned.
    """

    def __init__(self, dynamics: BodyDynamics, g: float) -> None:
        self._dynamics = dynamics
        self._g = g
        self._state = np.zeros(2 * N_DOF)
        self._slopes = np.zeros((4, 2 * N_DOF))
        self._vectors = np.zeros((3, 2))
        self._force = np.zeros(3)
        self._no_w_dot = np.zeros(N_DOF)

    def step(
        self, q: FloatArray, w: FloatArray, f_ned: list[float] | None, dt: float
    ) -> tuple[FloatArray, FloatArray]:
        """One step from (q, w) with the force ON the end effector f_ned (N, map_ned) or None.

        Returns:
            (q, w) at t + dt, views of one new array.

        Raises:
            SingularAttitudeError: If a stage reaches pitch +-90 deg.
        """
        dynamics, state, slopes = self._dynamics, self._state, self._slopes
        state[:N_DOF] = q
        state[N_DOF:] = w
        has_force = f_ned is not None
        if f_ned is not None:
            self._force[:] = f_ned
        arm, velocities, vectors = dynamics.arm_angles, dynamics.quasi_velocities, self._vectors
        w_dot = self._no_w_dot
        for stage, h in enumerate((0.0, 0.5 * dt, 0.5 * dt, dt)):
            theta = rk4_stage_input(state, slopes, stage, w_dot, h, self._g, self._force,
                                    has_force, arm, velocities, vectors)
            check_pitch(theta, 'q (during integration)')
            w_dot = dynamics.accelerations_as_posed(vectors)
        result = np.empty(2 * N_DOF)
        rk4_combine(state, slopes, w_dot, dt, result)
        return result[:N_DOF], result[N_DOF:]


@kernel
def rk4_stage_input(
    state: FloatArray, slopes: FloatArray, stage: int, w_dot_before: FloatArray, h: float,
    g: float, f_ned: FloatArray, has_force: bool, arm: FloatArray, w_out: FloatArray,
    vectors: FloatArray,
) -> float:
    """Pose RK4 stage ``stage`` at state + h k_(stage-1); q_dot = B w (eq. 4) into its slope.

    ``slopes`` rows are k_s = [q_dot; w_dot]; the w_dot of the stage before
    (``w_dot_before``, the dynamics' accelerations) completes row stage - 1 first. Writes the
    arm angles into ``arm``, w into ``w_out``, and into ``vectors`` the gravitational
    acceleration g R^T e_z and the force R^T f_ned in base_link_frd (R = rot_ned_from_body,
    J1 of sec. 3.2, ZYX). Returns the stage's pitch (the caller guards J2's singularity).
    """
    n = arm.shape[0] + 6
    k = slopes[max(stage - 1, 0)]
    if stage > 0:
        for i in range(n):
            k[n + i] = w_dot_before[i]
    x = np.empty(2 * n)
    for i in range(2 * n):
        x[i] = state[i] + h * k[i] if stage > 0 else state[i]
    c4, s4 = math.cos(x[3]), math.sin(x[3])
    c5, s5 = math.cos(x[4]), math.sin(x[4])
    c6, s6 = math.cos(x[5]), math.sin(x[5])
    r = (
        c5 * c6, -s6 * c4 + s4 * s5 * c6, s4 * s6 + s5 * c4 * c6,
        s6 * c5, c4 * c6 + s4 * s5 * s6, -s4 * c6 + s5 * s6 * c4,
        -s5, s4 * c5, c4 * c5,
    )  # fmt: skip
    u, v, ww, p, q, rr = x[n], x[n + 1], x[n + 2], x[n + 3], x[n + 4], x[n + 5]
    out = slopes[stage]
    out[0] = r[0] * u + r[1] * v + r[2] * ww
    out[1] = r[3] * u + r[4] * v + r[5] * ww
    out[2] = r[6] * u + r[7] * v + r[8] * ww
    a = s4 * q + c4 * rr
    out[3] = p + a * s5 / c5
    out[4] = c4 * q - s4 * rr
    out[5] = a / c5
    for i in range(6, n):
        out[i] = x[n + i]
        arm[i - 6] = x[i]
    for i in range(n):
        w_out[i] = x[n + i]
    vectors[0, 0], vectors[1, 0], vectors[2, 0] = g * r[6], g * r[7], g * r[8]
    if has_force:
        f0, f1, f2 = f_ned[0], f_ned[1], f_ned[2]
        vectors[0, 1] = r[0] * f0 + r[3] * f1 + r[6] * f2
        vectors[1, 1] = r[1] * f0 + r[4] * f1 + r[7] * f2
        vectors[2, 1] = r[2] * f0 + r[5] * f1 + r[8] * f2
    else:
        vectors[0, 1], vectors[1, 1], vectors[2, 1] = 0.0, 0.0, 0.0
    theta: float = x[4]
    return theta


@kernel
def rk4_combine(
    state: FloatArray, slopes: FloatArray, w_dot_last: FloatArray, dt: float, out: FloatArray
) -> None:
    """Out = state + dt/6 (k1 + 2 k2 + 2 k3 + k4), the last stage's w_dot completing k4."""
    n = state.shape[0] // 2
    for i in range(n):
        slopes[3, n + i] = w_dot_last[i]
    sixth = dt / 6.0
    for i in range(2 * n):
        out[i] = state[i] + sixth * (
            slopes[0, i] + slopes[3, i] + 2.0 * (slopes[1, i] + slopes[2, i])
        )


def semi_implicit_euler_step(
    dynamics: BodyDynamics,
    g: float,
    q: list[float],
    w: FloatArray,
    f_ned: list[float] | None,
    dt: float,
) -> tuple[FloatArray, FloatArray]:
    """One semi-implicit (symplectic) Euler step: w first, then q with the new w.

    Args: as ``rk4_step``, with w as an array.

    Raises:
        SingularAttitudeError: At pitch +-90 deg.
    """
    rot = rotation(q[3], q[4], q[5])
    f_body = None if f_ned is None else mat_t_vec(rot, f_ned)
    w_dot = dynamics.w_dot(q[6:9], w, (g * rot[6], g * rot[7], g * rot[8]), f_body)
    w_new: FloatArray = w + dt * w_dot[:N_DOF]
    q_new: FloatArray = np.asarray(q) + dt * np.array(q_dot_from_w(q, w_new.tolist(), rot))
    return q_new, w_new
