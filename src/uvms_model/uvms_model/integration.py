"""Fixed-step integrators of the UVMS state (q, w): q_dot = B(q) w (eq. 4), w_dot of eq. 8.

The input tau_b (held by ``BodyDynamics.set_tau_b``) and the end-effector force are constant
over the step. The RK4 stages run in plain floats: for 9-vectors a list comprehension costs
less than the numpy calls it would replace, and each stage is one ``BodyDynamics.w_dot``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from uvms_model.body_dynamics import BodyDynamics
from uvms_model.coordinates import (
    N_DOF,
    mat_t_vec,
    q_dot_from_w,
    rotation,
    rotation_and_q_dot,
)

FloatArray = NDArray[np.float64]


def _stage(
    dynamics: BodyDynamics, g: float, q: list[float], w: list[float], f_ned: list[float] | None
) -> tuple[list[float], list[float]]:
    """(q_dot, w_dot) at (q, w) as lists (w_dot runs on into the sliders' accelerations)."""
    rot, q_dot = rotation_and_q_dot(q, w)
    f_body = None if f_ned is None else mat_t_vec(rot, f_ned)
    w_dot = dynamics.w_dot(q[6:9], w, (g * rot[6], g * rot[7], g * rot[8]), f_body)
    return q_dot, w_dot.tolist()


def rk4_step(
    dynamics: BodyDynamics,
    g: float,
    q: list[float],
    w: list[float],
    f_ned: list[float] | None,
    dt: float,
) -> tuple[FloatArray, FloatArray]:
    """One classical fourth-order Runge-Kutta step of (q, w).

    Args:
        dynamics: The body-form dynamics, with tau_b held.
        g: Gravitational acceleration (m/s^2), down in map_ned.
        q: Generalized coordinates (9,).
        w: Quasi-velocities (9,).
        f_ned: Force ON the end effector in map_ned (N), or None.
        dt: Step (s).

    Returns:
        (q, w) at t + dt, new arrays.

    Raises:
        SingularAttitudeError: If a stage reaches pitch +-90 deg.
    """
    half = 0.5 * dt
    p1, a1 = _stage(dynamics, g, q, w, f_ned)
    p2, a2 = _stage(
        dynamics,
        g,
        [x + half * d for x, d in zip(q, p1, strict=True)],
        [x + half * d for x, d in zip(w, a1, strict=False)],
        f_ned,
    )
    p3, a3 = _stage(
        dynamics,
        g,
        [x + half * d for x, d in zip(q, p2, strict=True)],
        [x + half * d for x, d in zip(w, a2, strict=False)],
        f_ned,
    )
    p4, a4 = _stage(
        dynamics,
        g,
        [x + dt * d for x, d in zip(q, p3, strict=True)],
        [x + dt * d for x, d in zip(w, a3, strict=False)],
        f_ned,
    )
    sixth = dt / 6.0
    q_new = np.array(
        [
            x + sixth * (d1 + d4 + 2.0 * (d2 + d3))
            for x, d1, d2, d3, d4 in zip(q, p1, p2, p3, p4, strict=True)
        ]
    )
    w_new = np.array(
        [
            x + sixth * (d1 + d4 + 2.0 * (d2 + d3))
            for x, d1, d2, d3, d4 in zip(w, a1, a2, a3, a4, strict=False)
        ]
    )
    return q_new, w_new


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
