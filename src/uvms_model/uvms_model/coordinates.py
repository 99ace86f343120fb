"""Generalized coordinates q and quasi-velocities w (paper eq. 4) in plain floats (hot path).

The same maps as ``uvms_model.kinematics`` (J1, J2, B of sec. 3.2) written for one state at a
time: rotations as row-major 9-tuples, vectors as tuples or lists, and B, B^-1 as (9, 9) arrays
filled from a template in one indexed write. At this size Python arithmetic on floats is
cheaper than numpy's per-call overhead (about 0.3-1 us a call), so nothing here builds small
arrays element by element.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from uvms_model.kinematics import check_pitch

FloatArray = NDArray[np.float64]

N_DOF = 9
"""Generalized coordinates: vehicle position and ZYX Euler angles (6), three arm joints."""

Vec3 = tuple[float, float, float]
Mat3 = tuple[float, float, float, float, float, float, float, float, float]
"""A 3x3 matrix as a row-major 9-tuple."""


def rotation(phi: float, theta: float, psi: float) -> Mat3:
    """rot_ned_from_body (J1 of sec. 3.2) as a row-major 9-tuple."""
    c4, s4 = math.cos(phi), math.sin(phi)
    c5, s5 = math.cos(theta), math.sin(theta)
    c6, s6 = math.cos(psi), math.sin(psi)
    return (
        c5 * c6, -s6 * c4 + s4 * s5 * c6, s4 * s6 + s5 * c4 * c6,
        s6 * c5, c4 * c6 + s4 * s5 * s6, -s4 * c6 + s5 * s6 * c4,
        -s5, s4 * c5, c4 * c5,
    )  # fmt: skip


def quaternion_xyzw(phi: float, theta: float, psi: float) -> tuple[float, float, float, float]:
    """Unit quaternion (x, y, z, w), Pinocchio's order, of Rz(psi) Ry(theta) Rx(phi)."""
    c1, s1 = math.cos(0.5 * phi), math.sin(0.5 * phi)
    c2, s2 = math.cos(0.5 * theta), math.sin(0.5 * theta)
    c3, s3 = math.cos(0.5 * psi), math.sin(0.5 * psi)
    return (
        s1 * c2 * c3 - c1 * s2 * s3,
        c1 * s2 * c3 + s1 * c2 * s3,
        c1 * c2 * s3 - s1 * s2 * c3,
        c1 * c2 * c3 + s1 * s2 * s3,
    )


def mat_vec(r: Sequence[float], v: Sequence[float]) -> Vec3:
    """R v for R a row-major 9-sequence and v a 3-sequence (only v's first three are read)."""
    return (
        r[0] * v[0] + r[1] * v[1] + r[2] * v[2],
        r[3] * v[0] + r[4] * v[1] + r[5] * v[2],
        r[6] * v[0] + r[7] * v[1] + r[8] * v[2],
    )


def mat_t_vec(r: Sequence[float], v: Sequence[float]) -> Vec3:
    """R^T v for R a row-major 9-sequence."""
    return (
        r[0] * v[0] + r[3] * v[1] + r[6] * v[2],
        r[1] * v[0] + r[4] * v[1] + r[7] * v[2],
        r[2] * v[0] + r[5] * v[1] + r[8] * v[2],
    )


def q_dot_from_w(q: Sequence[float], w: Sequence[float], rot: Mat3) -> list[float]:
    """q_dot = B(q) w (eq. 4); ``rot`` is rot_ned_from_body at q.

    Raises:
        SingularAttitudeError: Near pitch = +-90 deg, where J2 is singular.
    """
    phi, theta = q[3], q[4]
    c5 = check_pitch(theta, 'q (during integration)')
    c4, s4 = math.cos(phi), math.sin(phi)
    t5 = math.sin(theta) / c5
    p, qq, r = w[3], w[4], w[5]
    return [
        *mat_vec(rot, w),
        p + (s4 * qq + c4 * r) * t5,
        c4 * qq - s4 * r,
        (s4 * qq + c4 * r) / c5,
        w[6],
        w[7],
        w[8],
    ]


def w_from_q_dot(q: Sequence[float], q_dot: Sequence[float], rot: Mat3) -> list[float]:
    """Quasi-velocities w = B^-1 q_dot = [R^T p_dot; J2^-1 eta_dot; q_m_dot] (any pitch)."""
    c4, s4 = math.cos(q[3]), math.sin(q[3])
    c5, s5 = math.cos(q[4]), math.sin(q[4])
    phi_dot, theta_dot, psi_dot = q_dot[3], q_dot[4], q_dot[5]
    return [
        *mat_t_vec(rot, q_dot),
        phi_dot - s5 * psi_dot,
        c4 * theta_dot + s4 * c5 * psi_dot,
        -s4 * theta_dot + c4 * c5 * psi_dot,
        q_dot[6],
        q_dot[7],
        q_dot[8],
    ]


# Entries of B and B^-1 that depend on q (row-major flat indices), all others constant.
_CHANGING = np.array([0, 1, 2, 9, 10, 11, 18, 19, 20, 31, 32, 40, 41, 49, 50], dtype=np.intp)
_IDENTITY = np.eye(N_DOF)
_IDENTITY.setflags(write=False)


def velocity_transform(q: Sequence[float], rot: Mat3) -> FloatArray:
    """B(q) (9, 9) of eq. 4, q_dot = B w: blockdiag(J1, J2, I) (paper sec. 3.2), a new array.

    Raises:
        SingularAttitudeError: Near pitch = +-90 deg.
    """
    phi, theta = q[3], q[4]
    c5 = check_pitch(theta)
    c4, s4 = math.cos(phi), math.sin(phi)
    t5 = math.sin(theta) / c5
    b = _IDENTITY.copy()
    b.ravel()[_CHANGING] = (
        *rot,
        s4 * t5, c4 * t5,
        c4, -s4,
        s4 / c5, c4 / c5,
    )  # fmt: skip
    return b


def velocity_transform_inverse(q: Sequence[float], rot: Mat3) -> FloatArray:
    """B^-1 = blockdiag(J1^T, J2^-1, I) (9, 9), regular at any pitch, a new array."""
    c4, s4 = math.cos(q[3]), math.sin(q[3])
    c5, s5 = math.cos(q[4]), math.sin(q[4])
    r0, r1, r2, r3, r4, r5, r6, r7, r8 = rot
    b_inv = _IDENTITY.copy()
    b_inv.ravel()[_CHANGING] = (
        r0, r3, r6, r1, r4, r7, r2, r5, r8,
        0.0, -s5,
        c4, s4 * c5,
        -s4, c4 * c5,
    )  # fmt: skip
    return b_inv
