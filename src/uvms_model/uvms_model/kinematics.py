"""Vehicle kinematics of the paper's sec. 3.2: J1, J2 and B(q), with NED/FRD frames.

Angles are roll phi, pitch theta, yaw psi (ZYX Euler, paper q4, q5, q6). Rotations are
named ``rot_<to>_from_<from>`` so that ``v_ned = rot_ned_from_body(phi, theta, psi) @ v_body``.

Power balance fixes the map of generalized forces: with ``q_dot = B w`` (eq. 4),
``tau . q_dot = tau_b . w`` gives ``tau_b = B^T tau``. The paper prints ``tau = B tau_b``
under eq. 18; that holds only where B is orthogonal (not for J2), so this package uses
``tau_b = B^T tau`` throughout.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from uvms_model.errors import SingularAttitudeError

FloatArray = NDArray[np.float64]

SINGULAR_COS_PITCH = 1e-3
"""|cos(theta)| below which J2 (paper sec. 3.2) is treated as singular (|theta| > 89.94 deg)."""


def check_pitch(theta: float, name: str = 'q') -> float:
    """Return cos(theta), raising SingularAttitudeError near pitch = +-90 deg (paper sec. 3.2).

    Args:
        theta: Pitch angle (rad).
        name: Name of the argument the pitch came from, for the error message.

    Returns:
        cos(theta).

    Raises:
        SingularAttitudeError: If |cos(theta)| < SINGULAR_COS_PITCH.
    """
    c = math.cos(theta)
    if abs(c) < SINGULAR_COS_PITCH:
        raise SingularAttitudeError(
            f'{name}: pitch theta = {theta!r} rad ({math.degrees(theta):.3f} deg) is within '
            f'{math.degrees(math.asin(SINGULAR_COS_PITCH)):.3f} deg of +-90 deg, where the '
            'Euler-angle rate matrix J2 (paper sec. 3.2) is singular'
        )
    return c


def rot_ned_from_body(phi: float, theta: float, psi: float) -> FloatArray:
    """Rotation base_link_frd -> map_ned, the paper's J1 (sec. 3.2): Rz(psi) Ry(theta) Rx(phi).

    Example:
        >>> rot_ned_from_body(0.0, 0.0, math.pi / 2) @ np.array([1.0, 0.0, 0.0])  # doctest: +SKIP
        array([0., 1., 0.])  # facing east, forward is east
    """
    c4, s4 = math.cos(phi), math.sin(phi)
    c5, s5 = math.cos(theta), math.sin(theta)
    c6, s6 = math.cos(psi), math.sin(psi)
    return np.array(
        [
            [c5 * c6, -s6 * c4 + s4 * s5 * c6, s4 * s6 + s5 * c4 * c6],
            [s6 * c5, c4 * c6 + s4 * s5 * s6, -s4 * c6 + s5 * s6 * c4],
            [-s5, s4 * c5, c4 * c5],
        ]
    )


def euler_rate_matrix(phi: float, theta: float) -> FloatArray:
    """J2 of the paper (sec. 3.2): Euler-angle rates from body rates, eta2_dot = J2 omega.

    Raises:
        SingularAttitudeError: Near pitch = +-90 deg.
    """
    c5 = check_pitch(theta)
    c4, s4 = math.cos(phi), math.sin(phi)
    t5 = math.sin(theta) / c5
    return np.array(
        [
            [1.0, s4 * t5, c4 * t5],
            [0.0, c4, -s4],
            [0.0, s4 / c5, c4 / c5],
        ]
    )


def euler_rate_matrix_inverse(phi: float, theta: float) -> FloatArray:
    """J2^-1: body rates from Euler-angle rates, omega = J2^-1 eta2_dot (regular everywhere)."""
    c4, s4 = math.cos(phi), math.sin(phi)
    c5, s5 = math.cos(theta), math.sin(theta)
    return np.array(
        [
            [1.0, 0.0, -s5],
            [0.0, c4, s4 * c5],
            [0.0, -s4, c4 * c5],
        ]
    )


def skew(v: FloatArray) -> FloatArray:
    """Cross-product matrix [v]x with [v]x u = v x u."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def euler_from_rotation(rot_ned_from_body_: FloatArray) -> tuple[float, float, float]:
    """Roll, pitch, yaw (ZYX, as J1 of sec. 3.2) of a rotation matrix, pitch in [-pi/2, pi/2]."""
    r = rot_ned_from_body_
    theta = -math.asin(max(-1.0, min(1.0, float(r[2, 0]))))
    phi = math.atan2(float(r[2, 1]), float(r[2, 2]))
    psi = math.atan2(float(r[1, 0]), float(r[0, 0]))
    return phi, theta, psi
