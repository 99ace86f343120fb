"""Generalized coordinates q and quasi-velocities w (paper eq. 4) for one state (hot path).

The same maps as ``uvms_model.kinematics`` (J1, J2, B of sec. 3.2), written once as compiled
kernels (``rotation_matrix``, ``velocity_transforms``) that the other kernels call, with thin
Python faces for the model's own callers. Rotations handed to Python code are row-major
9-tuples: at this size, indexing a tuple costs less than indexing an array.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import cast

import numpy as np
from numpy.typing import NDArray

from uvms_model.jit import kernel
from uvms_model.kinematics import check_pitch

FloatArray = NDArray[np.float64]

Vec3 = tuple[float, float, float]
Mat3 = tuple[float, float, float, float, float, float, float, float, float]
"""A 3x3 matrix as a row-major 9-tuple."""


@kernel
def rotation_matrix(phi: float, theta: float, psi: float) -> FloatArray:
    """rot_ned_from_body (J1 of sec. 3.2) = Rz(psi) Ry(theta) Rx(phi), (3, 3), compiled."""
    c4, s4 = math.cos(phi), math.sin(phi)
    c5, s5 = math.cos(theta), math.sin(theta)
    c6, s6 = math.cos(psi), math.sin(psi)
    return np.array((
        (c5 * c6, -s6 * c4 + s4 * s5 * c6, s4 * s6 + s5 * c4 * c6),
        (s6 * c5, c4 * c6 + s4 * s5 * s6, -s4 * c6 + s5 * s6 * c4),
        (-s5, s4 * c5, c4 * c5),
    ))  # fmt: skip


@kernel
def velocity_transforms(q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """B(q) = blockdiag(J1, J2, I) and B⁻¹ = blockdiag(J1ᵀ, J2⁻¹, I), (6 + n, 6 + n) each (eq. 4).

    q_dot = B w. B⁻¹ is regular at any pitch; B has 1/cos(pitch) entries (inf at +-90 deg):
    the caller checks the pitch (``check_pitch``). Compiled.
    """
    n = q.shape[0]
    rot = rotation_matrix(q[3], q[4], q[5])
    c4, s4 = math.cos(q[3]), math.sin(q[3])
    c5, s5 = math.cos(q[4]), math.sin(q[4])
    t5 = s5 / c5
    b = np.eye(n)
    b_inv = np.eye(n)
    for i in range(3):
        for j in range(3):
            b[i, j] = rot[i, j]
            b_inv[i, j] = rot[j, i]
    b[3, 4], b[3, 5] = s4 * t5, c4 * t5
    b[4, 4], b[4, 5] = c4, -s4
    b[5, 4], b[5, 5] = s4 / c5, c4 / c5
    b_inv[3, 5] = -s5
    b_inv[4, 4], b_inv[4, 5] = c4, s4 * c5
    b_inv[5, 4], b_inv[5, 5] = -s4, c4 * c5
    return b, b_inv


def rotation(phi: float, theta: float, psi: float) -> Mat3:
    """rot_ned_from_body (J1 of sec. 3.2) as a row-major 9-tuple."""
    return cast(Mat3, tuple(rotation_matrix(phi, theta, psi).ravel().tolist()))


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


def mat_t_vec(r: Sequence[float], v: Sequence[float]) -> Vec3:
    """R^T v for R a row-major 9-sequence."""
    return (
        r[0] * v[0] + r[3] * v[1] + r[6] * v[2],
        r[1] * v[0] + r[4] * v[1] + r[7] * v[2],
        r[2] * v[0] + r[5] * v[1] + r[8] * v[2],
    )


def velocity_transform(q: FloatArray, name: str = 'q') -> FloatArray:
    """B(q) (6 + n, 6 + n) of eq. 4, q_dot = B w (paper sec. 3.2), a new array.

    Raises:
        SingularAttitudeError: Near pitch = +-90 deg (``name`` names q in the message).
    """
    check_pitch(float(q[4]), name)
    return velocity_transforms(q)[0]


def velocity_transform_inverse(q: FloatArray) -> FloatArray:
    """B^-1 = blockdiag(J1^T, J2^-1, I) (6 + n, 6 + n), regular at any pitch, a new array."""
    return velocity_transforms(q)[1]
