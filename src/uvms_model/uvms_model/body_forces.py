"""External forces on the bodies of the dynamic model (Pinocchio's ``fext``, body frames).

Everything Pinocchio's rigid bodies lack enters here, written into the ``fext`` of the hull
and link_1..3 at the posed state (after forward kinematics):

- drag (eq. 8, D_b): the hull's quadratic and linear drag per twist component, and the links'
  cross-flow drag, -1/2 rho C_D (2 r) |v_n| v_n per strip (Gauss-Legendre strips along each
  link, v_n the strip's velocity normal to the link axis);
- the added mass's slider corrections (``AddedMass.slider_correction``), quadratic in the
  body twist;
- gravity and buoyancy (G_b): each body's net weight W = m - rho V at its first moment
  h = m c_g - rho V c_b, along the gravity direction in the body frame;
- the force on the end effector (contact), applied at ``ee_link``.

Speed: all of it is three matrix products and two elementwise passes on preallocated
arrays. ``twists @ forward`` gives every strip's two normal speeds, every linear form p_i . nu
of the slider corrections (each written sum_i lambda_i (p_i . nu)^2 by the eigen-decomposition
of its symmetric matrix) and the hull's linear-drag speeds; the body rotations applied to the
gravity direction and the end-effector force (both in base_link_frd) give their components in
every body frame; one ``back @ (...)`` maps all of it to the bodies' forces.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin  # type: ignore[import-untyped]
from numpy.typing import NDArray

from uvms_model.added_mass import AddedMass, quadratic_form
from uvms_model.coordinates import Vec3
from uvms_model.description import ROOT_LINK, RobotDescription
from uvms_model.errors import DescriptionError, ModelError
from uvms_model.hydrodynamics import hull_quadratic_drag
from uvms_model.kinematics import skew
from uvms_model.parameters import HydrodynamicsParameters

FloatArray = NDArray[np.float64]


def net_weights(
    description: RobotDescription, hydro: HydrodynamicsParameters, kin: pin.Model
) -> tuple[list[float], list[FloatArray], float]:
    """Net weights W_i = m_i - rho V_i (kg), first moments h_i (kg m) and the hull's rho V.

    Buoyancy acts at the centre of the displaced volume: h_i = m_i c_g,i - rho V_i c_b,i in
    the body frame. The hull displaces ``buoyancy_ratio`` times the total mass less what the
    links displace.

    Raises:
        DescriptionError: If the buoyancy ratio is below what the links alone provide.
    """
    rho = hydro.water_density_kg_m3
    masses = [kin.inertias[i].mass for i in range(1, kin.njoints)]
    levers = [np.asarray(kin.inertias[i].lever) for i in range(1, kin.njoints)]
    if hydro.buoyancy_enabled:
        link_displaced = [rho * cylinder.volume_m3 for cylinder in description.links]
        ratio = description.hull_hydrodynamics.buoyancy_ratio
        hull_displaced = ratio * sum(masses) - sum(link_displaced)
        if hull_displaced < 0.0:
            floor = sum(link_displaced) / sum(masses)
            raise DescriptionError(
                f'{description.hydrodynamics_path}: {ROOT_LINK}.buoyancy_ratio = {ratio!r} is '
                f'below what the links alone provide ({floor:.4g}); valid range '
                f'[{floor:.4g}, 10.0]'
            )
    else:
        link_displaced = [0.0] * len(description.links)
        hull_displaced = 0.0
    centres = [np.array(description.hull_hydrodynamics.center_of_buoyancy_m)] + [
        np.array(cylinder.center_m) for cylinder in description.links
    ]
    displaced = [hull_displaced, *link_displaced]
    weights = [m - d for m, d in zip(masses, displaced, strict=True)]
    moments = [
        m * c - d * b for m, c, d, b in zip(masses, levers, displaced, centres, strict=True)
    ]
    return weights, moments, hull_displaced


class BodyForces:
    """The maps from the posed state to the bodies' external forces, and their workspace.

    Args:
        description: The robot description (shapes, hydrodynamic parameters, ee offset).
        hydro: Hydrodynamic switches and constants.
        added: Added mass of the hull and link_1..3 (None: none).
        kin: The kinematic model (rigid masses and centres).
        bodies: Joints of the hull and link_1..3 in the dynamic model (consecutive).
        twists: (njoints, 6) view of the dynamic model's joint twists.
        placements: (njoints, 12) view of its joint placements (rotation column-major, then
            translation).
        forces: (njoints, 6) view of its ``fext``.
    """

    def __init__(
        self,
        description: RobotDescription,
        hydro: HydrodynamicsParameters,
        added: list[AddedMass | None],
        kin: pin.Model,
        bodies: list[int],
        twists: FloatArray,
        placements: FloatArray,
        forces: FloatArray,
    ) -> None:
        first_body, count = bodies[0], len(bodies)
        if bodies != list(range(first_body, first_body + count)):
            raise ModelError(f'the bodies {bodies} are not consecutive joints')
        span = slice(first_body, first_body + count)
        self._twists = twists[span].reshape(-1)  # views (rows are contiguous)
        self._forces = forces[span].reshape(-1)
        # Per body, the rotation read row-major is rot_body_from_base: rows 0-2 of each
        # 4 x 3 block; row 3 is the translation (its products are never used).
        self._rotations = placements[span].reshape(4 * count, 3)
        if not (
            np.shares_memory(self._twists, twists)
            and np.shares_memory(self._forces, forces)
            and np.shares_memory(self._rotations, placements)
        ):
            raise ModelError('Pinocchio data rows are not contiguous')
        n_rows = 6 * count
        rho = hydro.water_density_kg_m3
        strips_first: list[FloatArray] = []  # twist . column = first normal speed
        strips_second: list[FloatArray] = []
        gains: list[float] = []
        linear: list[tuple[FloatArray, float]] = []
        if hydro.drag_enabled:
            hull = description.hull_hydrodynamics
            a, b = description.hull.semi_axes_m[0], description.hull.semi_axes_m[1]
            quadratic = hull_quadratic_drag(
                a, b, rho, hull.drag_coefficient_translation, hull.drag_coefficient_rotation
            )
            offsets = [hull.linear_drag_translation_n_s_m] * 3
            offsets += [hull.linear_drag_rotation_n_m_s] * 3
            for k in range(6):  # the hull: -(D_k |nu_k| + d_k) nu_k per twist component
                column = np.zeros(n_rows)
                column[k] = 1.0
                if quadratic[k] != 0.0:
                    strips_first.append(column)
                    strips_second.append(np.zeros(n_rows))
                    gains.append(-float(quadratic[k]))
                if offsets[k] != 0.0:
                    linear.append((column, -float(offsets[k])))
            xi, weights = np.polynomial.legendre.leggauss(hydro.drag_strips_per_link)
            for body, (cylinder, params) in enumerate(
                zip(description.links, description.link_hydrodynamics, strict=True), start=1
            ):
                if params.cross_flow_drag_coefficient == 0.0:
                    continue
                rot = np.reshape(cylinder.rotation, (3, 3))
                centre, axis = np.array(cylinder.center_m), rot[:, 2]
                gain = 0.5 * rho * params.cross_flow_drag_coefficient * 2.0 * cylinder.radius_m
                for s, weight in zip(0.5 * cylinder.length_m * xi, weights, strict=True):
                    point = centre + s * axis
                    for normal, columns in ((rot[:, 0], strips_first), (rot[:, 1], strips_second)):
                        column = np.zeros(n_rows)
                        column[6 * body : 6 * body + 3] = normal
                        column[6 * body + 3 : 6 * body + 6] = np.cross(point, normal)
                        columns.append(column)
                    # dF = -1/2 rho C_D (2 r) |v_n| v_n dx over the strip of width dx.
                    gains.append(-gain * 0.5 * cylinder.length_m * float(weight))
        forms: list[FloatArray] = []  # linear forms p_i of the corrections ...
        scales: list[FloatArray] = []  # ... and where lambda_i (p_i . nu)^2 goes
        for body, body_added in enumerate(added):
            if body_added is None or body_added.lateral_kg == body_added.axial_kg:
                continue
            tensor = quadratic_form(body_added.slider_correction)
            tolerance = 1e-13 * max(float(np.abs(tensor).max()), 1e-300)
            for component in range(6):
                values, vectors = np.linalg.eigh(tensor[component])
                for value, vector in zip(values, vectors.T, strict=True):
                    if abs(value) <= tolerance:
                        continue
                    form = np.zeros(n_rows)
                    form[6 * body : 6 * body + 6] = vector
                    scale = np.zeros(n_rows)
                    scale[6 * body + component] = value
                    forms.append(form)
                    scales.append(scale)
        # Gravity direction (column 0) and end-effector force (column 1) in every body frame.
        weights_kg, moments_kg_m, self.hull_displaced_mass_kg = net_weights(
            description, hydro, kin
        )
        tip = count - 1
        ee_offset = np.asarray(description.ee_offset_m, dtype=float)
        rotated = np.zeros((n_rows, 4 * count * 2))
        for body in range(count):
            for r in range(3):
                gravity = 2 * (4 * body + r)
                rotated[6 * body + r, gravity] = weights_kg[body]
                rotated[6 * body + 3 : 6 * body + 6, gravity] = skew(moments_kg_m[body])[:, r]
        for r in range(3):
            force = 2 * (4 * tip + r) + 1
            rotated[6 * tip + r, force] = 1.0
            rotated[6 * tip + 3 : 6 * tip + 6, force] = skew(ee_offset)[:, r]

        # Buffer: [linear | forms, first, second | rotated | forms again, speed, speed].
        # One product fills it up to the repeated forms (zeros where the rotated vectors
        # go, written next), hypot the speeds, and one elementwise product then makes
        # [forms^2, |v_n| first, |v_n| second] in place; ``back`` reads up to the rotated.
        n, n_forms, n_linear = len(gains), len(forms), len(linear)
        n_rotated = rotated.shape[1]
        n_products = n_forms + 2 * n
        forward = [c for c, _ in linear] + forms + strips_first + strips_second
        forward += [np.zeros(n_rows)] * n_rotated + forms
        back = [c * d for c, d in linear] + scales
        back += [c * g for c, g in zip(strips_first, gains, strict=True)]
        back += [c * g for c, g in zip(strips_second, gains, strict=True)]
        self._back = np.ascontiguousarray(np.column_stack([*back, rotated]))
        self._has_forward = n_linear + n_products > 0
        self._forward = np.column_stack(forward) if self._has_forward else np.zeros((n_rows, 0))
        self._buffer = np.zeros(self._back.shape[1] + n_products)
        self._back_in = self._buffer[: self._back.shape[1]]
        self._products_in = self._buffer[: self._forward.shape[1]]
        self._products = self._buffer[n_linear : n_linear + n_products]
        self._multipliers = self._buffer[n_linear + n_products + n_rotated :]
        self._first = self._buffer[n_linear + n_forms : n_linear + n_forms + n]
        self._second = self._buffer[n_linear + n_forms + n : n_linear + n_products]
        speeds = self._multipliers[n_forms:].reshape(2, n)
        self._speed, self._speed_again = speeds[0], speeds[1]
        rotated_start = n_linear + n_products
        self._rotated = self._buffer[rotated_start : rotated_start + n_rotated].reshape(-1, 2)
        self._has_products = n_products > 0
        self._vectors = np.zeros((3, 2))  # [gravity direction, ee force] in base_link_frd
        self._vectors_flat = self._vectors.reshape(-1)

    def apply(self, gravity_body: Vec3, f_ee_body: Vec3 | None) -> None:
        """Write every body's external force into ``fext`` at the posed state (after FK).

        Args:
            gravity_body: Gravitational acceleration in base_link_frd (m/s^2).
            f_ee_body: Force ON the end effector in base_link_frd (N), or None.
        """
        if self._has_forward:
            np.dot(self._twists, self._forward, out=self._products_in)
            if self._has_products:
                np.hypot(self._first, self._second, out=self._speed)
                self._speed_again[:] = self._speed
                self._products *= self._multipliers
        g0, g1, g2 = gravity_body
        if f_ee_body is None:
            self._vectors_flat[:] = (g0, 0.0, g1, 0.0, g2, 0.0)
        else:
            f0, f1, f2 = f_ee_body
            self._vectors_flat[:] = (g0, f0, g1, f1, g2, f2)
        np.dot(self._rotations, self._vectors, out=self._rotated)
        np.dot(self._back, self._back_in, out=self._forces)
