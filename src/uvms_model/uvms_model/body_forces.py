"""External forces on the bodies of the dynamic model (Pinocchio's ``fext``, body frames).

Everything Pinocchio's rigid bodies lack enters here, written into the ``fext`` of the hull
and the arm links at the posed state (after forward kinematics):

- drag (eq. 8, D_b): the hull's quadratic and linear drag per twist component, and the links'
  cross-flow drag, -1/2 rho C_D (2 r) |v_n| v_n per strip (Gauss-Legendre strips along each
  link, v_n the strip's velocity normal to the link axis);
- the added mass's slider corrections (``AddedMass.slider_correction``), quadratic in the
  body twist;
- gravity and buoyancy (G_b): each body's net weight W = m - rho V at its first moment
  h = m c_g - rho V c_b, along the gravity direction in the body frame;
- the force on the end effector (contact), applied at ``ee_link``;
- with an ocean current (``current_base``, ``has_current``): drag on each body's velocity
  relative to the water, nu_r = nu - [u_i; 0], and the added mass's terms turned into their
  relative form (``uvms_model.relative_flow``, Fossen 2011 sec. 8.3). Without one, the kernel
  runs exactly the arithmetic it ran before currents existed (bit-identical results).

Speed: one compiled kernel (``external_forces``, Numba) on preallocated arrays. Every column
of the linear maps touches one body, so each is kept as (body, six numbers): the twists give
every strip's two normal speeds, every linear form p_i . nu of the slider corrections (each
written sum_i lambda_i (p_i . nu)^2 by the eigen-decomposition of its symmetric matrix) and the
hull's linear-drag speeds; the body rotations applied to the gravity direction and the
end-effector force (both in base_link_frd) give their components in every body frame; the
``back`` columns map all of it to the bodies' forces.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin  # type: ignore[import-untyped]
from numpy.typing import NDArray

from uvms_model.added_mass import AddedMass, quadratic_form
from uvms_model.coordinates import Vec3
from uvms_model.description import ROOT_LINK, RobotDescription
from uvms_model.errors import DescriptionError, ModelError
from uvms_model.hydrodynamics import hull_quadratic_drag
from uvms_model.jit import kernel
from uvms_model.kinematics import skew
from uvms_model.parameters import HydrodynamicsParameters
from uvms_model.relative_flow import added_mass_flow_force, flow_in_bodies

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
        volume = description.hull_hydrodynamics.displaced_volume_m3
        if ratio is None:
            assert volume is not None  # one of the two (description._hull_entry)
            ratio = (rho * volume + sum(link_displaced)) / sum(masses)
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


def _hull_drag(description: RobotDescription, rho: float) -> tuple[list[float], list[float]]:
    """The hull's quadratic and linear drag per twist component (eq. 8, D_b).

    ``coefficients``: the file's magnitudes, -(D_q,k |nu_k| + D_l,k) nu_k. Otherwise
    (``prolate_spheroid``, ``none``): C_D on the ellipsoid's areas and silhouette and the
    paper's linear coefficients (docs/model.md).
    """
    hull = description.hull_hydrodynamics
    if hull.added_mass == 'coefficients':
        assert hull.quadratic_damping is not None and hull.linear_damping is not None
        return list(hull.quadratic_damping), list(hull.linear_damping)
    assert description.hull is not None
    a, b = description.hull.semi_axes_m[0], description.hull.semi_axes_m[1]
    quadratic = hull_quadratic_drag(
        a, b, rho, hull.drag_coefficient_translation, hull.drag_coefficient_rotation
    )
    offsets = [hull.linear_drag_translation_n_s_m] * 3 + [hull.linear_drag_rotation_n_m_s] * 3
    return [float(v) for v in quadratic], offsets


class BodyForces:
    """The maps from the posed state to the bodies' external forces, and their workspace.

    Args:
        description: The robot description (shapes, hydrodynamic parameters, ee offset).
        hydro: Hydrodynamic switches and constants.
        added: Added mass of the hull and each arm link (None: none).
        kin: The kinematic model (rigid masses and centres).
        bodies: Joints of the hull and the arm links in the dynamic model (consecutive).
        twists: (njoints, 6) view of the dynamic model's joint twists.
        placements: (njoints, 12) view of its joint placements (rotation column-major, then
            translation).
        forces: (njoints, 6) view of its ``fext``.
        hull_added: M_A (6, 6) of a hull given by coefficients, None otherwise (for the
            current's added-mass terms; the others come from ``added``).
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
        hull_added: FloatArray | None = None,
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
            quadratic, offsets = _hull_drag(description, rho)
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

        # Every column of these maps touches one body's six rows: kept as (body, 6 numbers).
        self._n_linear, self._n_forms, self._n_strips = len(linear), len(forms), len(gains)
        forward = [c for c, _ in linear] + forms + strips_first + strips_second
        back = [c * d for c, d in linear] + scales
        back += [c * g for c, g in zip(strips_first, gains, strict=True)]
        back += [c * g for c, g in zip(strips_second, gains, strict=True)]
        back += list(rotated.T)
        self._forward_body, self._forward = body_columns(forward, count)
        self._back_body, self._back = body_columns(back, count)
        self._values = np.zeros(len(back))
        self._vectors = np.zeros((3, 2))  # [gravity direction, ee force] in base_link_frd
        self._vectors_flat = self._vectors.reshape(-1)
        # The current: v_c in base_link_frd (written by the caller), each body's u_i, and the
        # bodies whose added mass the current's relative form corrects.
        self.current_base = np.zeros(3)
        self.has_current = False
        self._flow = np.zeros((count, 3))
        matrices = [(body, body_added.matrix() if body_added is not None
                     else hull_added if body == 0 else None)
                    for body, body_added in enumerate(added)]
        kept = [(body, m) for body, m in matrices if m is not None and np.any(m != 0.0)]
        self._added_bodies = np.array([body for body, _ in kept], dtype=np.intp)
        self._added_matrices = np.array([m for _, m in kept], dtype=float).reshape(-1, 6, 6)

    def apply(
        self, gravity_body: Vec3, f_ee_body: Vec3 | None, current_body: Vec3 | None = None
    ) -> None:
        """Write every body's external force into ``fext`` at the posed state (after FK).

        Args:
            gravity_body: Gravitational acceleration in base_link_frd (m/s^2).
            f_ee_body: Force ON the end effector in base_link_frd (N), or None.
            current_body: The water's velocity v_c in base_link_frd (m/s), or None (still).
        """
        self.has_current = current_body is not None
        if current_body is not None:
            self.current_base[:] = current_body
        g0, g1, g2 = gravity_body
        if f_ee_body is None:
            self._vectors_flat[:] = (g0, 0.0, g1, 0.0, g2, 0.0)
        else:
            f0, f1, f2 = f_ee_body
            self._vectors_flat[:] = (g0, f0, g1, f1, g2, f2)
        self.apply_vectors(self._vectors)

    def apply_vectors(self, vectors: FloatArray) -> None:
        """``apply`` with [gravity direction, ee force] (3, 2), base_link_frd, as one array.

        The current is ``current_base`` when ``has_current`` is set.
        """
        external_forces(
            self._twists, self._rotations, vectors, self._forward_body, self._forward,
            self._back_body, self._back, self._n_linear, self._n_forms, self._n_strips,
            self._values, self._forces, self.has_current, self.current_base, self._flow,
            self._added_bodies, self._added_matrices,
        )  # fmt: skip


def body_columns(columns: list[FloatArray], n_bodies: int) -> tuple[NDArray[np.intp], FloatArray]:
    """Columns of (6 n_bodies) rows, each nonzero in one body's six rows, as (body, 6 numbers).

    Raises:
        ModelError: If a column touches two bodies.
    """
    bodies = np.zeros(len(columns), dtype=np.intp)
    entries = np.zeros((len(columns), 6))
    for j, column in enumerate(columns):
        blocks = np.reshape(column, (n_bodies, 6))
        touched = np.flatnonzero(np.any(blocks != 0.0, axis=1))
        if len(touched) > 1:
            raise ModelError(f'force map column {j} acts on bodies {touched.tolist()}')
        bodies[j] = touched[0] if len(touched) else 0
        entries[j] = blocks[bodies[j]]
    return bodies, entries


@kernel
def external_forces(
    twists: FloatArray, rotations: FloatArray, vectors: FloatArray,
    forward_body: NDArray[np.intp], forward: FloatArray,
    back_body: NDArray[np.intp], back: FloatArray,
    n_linear: int, n_forms: int, n_strips: int, values: FloatArray, forces: FloatArray,
    has_current: bool, current_base: FloatArray, flow: FloatArray,
    added_bodies: NDArray[np.intp], added_matrices: FloatArray,
) -> None:
    """The bodies' external forces (``forces``, 6 per body) from their twists and rotations.

    ``values``, in the order of the ``back`` columns: the hull's linear-drag speeds, the
    squared linear forms (p_i . nu)^2 of the slider corrections, |v_n| v_n of every strip
    (two normal directions), then the rotated vectors ``rotations @ vectors`` (gravity
    direction and ee force in each body frame, 4 rows a body, the translation row unused).
    Then ``forces = sum_j back_j values_j`` (drag gains, eigenvalues and net weights are in
    ``back``). With ``has_current``, the drag speeds (linear and strips, not the slider forms)
    are taken relative to the water, u_i = ``flow``[i] in body i's frame, and the added mass's
    current terms are added (``relative_flow.added_mass_flow_force``).
    """
    if has_current:
        flow_in_bodies(rotations, current_base, flow)
    for j in range(n_linear + n_forms + 2 * n_strips):
        body = forward_body[j]
        base = 6 * body
        total = 0.0
        if has_current and (j < n_linear or j >= n_linear + n_forms):
            for i in range(3):
                total += (twists[base + i] - flow[body, i]) * forward[j, i]
            for i in range(3, 6):
                total += twists[base + i] * forward[j, i]
        else:
            for i in range(6):
                total += twists[base + i] * forward[j, i]
        values[j] = total
    for j in range(n_linear, n_linear + n_forms):
        values[j] = values[j] * values[j]
    first = n_linear + n_forms
    for j in range(first, first + n_strips):
        a, b = values[j], values[j + n_strips]
        speed = math.sqrt(a * a + b * b)
        values[j] = speed * a
        values[j + n_strips] = speed * b
    start = first + 2 * n_strips
    for row in range(rotations.shape[0]):
        for column in range(2):
            values[start + 2 * row + column] = (
                rotations[row, 0] * vectors[0, column]
                + rotations[row, 1] * vectors[1, column]
                + rotations[row, 2] * vectors[2, column]
            )
    forces[:] = 0.0
    for j in range(values.shape[0]):
        base = 6 * back_body[j]
        value = values[j]
        if value != 0.0:
            for i in range(6):
                forces[base + i] += back[j, i] * value
    if has_current:
        added_mass_flow_force(twists, flow, added_bodies, added_matrices, forces)
