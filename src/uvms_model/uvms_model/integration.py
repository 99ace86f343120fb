"""Fixed-step integrators of the UVMS state (q, w): q_dot = B(q) w (eq. 4), w_dot of eq. 8.

The input tau_b (held by ``BodyDynamics.set_tau_b``) and the end-effector force are constant
over the step. An RK4 stage is a compiled kernel (Numba, ``uvms_model.jit``) between
Pinocchio's compiled calls: at 9-vectors, Python arithmetic and numpy calls would cost more
than the dynamics themselves.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from uvms_model.body_dynamics import BodyDynamics
from uvms_model.coordinates import (
    mat_t_vec,
    rotation,
    rotation_matrix,
    velocity_transform,
    velocity_transforms,
)
from uvms_model.jit import kernel
from uvms_model.kinematics import check_pitch
from uvms_model.loop_products import matvec

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
        self._n = n = dynamics.n_dof
        self._state = np.zeros(2 * n)
        self._slopes = np.zeros((4, 2 * n))
        self._vectors = np.zeros((3, 2))
        self._force = np.zeros(3)
        self._no_w_dot = np.zeros(n)
        self._current_ned = np.zeros(3)

    def step(
        self, q: FloatArray, w: FloatArray, f_ned: list[float] | None, dt: float,
        current_ned: FloatArray | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """One step from (q, w) with the force ON the end effector f_ned (N, map_ned) or None.

        ``current_ned`` is the water's velocity v_c (m/s, map_ned), held over the step, or None
        for still water (then every stage runs as it did before currents existed).

        Returns:
            (q, w) at t + dt, views of one new array.

        Raises:
            SingularAttitudeError: If a stage reaches pitch +-90 deg.
        """
        dynamics, state, slopes = self._dynamics, self._state, self._slopes
        n = self._n
        state[:n] = q
        state[n:] = w
        has_force = f_ned is not None
        if f_ned is not None:
            self._force[:] = f_ned
        arm, velocities, vectors = dynamics.arm_angles, dynamics.quasi_velocities, self._vectors
        w_dot = self._no_w_dot
        forces = dynamics.forces
        forces.has_current = has_current = current_ned is not None
        if current_ned is not None:
            self._current_ned[:] = current_ned
        for stage, h in enumerate((0.0, 0.5 * dt, 0.5 * dt, dt)):
            theta = rk4_stage_input(state, slopes, stage, w_dot, h, self._g, self._force,
                                    has_force, arm, velocities, vectors)
            if has_current:
                rotate_to_body(state, slopes, stage, h, self._current_ned,
                               forces.current_base)
            check_pitch(theta, 'q (during integration)')
            w_dot = dynamics.accelerations_as_posed(vectors)
        result = np.empty(2 * n)
        rk4_combine(state, slopes, w_dot, dt, result)
        return result[:n], result[n:]


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
    J1 of sec. 3.2). Returns the stage's pitch (the caller guards J2's singularity).
    """
    n = arm.shape[0] + 6
    k = slopes[max(stage - 1, 0)]
    if stage > 0:
        k[n:] = w_dot_before[:n]
    x = state + h * k if stage > 0 else state.copy()
    q, w = x[:n], x[n:]
    b, _ = velocity_transforms(q)
    slopes[stage, :n] = matvec(b, w)
    arm[:] = q[6:]
    w_out[:] = w
    rot = b[:3, :3]
    for i in range(3):
        vectors[i, 0] = g * rot[2, i]
        force = rot[0, i] * f_ned[0] + rot[1, i] * f_ned[1] + rot[2, i] * f_ned[2]
        vectors[i, 1] = force if has_force else 0.0
    theta: float = q[4]
    return theta


@kernel
def rotate_to_body(
    state: FloatArray, slopes: FloatArray, stage: int, h: float, v_ned: FloatArray,
    out: FloatArray,
) -> None:
    """R^T v_ned (base_link_frd) at the attitude of RK4 stage ``stage`` (as rk4_stage_input)."""
    phi, theta, psi = state[3], state[4], state[5]
    if stage > 0:
        k = slopes[stage - 1]
        phi, theta, psi = phi + h * k[3], theta + h * k[4], psi + h * k[5]
    rot = rotation_matrix(phi, theta, psi)
    for i in range(3):
        out[i] = rot[0, i] * v_ned[0] + rot[1, i] * v_ned[1] + rot[2, i] * v_ned[2]


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
    current_ned: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray]:
    """One semi-implicit (symplectic) Euler step: w first, then q with the new w.

    Args: as ``Rk4Integrator.step``, with the dynamics and g, q as a list.

    Raises:
        SingularAttitudeError: At pitch +-90 deg.
    """
    rot = rotation(q[3], q[4], q[5])
    f_body = None if f_ned is None else mat_t_vec(rot, f_ned)
    current = None if current_ned is None else mat_t_vec(rot, current_ned.tolist())
    w_dot = dynamics.w_dot(q[6:], w, (g * rot[6], g * rot[7], g * rot[8]), f_body, current)
    w_new: FloatArray = w + dt * w_dot[:dynamics.n_dof]
    q_arr = np.asarray(q)
    q_new: FloatArray = q_arr + dt * velocity_transform(q_arr, 'q (during integration)').dot(w_new)
    return q_new, w_new
