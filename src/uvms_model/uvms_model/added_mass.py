"""Added mass of the hull and the links (Kirchhoff, paper eq. 8) from their collision shapes.

Each body's added mass is axisymmetric about its shape's axis e through its centre c: axial
a_ax, lateral a_lat (a_ax < a_lat for the prolate hull and the slender links), rotary j_ax,
j_lat. Pinocchio's inertias are rigid-body ones (the same mass in every direction), so the
dynamic model (``uvms_model.pinocchio_models``) splits it: a rigid part of mass a_ax at c with
the rotary terms, fixed to the body, and the lateral excess a_lat - a_ax as a point mass on a
frictionless slider along e. ``AddedMass.slider_correction`` is what turns the slider's
velocity terms into Kirchhoff's.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from uvms_model.description import RobotDescription
from uvms_model.errors import DescriptionError
from uvms_model.hydrodynamics import lamb_coefficients
from uvms_model.kinematics import skew

FloatArray = NDArray[np.float64]


class AddedMass(NamedTuple):
    """Axisymmetric added mass of one body about its shape's axis, in the body's frame."""

    center: FloatArray  # c (3,) (m)
    axis: FloatArray  # e (3,), unit
    rotation: FloatArray  # rot_body_from_shape (3, 3) with the axis as column ``axis_column``
    axis_column: int
    axial_kg: float
    lateral_kg: float
    axial_rotary_kg_m2: float
    lateral_rotary_kg_m2: float

    def rigid_rotary(self) -> FloatArray:
        """Rotary added inertia about c in body axes (kg m^2)."""
        diag = np.full(3, self.lateral_rotary_kg_m2)
        diag[self.axis_column] = self.axial_rotary_kg_m2
        result: FloatArray = self.rotation @ np.diag(diag) @ self.rotation.T
        return result

    def matrix(self) -> FloatArray:
        """M_A (6, 6) at the body origin, [linear; angular] order."""
        cx = skew(self.center)
        rigid = np.zeros((6, 6))
        m = self.axial_kg
        rigid[:3, :3] = m * np.eye(3)
        rigid[:3, 3:] = -m * cx
        rigid[3:, :3] = m * cx
        rigid[3:, 3:] = self.rigid_rotary() - m * cx @ cx
        # Lateral excess at c: v_c = v - [c]x omega.
        to_c = np.hstack((np.eye(3), -cx))
        lateral = (self.lateral_kg - m) * (np.eye(3) - np.outer(self.axis, self.axis))
        result: FloatArray = rigid + to_c.T @ lateral @ to_c
        return result

    def slider_correction(self, nu: FloatArray) -> FloatArray:
        """Force ON the body (6,) that turns the slider's velocity terms into Kirchhoff's.

        With P = I - e e^T, m = a_lat - a_ax and v_c = v + omega x c, Kirchhoff's terms of
        the lateral inertia m P at c are [m omega x P v_c; m v_c x P v_c]; the eliminated
        slider gives [m P (omega x v_c); 0] (its point mass has no moment). The difference
        is an extra bias, applied as the opposite force.
        """
        v, omega = nu[:3], nu[3:]
        c, e = self.center, self.axis
        m = self.lateral_kg - self.axial_kg
        v_c = v + np.cross(omega, c)
        lat = v_c - e * float(e @ v_c)
        w_v = np.cross(omega, v_c)
        force = m * (np.cross(omega, lat) - (w_v - e * float(e @ w_v)))
        moment = m * np.cross(v_c, lat) + np.cross(c, force)
        return -np.concatenate((force, moment))


def quadratic_form(function: Callable[[FloatArray], FloatArray], size: int = 6) -> FloatArray:
    """Tensor Q (n, size, size) with f(x)_j = x^T Q_j x for a quadratic map f (polarization)."""
    basis = np.eye(size)
    single = [np.asarray(function(basis[a])) for a in range(size)]
    n = single[0].size
    q = np.zeros((n, size, size))
    for a in range(size):
        q[:, a, a] = single[a]
        for b in range(a + 1, size):
            both = np.asarray(function(basis[a] + basis[b]))
            q[:, a, b] = q[:, b, a] = 0.5 * (both - single[a] - single[b])
    return q


def hull_added_mass_matrix(description: RobotDescription) -> FloatArray | None:
    """M_A (6, 6) of a hull given by coefficients, about O in base_link_frd; else None.

    M_A = diag(-X_u_dot, -Y_v_dot, -Z_w_dot, -K_p_dot, -M_q_dot, -N_r_dot) (Fossen 2011,
    eq. 6.50 with the off-diagonal terms of a body with three planes of symmetry zero); the
    file gives the magnitudes (docs/robots.md).

    >>> from uvms_model.description import HullHydrodynamics
    >>> from types import SimpleNamespace
    >>> hull = HullHydrodynamics('coefficients', None, added_mass_kg=(1, 2, 3, 4, 5, 6))
    >>> hull_added_mass_matrix(SimpleNamespace(hull_hydrodynamics=hull)).diagonal().tolist()
    [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    """
    hull = description.hull_hydrodynamics
    if hull.added_mass != 'coefficients' or hull.added_mass_kg is None:
        return None
    return np.diag(np.asarray(hull.added_mass_kg, dtype=float))


def added_masses(description: RobotDescription, rho: float) -> list[AddedMass | None]:
    """Added mass of the hull and each arm link from their collision geometry (None: none).

    A hull given by coefficients has None here: its M_A (``hull_added_mass_matrix``) is
    added to the mass matrix of eq. 8 directly.

    Args:
        description: The robot description (shapes and hydrodynamic parameters).
        rho: Water density (kg/m^3).

    Raises:
        DescriptionError: If the hull is not a prolate spheroid but should be one.
    """
    result: list[AddedMass | None] = []
    hull = description.hull
    if description.hull_hydrodynamics.added_mass == 'prolate_spheroid' and hull is not None:
        a, b, c = hull.semi_axes_m
        if not (a > b and abs(b - c) <= 1e-12 * b):
            raise DescriptionError(
                f'{description.urdf_path}: the hull ({2 * a} x {2 * b} x {2 * c} m) must be '
                'a prolate spheroid, longest along x, for added_mass: prolate_spheroid '
                f'({description.hydrodynamics_path})'
            )
        m_f = 4.0 / 3.0 * math.pi * rho * a * b * b
        k1, k2, k_rot = lamb_coefficients(a, b)
        result.append(
            AddedMass(
                center=np.zeros(3),
                axis=np.array([1.0, 0.0, 0.0]),
                rotation=np.eye(3),
                axis_column=0,
                axial_kg=k1 * m_f,
                lateral_kg=k2 * m_f,
                axial_rotary_kg_m2=0.0,
                lateral_rotary_kg_m2=k_rot * m_f * (a * a + b * b) / 5.0,
            )
        )
    else:
        result.append(None)
    for cylinder, hydro in zip(description.links, description.link_hydrodynamics, strict=True):
        if hydro.added_mass != 'slender_cylinder':
            result.append(None)
            continue
        length, radius = cylinder.length_m, cylinder.radius_m
        m_lat = rho * math.pi * radius * radius * length
        k1 = lamb_coefficients(0.5 * length, radius)[0]
        result.append(
            AddedMass(
                center=np.array(cylinder.center_m),
                axis=cylinder.axis,
                rotation=np.reshape(cylinder.rotation, (3, 3)),
                axis_column=2,
                axial_kg=k1 * m_lat,
                lateral_kg=m_lat,
                axial_rotary_kg_m2=0.0,
                lateral_rotary_kg_m2=m_lat * length * length / 12.0,
            )
        )
    return result
