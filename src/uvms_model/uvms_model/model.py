"""UVMS dynamics (paper eq. 8, 18-20, 22-23) on Pinocchio, from the robot's URDF.

Pinocchio builds two models, once, from the URDF text (``uvms_model.description``) with a
free-flyer root, and each keeps one preallocated ``Data`` workspace:

- the *kinematic* model is the URDF as written (frames ``base_link_frd``, ``link_1..3``,
  ``ee_link``, ``ft_sensor_link``); its free-flyer velocity is the body twist [v; omega] in
  ``base_link_frd``, i.e. the first six quasi-velocities w of eq. 8;
- the *dynamic* model adds the added mass of the water each body entrains (Kirchhoff's
  equations of a body in ideal fluid: M_A is part of the body's inertia, never a force from a
  past acceleration).

Added mass in Pinocchio. Each body's added mass is axisymmetric about its shape's axis e
through its centre c: axial a_ax, lateral a_lat (a_ax < a_lat for the prolate hull and the
slender links), rotary j_ax, j_lat. Pinocchio's inertias are rigid-body ones (the same mass in
every direction), so the added mass is split: a rigid part of mass a_ax at c with the rotary
terms, fixed to the body, and the lateral excess m_s = a_lat - a_ax as a point mass at c on a
frictionless *slider* (a prismatic joint along e) held at rest. A free slider at zero speed
transmits no axial force: eliminating its acceleration leaves exactly the lateral-only inertia
m_s (I - e e^T) at c, so the articulated-body algorithm (ABA), CRBA and RNEA of this model
produce the mass matrix M_b = M_RB + sum_i J_i^T M_A,i J_i of eq. 8 with no approximation. The
velocity terms of the two differ (the slider's point mass has no moment of momentum); their
difference, quadratic in the body twist, is applied as an external force.

Everything else is ours and enters as external body forces (Pinocchio's ``fext``, in each
body's frame): gravity and buoyancy (net weights W_i = m_i - rho V_i with their first moments),
the hull's linear and quadratic drag, the links' cross-flow strip drag, and the contact force
on the end effector. The dynamic model is posed with its base at the origin of
``base_link_frd``, so "world" is the body frame and the attitude enters through the gravity
direction only.

Pinocchio's terse names, glossed: ``oMi`` placement of joint i in the world (o: origin),
``oMf`` the same for frames, ``v``/``a`` joint twists/accelerations in their local frames,
``crba`` composite-rigid-body algorithm (mass matrix, upper triangle), ``rnea`` recursive
Newton-Euler (inverse dynamics), ``aba`` articulated-body algorithm (forward dynamics),
``LOCAL_WORLD_ALIGNED`` a frame's origin with the world's axes.

Speed: the per-evaluation work is a fixed handful of compiled calls on preallocated arrays.
The twists, placements and external forces of all joints are read and written through one
strided numpy view each (Pinocchio keeps them contiguous; checked at construction), so no
per-call Pinocchio objects are built.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import pinocchio as pin  # type: ignore[import-untyped]
from numpy.typing import ArrayLike, NDArray

from uvms_model.description import (
    ARM_LINKS,
    EE_LINK,
    ROOT_LINK,
    SENSOR_LINK,
    RobotDescription,
    load_description,
)
from uvms_model.errors import DescriptionError, ModelError, StateError, UnreachableError
from uvms_model.hydrodynamics import hull_quadratic_drag, lamb_coefficients
from uvms_model.kinematics import check_pitch
from uvms_model.parameters import UvmsParameters

FloatArray = NDArray[np.float64]

N_JOINTS = 3
N_DOF = 6 + N_JOINTS
FRAME_NAMES = (ROOT_LINK, *ARM_LINKS, EE_LINK, SENSOR_LINK)
"""Frames of ``UvmsModel.frame_poses``, all posed in map_ned."""

Vec3 = tuple[float, float, float]
Mat3 = tuple[float, float, float, float, float, float, float, float, float]  # row-major


class TaskSpaceTerms(NamedTuple):
    """What the controller needs at one state (q, q_dot), from one pass of the model.

    Attributes:
        X: End-effector position in map_ned (3,) (m).
        J: End-effector Jacobian (3, 9) in map_ned with respect to q_dot (eq. 22).
        J_dot_q_dot: J_dot q_dot (3,) (m/s^2), eq. 23.
        M: Mass matrix M(q) (9, 9) in generalized coordinates (eq. 18).
        zeta: Bias zeta(q, q_dot) (9,) of eq. 19.
        B: Velocity transform B(q) (9, 9) of eq. 4.
        rot_ned_from_ee: ee_link axes in map_ned (3, 3).
        q_dot: Generalized velocities (9,) of the state.
    """

    X: FloatArray
    J: FloatArray
    J_dot_q_dot: FloatArray
    M: FloatArray
    zeta: FloatArray
    B: FloatArray
    rot_ned_from_ee: FloatArray
    q_dot: FloatArray


def _vector(name: str, value: ArrayLike, size: int) -> FloatArray:
    """Return ``value`` as a finite float vector of ``size`` or raise StateError naming it."""
    array = np.asarray(value, dtype=float)
    if array.shape != (size,):
        raise StateError(f'{name} must have shape ({size},), got {array.shape}')
    if not math.isfinite(sum(array.tolist())):  # sum of floats: cheaper than ndarray.sum
        raise StateError(f'{name} must be finite, got {array.tolist()!r}')
    return array


def _cross(a: Sequence[float], b: Sequence[float]) -> Vec3:
    """Cross product of two 3-vectors given as Python sequences."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _skew(v: Sequence[float] | FloatArray) -> FloatArray:
    """[v]x with [v]x u = v x u."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _rotation(phi: float, theta: float, psi: float) -> Mat3:
    """rot_ned_from_body (J1 of sec. 3.2), row-major, as plain floats."""
    c4, s4 = math.cos(phi), math.sin(phi)
    c5, s5 = math.cos(theta), math.sin(theta)
    c6, s6 = math.cos(psi), math.sin(psi)
    return (
        c5 * c6, -s6 * c4 + s4 * s5 * c6, s4 * s6 + s5 * c4 * c6,
        s6 * c5, c4 * c6 + s4 * s5 * s6, -s4 * c6 + s5 * s6 * c4,
        -s5, s4 * c5, c4 * c5,
    )  # fmt: skip


def _quaternion_xyzw(phi: float, theta: float, psi: float) -> tuple[float, float, float, float]:
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


def _mat_vec(r: Sequence[float], v: Sequence[float]) -> Vec3:
    return (
        r[0] * v[0] + r[1] * v[1] + r[2] * v[2],
        r[3] * v[0] + r[4] * v[1] + r[5] * v[2],
        r[6] * v[0] + r[7] * v[1] + r[8] * v[2],
    )


def _mat_t_vec(r: Sequence[float], v: Sequence[float]) -> Vec3:
    return (
        r[0] * v[0] + r[3] * v[1] + r[6] * v[2],
        r[1] * v[0] + r[4] * v[1] + r[7] * v[2],
        r[2] * v[0] + r[5] * v[1] + r[8] * v[2],
    )


def _rows(elements: Sequence[FloatArray], width: int) -> FloatArray:
    """One (n, width) view over equally spaced per-joint Eigen vectors of a Pinocchio Data.

    Pinocchio stores a joint quantity (twists, placements, forces) in one std::vector, so the
    rows lie at a fixed stride; a view over all of them reads or writes every joint in one
    numpy operation. The addresses are checked: a layout that is not a plain array raises.
    """
    addresses = [array.__array_interface__['data'][0] for array in elements]
    stride = addresses[1] - addresses[0]
    if any(b - a != stride for a, b in itertools.pairwise(addresses)) or any(
        array.strides[0] != 8 for array in elements
    ):
        raise ModelError('Pinocchio data is not laid out as one array per quantity')
    first = elements[0]
    view: FloatArray = np.lib.stride_tricks.as_strided(
        first, shape=(len(elements), width), strides=(stride, 8), writeable=True
    )
    return view


class _AddedMass(NamedTuple):
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
        c = self.center
        cx = _skew(c)
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


def _quadratic_form(function: object, size: int = 6) -> FloatArray:
    """Tensor Q (n, size, size) with f(x) = x^T Q_j x for a quadratic map f (polarization)."""
    f = function  # a callable of a (size,) array returning (n,)
    basis = np.eye(size)
    single = [np.asarray(f(basis[a])) for a in range(size)]  # type: ignore[operator]
    n = single[0].size
    q = np.zeros((n, size, size))
    for a in range(size):
        q[:, a, a] = single[a]
        for b in range(a + 1, size):
            both = np.asarray(f(basis[a] + basis[b]))  # type: ignore[operator]
            q[:, a, b] = q[:, b, a] = 0.5 * (both - single[a] - single[b])
    return q


class UvmsModel:
    """Dynamics and kinematics of the UVMS of the paper (sec. 3 and 5.1), from its URDF.

    Coordinates (docs/model.md): q = [x, y, z, phi, theta, psi, q1, q2, q3] with the vehicle
    origin in map_ned and ZYX Euler angles; quasi-velocities w = [u, v, w, p, q, r, q1_dot,
    q2_dot, q3_dot] in base_link_frd; q_dot = B(q) w (eq. 4). Arrays returned are new arrays
    owned by the caller. Not thread-safe (one Pinocchio workspace per instance).

    Args:
        params: Environment, switches and the description's paths (``description.*``).
        description: The robot description; None reads the files ``params`` names.

    Raises:
        DescriptionError: For a missing, malformed or incomplete description.

    Example:
        >>> model = UvmsModel()
        >>> q = np.zeros(9); w = np.zeros(9); tau_b = np.zeros(9)
        >>> q, w = model.step(q, w, tau_b, None, 1e-3)
    """

    n_dof: int = N_DOF
    n_joints: int = N_JOINTS

    def __init__(
        self, params: UvmsParameters | None = None, description: RobotDescription | None = None
    ) -> None:
        self.params = params if params is not None else UvmsParameters()
        p = self.params
        if description is None:
            description = load_description(
                p.description.urdf_path, p.description.hydrodynamics_path
            )
        self.description = description
        self.joint_names: tuple[str, ...] = description.joint_names
        self._method = p.integration.method
        self._kin = self._build_kinematics(description)
        self._kin_data = self._kin.createData()
        self._frame_ids = {name: self._kin.getFrameId(name) for name in FRAME_NAMES}
        self._ee_frame = self._frame_ids[EE_LINK]
        # Kinematic configuration [p (3), quaternion x y z w (4), q_m (3)], reused.
        self._q_kin = pin.neutral(self._kin)
        self._zero_v = np.zeros(N_DOF)
        self._build_dynamics(description)

    # ------------------------------------------------------------------ construction

    @staticmethod
    def _build_kinematics(description: RobotDescription) -> pin.Model:
        """Pinocchio model of the URDF as written, free-flyer root (base_link_frd)."""
        try:
            model = pin.buildModelFromXML(description.urdf_text, pin.JointModelFreeFlyer())
        except (ValueError, RuntimeError) as exc:
            raise DescriptionError(
                f'{description.urdf_path}: Pinocchio cannot build a model: {exc}'
            ) from exc
        names = tuple(model.names)[2:]
        if names != description.joint_names:
            raise DescriptionError(
                f'{description.urdf_path}: Pinocchio found the joints {list(names)}, expected '
                f'{list(description.joint_names)}'
            )
        for frame in FRAME_NAMES:
            if not model.existFrame(frame):
                raise DescriptionError(f"{description.urdf_path}: no frame '{frame}'")
        return model

    def _added_masses(self, description: RobotDescription) -> list[_AddedMass | None]:
        """Added mass of the hull and the links from their collision geometry (or None)."""
        rho = self.params.hydrodynamics.water_density_kg_m3
        result: list[_AddedMass | None] = []
        hull = description.hull
        if description.hull_hydrodynamics.added_mass == 'prolate_spheroid':
            a, b, c = hull.semi_axes_m
            if not (a > b and abs(b - c) <= 1e-12 * b):
                raise DescriptionError(
                    f'{description.urdf_path}: the hull ({2 * a} x {2 * b} x {2 * c} m) must be '
                    'a prolate spheroid, longest along x, for added_mass: prolate_spheroid '
                    f'({description.hydrodynamics_path})'
                )
            m_f = 4.0 / 3.0 * math.pi * rho * a * b * b
            k1, k2, k_rot = lamb_coefficients(a, b)
            hull_added = _AddedMass(
                center=np.zeros(3),
                axis=np.array([1.0, 0.0, 0.0]),
                rotation=np.eye(3),
                axis_column=0,
                axial_kg=k1 * m_f,
                lateral_kg=k2 * m_f,
                axial_rotary_kg_m2=0.0,
                lateral_rotary_kg_m2=k_rot * m_f * (a * a + b * b) / 5.0,
            )
            result.append(hull_added)
        else:
            result.append(None)
        for cylinder, hydro in zip(description.links, description.link_hydrodynamics, strict=True):
            if hydro.added_mass != 'slender_cylinder':
                result.append(None)
                continue
            length, radius = cylinder.length_m, cylinder.radius_m
            m_lat = rho * math.pi * radius * radius * length
            k1 = lamb_coefficients(0.5 * length, radius)[0]
            link_added = _AddedMass(
                center=np.array(cylinder.center_m),
                axis=cylinder.axis,
                rotation=np.reshape(cylinder.rotation, (3, 3)),
                axis_column=2,
                axial_kg=k1 * m_lat,
                lateral_kg=m_lat,
                axial_rotary_kg_m2=0.0,
                lateral_rotary_kg_m2=m_lat * length * length / 12.0,
            )
            result.append(link_added)
        return result

    def _build_dynamics(self, description: RobotDescription) -> None:
        """The dynamic models (rigid bodies + added mass), their workspaces and force maps."""
        hydro = self.params.hydrodynamics
        added: list[_AddedMass | None] = (
            self._added_masses(description) if hydro.added_mass_enabled else [None] * 4
        )
        self.added_mass_vehicle: FloatArray = (
            added[0].matrix() if added[0] is not None else np.zeros((6, 6))
        )
        """Added-mass matrix M_A (6, 6) of the hull at O, base_link_frd axes."""
        self.added_mass_links: FloatArray = np.array(
            [a.matrix() if a is not None else np.zeros((6, 6)) for a in added[1:]]
        )
        """Added-mass matrices (3, 6, 6) of the links at their joint, link axes."""
        # The fast model puts the sliders after the bodies' joints, so that w, tau_b and
        # w_dot are its first nine velocities; ABA and RNEA take any joint order. CRBA needs
        # the depth-first order (each subtree one span of velocities): a twin model has it.
        self._dyn, bodies, _ = self._dynamic_model(description, added, sliders_last=True)
        dfs, bodies_dfs, sliders_dfs = self._dynamic_model(
            description, added, sliders_last=False
        )
        self._dyn_dfs, self._dyn_dfs_data = dfs, dfs.createData()
        # CRBA fills the upper triangle U of the twin's mass matrix (column-major). One take
        # of these indices gives the full symmetric matrix in the fast model's order: the
        # nine quasi-velocities, then the sliders.
        order = [*range(6), *(dfs.idx_vs[b] for b in bodies_dfs[1:])]
        order += [dfs.idx_vs[j] for j in sliders_dfs]
        size = dfs.nv
        self._mass_take = np.array(
            [[min(i, j) + size * max(i, j) for j in order] for i in order], dtype=np.intp
        )
        self._mass_upper = self._dyn_dfs_data.M.T.reshape(-1)  # a view: U column by column
        slider_masses = [
            dfs.inertias[j].mass for j in sliders_dfs
        ]  # M_ss is diagonal and constant: each slider carries its point mass only
        self._slider_mass_inverse = 1.0 / np.array(slider_masses)
        self._q_dfs = pin.neutral(dfs)
        self._arm_q_dfs = tuple(int(dfs.idx_qs[b]) for b in bodies_dfs[1:])

        dyn = self._dyn
        data = dyn.createData()
        self._dyn_data = data
        n_bodies = dyn.njoints
        self._q_dyn = pin.neutral(dyn)  # base at the origin with identity attitude, always
        self._v_dyn = np.zeros(dyn.nv)
        self._v_body = self._v_dyn[:N_DOF]  # views: the quasi-velocities w ...
        self._tau_dyn = np.zeros(dyn.nv)
        self._tau_body = self._tau_dyn[:N_DOF]  # ... and the generalized body forces tau_b
        self._tau_b = np.zeros(N_DOF)
        self._zero_dyn = np.zeros(dyn.nv)
        self._fext = pin.StdVec_Force()
        for _ in range(n_bodies):
            self._fext.append(pin.Force.Zero())
        pin.forwardKinematics(dyn, data, self._q_dyn, self._v_dyn)
        self._twists = _rows([data.v[k].vector for k in range(n_bodies)], 6)
        self._twist_flat = self._twists.reshape(-1)  # contiguous (48-byte rows): a view
        # Each placement row: rotation column-major (9) then translation (3); read row-major
        # the rotation block is rot_world_from_joint transposed, rot_joint_from_world.
        self._placements = _rows([data.oMi[k].rotation[:, 0] for k in range(n_bodies)], 12)
        self._forces = _rows([self._fext[k].vector for k in range(n_bodies)], 6)
        self._force_flat = self._forces.reshape(-1)
        self._tip = bodies[-1]
        self._tip_rotation = self._placements[self._tip, :9]
        self._tip_force = self._forces[self._tip]
        self._ee_offset = description.ee_offset_m
        self._build_restoring(description, bodies)
        self._build_velocity_forces(description, added, bodies)

    def _dynamic_model(
        self,
        description: RobotDescription,
        added: list[_AddedMass | None],
        *,
        sliders_last: bool,
    ) -> tuple[pin.Model, list[int], list[int]]:
        """Pinocchio model of the rigid bodies with their added mass (rigid part + slider).

        Returns:
            The model, the joints of the hull and link_1..3, and the sliders' joints.
        """
        kin = self._kin
        dyn = pin.Model()
        dyn.gravity = pin.Motion.Zero()  # gravity and buoyancy are applied separately
        new_id = {0: 0}
        bodies: list[int] = []
        pending: list[tuple[int, _AddedMass]] = []
        sliders: list[int] = []

        def add_slider(joint: int, body_added: _AddedMass) -> None:
            slider = dyn.addJoint(
                joint,
                pin.JointModelPrismaticUnaligned(body_added.axis),
                pin.SE3(np.eye(3), body_added.center),
                f'{dyn.names[joint]}_added_mass_slider',
            )
            excess = body_added.lateral_kg - body_added.axial_kg
            dyn.appendBodyToJoint(
                slider, pin.Inertia(excess, np.zeros(3), np.zeros((3, 3))), pin.SE3.Identity()
            )
            sliders.append(slider)

        for i in range(1, kin.njoints):
            joint = dyn.addJoint(
                new_id[kin.parents[i]], kin.joints[i], kin.jointPlacements[i], kin.names[i]
            )
            new_id[i] = joint
            dyn.appendBodyToJoint(joint, kin.inertias[i], pin.SE3.Identity())
            bodies.append(joint)
            body_added = added[i - 1]
            if body_added is None:
                continue
            dyn.appendBodyToJoint(
                joint,
                pin.Inertia(body_added.axial_kg, body_added.center, body_added.rigid_rotary()),
                pin.SE3.Identity(),
            )
            if body_added.lateral_kg < body_added.axial_kg:
                raise DescriptionError(
                    f'{description.urdf_path}: body of {kin.names[i]}: axial added mass above '
                    'the lateral one (an oblate shape) is not supported'
                )
            if body_added.lateral_kg > body_added.axial_kg:
                if sliders_last:
                    pending.append((joint, body_added))
                else:
                    add_slider(joint, body_added)
        for joint, body_added in pending:
            add_slider(joint, body_added)
        return dyn, bodies, sliders

    def _build_restoring(self, description: RobotDescription, bodies: list[int]) -> None:
        """Pinocchio model(s) whose generalized gravity is G_b: net weights of the bodies.

        Each body weighs W = m - rho V with first moment m c_g - rho V c_b (buoyancy acts at
        the centre of the displaced volume). One model carries the net weights; should one be
        zero (a neutral body has no centre of net weight), weights and buoyancies go to two
        models instead, the second with its gravity reversed.
        """
        hydro = self.params.hydrodynamics
        rho = hydro.water_density_kg_m3
        kin = self._kin
        masses = [kin.inertias[i].mass for i in range(1, kin.njoints)]
        levers = [np.asarray(kin.inertias[i].lever) for i in range(1, kin.njoints)]
        volumes = [cylinder.volume_m3 for cylinder in description.links]
        if hydro.buoyancy_enabled:
            link_displaced = [rho * volume for volume in volumes]
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
            link_displaced = [0.0] * N_JOINTS
            hull_displaced = 0.0
        self.hull_displaced_mass_kg = hull_displaced
        """Mass of water displaced by the hull (kg), set by the hull's ``buoyancy_ratio``."""
        centres = [np.array(description.hull_hydrodynamics.center_of_buoyancy_m)] + [
            np.array(cylinder.center_m) for cylinder in description.links
        ]
        displaced = [hull_displaced, *link_displaced]
        g = hydro.gravity_m_s2
        wet = [m - d for m, d in zip(masses, displaced, strict=True)]
        terms = list(zip(wet, masses, levers, displaced, centres, strict=True))
        if all(abs(w) > 1e-9 * max(m, d, 1.0) for w, m, _, d, _ in terms):
            moments = [m * c - d * b for _, m, c, d, b in terms]
            sets = [(wet, [h / w for h, w in zip(moments, wet, strict=True)], g)]
        else:
            sets = [(masses, levers, g), (displaced, centres, -g)]
        self._restoring: list[tuple[pin.Model, object, FloatArray]] = []
        for weights, points, gravity in sets:
            model = pin.Model()
            model.gravity = pin.Motion(np.array([0.0, 0.0, gravity, 0.0, 0.0, 0.0]))
            for i in range(1, kin.njoints):
                joint = model.addJoint(
                    kin.parents[i], kin.joints[i], kin.jointPlacements[i], kin.names[i]
                )
                # Set, not appended: appending sums inertias through their total mass, which
                # a net weight may cancel (the neutral hull's is negative).
                model.inertias[joint] = pin.Inertia(
                    weights[i - 1], np.asarray(points[i - 1]), np.zeros((3, 3))
                )
            self._restoring.append((model, model.createData(), pin.neutral(model)))
        self._restoring_first = self._restoring[0]
        self._restoring_pair = len(self._restoring) == 2

    def _build_velocity_forces(
        self, description: RobotDescription, added: list[_AddedMass | None], bodies: list[int]
    ) -> None:
        """Maps of the forces that depend on the body twists: drag and slider corrections.

        One product ``twists @ forward`` gives every drag strip's two normal speeds and every
        linear form of the slider corrections; after the elementwise drag law and squares,
        one product ``back @ (...)`` gives every body's force. The corrections are quadratic
        in the twist: each component is written sum_i lambda_i (p_i . nu)^2 by the
        eigen-decomposition of its symmetric matrix.
        """
        hydro = self.params.hydrodynamics
        rho = hydro.water_density_kg_m3
        n_rows = 6 * self._dyn.njoints
        first: list[FloatArray] = []  # strip columns: twist . column = first normal speed
        second: list[FloatArray] = []
        gains: list[float] = []
        offsets: list[float] = []
        if hydro.drag_enabled:
            hull = description.hull_hydrodynamics
            a, b = description.hull.semi_axes_m[0], description.hull.semi_axes_m[1]
            quadratic = hull_quadratic_drag(
                a, b, rho, hull.drag_coefficient_translation, hull.drag_coefficient_rotation
            )
            linear = [hull.linear_drag_translation_n_s_m] * 3 + [
                hull.linear_drag_rotation_n_m_s
            ] * 3
            base = bodies[0]
            for k in range(6):  # the hull: D_k |nu_k| nu_k + d_k nu_k per twist component
                column = np.zeros(n_rows)
                column[6 * base + k] = 1.0
                first.append(column)
                second.append(np.zeros(n_rows))
                gains.append(-float(quadratic[k]))
                offsets.append(-float(linear[k]))
            xi, weights = np.polynomial.legendre.leggauss(hydro.drag_strips_per_link)
            for cylinder, params, joint in zip(
                description.links, description.link_hydrodynamics, bodies[1:], strict=True
            ):
                if params.cross_flow_drag_coefficient == 0.0:
                    continue
                rot = np.reshape(cylinder.rotation, (3, 3))
                centre, axis = np.array(cylinder.center_m), rot[:, 2]
                gain = 0.5 * rho * params.cross_flow_drag_coefficient * 2.0 * cylinder.radius_m
                for s, weight in zip(0.5 * cylinder.length_m * xi, weights, strict=True):
                    point = centre + s * axis
                    for normal, columns in ((rot[:, 0], first), (rot[:, 1], second)):
                        column = np.zeros(n_rows)
                        column[6 * joint : 6 * joint + 3] = normal
                        column[6 * joint + 3 : 6 * joint + 6] = np.cross(point, normal)
                        columns.append(column)
                    # dF = -1/2 rho C_D (2 r) |v_n| v_n dx over the strip of width dx.
                    gains.append(-gain * 0.5 * cylinder.length_m * float(weight))
                    offsets.append(0.0)
        forms: list[FloatArray] = []  # linear forms p_i of the corrections ...
        scales: list[FloatArray] = []  # ... and where lambda_i (p_i . nu)^2 goes
        for body_added, joint in zip(added, bodies, strict=True):
            if body_added is None or body_added.lateral_kg == body_added.axial_kg:
                continue
            tensor = _quadratic_form(body_added.slider_correction)
            tolerance = 1e-13 * max(float(np.abs(tensor).max()), 1e-300)
            for component in range(6):
                values, vectors = np.linalg.eigh(tensor[component])
                for value, vector in zip(values, vectors.T, strict=True):
                    if abs(value) <= tolerance:
                        continue
                    form = np.zeros(n_rows)
                    form[6 * joint : 6 * joint + 6] = vector
                    scale = np.zeros(n_rows)
                    scale[6 * joint + component] = value
                    forms.append(form)
                    scales.append(scale)
        n = len(gains)
        self._velocity_forces = bool(n or forms)
        if not self._velocity_forces:
            return
        self._forward = np.column_stack(first + second + forms)
        self._back = np.column_stack(first + second + scales)
        buffer = np.zeros(self._forward.shape[1])
        self._velocity_buffer = buffer
        self._normal_first, self._normal_second = buffer[:n], buffer[n : 2 * n]
        self._normals = buffer[: 2 * n].reshape(2, n)  # both normal speeds of every strip
        self._forms = buffer[2 * n :]
        self._speed = np.zeros(n)
        self._strip_gain = np.array(gains)
        self._strip_offset = np.array(offsets)

    # ------------------------------------------------------------------ body forces

    def _body_forces(self, f_body: Vec3 | None) -> None:
        """External forces on every body into ``fext`` at the posed state (after FK).

        The hull's and the links' drag, the slider corrections, and the force ``f_body`` on
        the end effector (base_link_frd), each in its body's frame.
        """
        if self._velocity_forces:
            buffer = self._velocity_buffer
            np.dot(self._twist_flat, self._forward, out=buffer)
            speed = np.hypot(self._normal_first, self._normal_second, out=self._speed)
            speed *= self._strip_gain
            speed += self._strip_offset
            self._normals *= speed
            self._forms *= self._forms
            np.dot(self._back, buffer, out=self._force_flat)
        else:
            self._force_flat.fill(0.0)
        if f_body is not None:
            # rot_link3_from_base is the placement's rotation block read row-major.
            f = _mat_vec(self._tip_rotation.tolist(), f_body)
            m = _cross(self._ee_offset, f)
            self._tip_force += (f[0], f[1], f[2], m[0], m[1], m[2])

    def _restoring_torque(self, q: Sequence[float]) -> FloatArray:
        """G_b(q) (9,): the generalized force of net weights, by Pinocchio's gravity pass."""
        x, y, z, w = _quaternion_xyzw(q[3], q[4], q[5])
        model, data, config = self._restoring_first
        config[3], config[4], config[5], config[6] = x, y, z, w
        config[7], config[8], config[9] = q[6], q[7], q[8]
        result: FloatArray = pin.computeGeneralizedGravity(model, data, config)
        if self._restoring_pair:
            model, data, _ = self._restoring[1]
            result = result + pin.computeGeneralizedGravity(model, data, config)
        return result

    # ------------------------------------------------------------------ dynamics, body form

    def _w_dot(self, q: Sequence[float], w: FloatArray, f_body: Vec3 | None) -> FloatArray:
        """Quasi-accelerations of eq. 8 by ABA at (q, w), with ``self._tau_b`` applied."""
        config = self._q_dyn
        config[7], config[8], config[9] = q[6], q[7], q[8]
        self._v_body[:] = w
        model, data = self._dyn, self._dyn_data
        pin.forwardKinematics(model, data, config, self._v_dyn)
        self._body_forces(f_body)
        np.subtract(self._tau_b, self._restoring_torque(q), out=self._tau_body)
        ddq = pin.aba(model, data, config, self._v_dyn, self._tau_dyn, self._fext)
        result: FloatArray = ddq[:N_DOF].copy()
        return result

    def _f_body(self, rot: Mat3, f_ee_ned: Sequence[float] | None) -> Vec3 | None:
        return None if f_ee_ned is None else _mat_t_vec(rot, f_ee_ned)

    def _check_q(self, q: ArrayLike) -> FloatArray:
        return _vector('q', q, N_DOF)

    def _mass_and_bias(self, q: Sequence[float], w: FloatArray) -> tuple[FloatArray, FloatArray]:
        """M_b(q_m) and C_b w + D_b w + G_b (eq. 8): CRBA and RNEA, sliders eliminated.

        With the sliders' rows s and the body rows r of the dynamic model's M and bias b,
        eliminating the sliders' accelerations (they transmit no force) gives
        M_b = M_rr - M_rs M_ss^-1 M_sr and bias = b_r - M_rs M_ss^-1 b_s (M_ss diagonal).
        """
        config = self._q_dyn
        config[7], config[8], config[9] = q[6], q[7], q[8]
        self._v_body[:] = w
        model, data = self._dyn, self._dyn_data
        pin.forwardKinematics(model, data, config, self._v_dyn)
        self._body_forces(None)
        tau = pin.rnea(model, data, config, self._v_dyn, self._zero_dyn, self._fext)
        mass, scaled = self._mass(q[6:9])
        bias = tau[:N_DOF] + self._restoring_torque(q)
        if self._slider_mass_inverse.size:
            bias -= scaled.dot(tau[N_DOF:])
        return mass, bias

    def _mass(self, q_m: Sequence[float]) -> tuple[FloatArray, FloatArray]:
        """M_b(q_m) by CRBA with the sliders eliminated, and M_rs M_ss^-1 (9, n_sliders)."""
        config = self._q_dfs
        i, j, k = self._arm_q_dfs
        config[i], config[j], config[k] = q_m[0], q_m[1], q_m[2]
        pin.crba(self._dyn_dfs, self._dyn_dfs_data, config)
        full = np.take(self._mass_upper, self._mass_take)
        mass = full[:N_DOF, :N_DOF]
        coupling = full[:N_DOF, N_DOF:]
        scaled = coupling * self._slider_mass_inverse
        if self._slider_mass_inverse.size:
            mass -= scaled.dot(coupling.T)
        return mass, scaled

    def mass_matrix_body(self, q: ArrayLike) -> FloatArray:
        """M_b(q_m) (9, 9) of eq. 8: rigid bodies plus added mass, in quasi-velocities w."""
        q = self._check_q(q)
        return self._mass(q.tolist()[6:9])[0]

    def bias_body(self, q: ArrayLike, w: ArrayLike) -> FloatArray:
        """C_b(q_m, w) w + D_b(q_m, w) w + G_b(q) (9,) of eq. 8, so M_b w_dot + bias = tau_b."""
        q = self._check_q(q)
        w = _vector('w', w, N_DOF)
        return self._mass_and_bias(q.tolist(), w)[1]

    def gravity_body(self, q: ArrayLike) -> FloatArray:
        """G_b(q) (9,) of eq. 8: gravity and buoyancy as generalized body forces."""
        q = self._check_q(q)
        return self._mass_and_bias(q.tolist(), self._zero_v)[1]

    def kinetic_energy(self, q: ArrayLike, w: ArrayLike) -> float:
        """Kinetic energy T = 1/2 w^T M_b w (J) of bodies and entrained water (added mass)."""
        w = _vector('w', w, N_DOF)
        return 0.5 * float(w @ self.mass_matrix_body(q) @ w)

    def forward_dynamics(
        self,
        q: ArrayLike,
        w: ArrayLike,
        tau_b: ArrayLike,
        f_ee_ned: ArrayLike | None = None,
    ) -> FloatArray:
        """Quasi-accelerations w_dot (9,) from eq. 8: M_b w_dot = tau_b + J_w^T f - bias.

        Args:
            q: Generalized coordinates (9,).
            w: Quasi-velocities (9,).
            tau_b: Generalized body forces (9,): vehicle force and moment in base_link_frd
                about the body origin, then joint torques.
            f_ee_ned: Force acting ON the end effector, in map_ned (3,) (N); None for none.
                A wall contact force F_e exerted BY the end effector enters as -F_e.
        """
        q = self._check_q(q)
        w = _vector('w', w, N_DOF)
        tau_b = _vector('tau_b', tau_b, N_DOF)
        f = None if f_ee_ned is None else _vector('f_ee_ned', f_ee_ned, 3).tolist()
        q_list = q.tolist()
        rot = _rotation(q_list[3], q_list[4], q_list[5])
        self._tau_b[:] = tau_b
        return self._w_dot(q_list, w, self._f_body(rot, f))

    # ------------------------------------------------------------------ integration

    def step(
        self,
        q: ArrayLike,
        w: ArrayLike,
        tau_b: ArrayLike,
        f_ee_ned: ArrayLike | None,
        dt: float,
        *,
        method: str | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """Advance (q, w) by one fixed step dt with tau_b and f_ee_ned held constant.

        Args:
            q: Generalized coordinates (9,).
            w: Quasi-velocities (9,).
            tau_b: Generalized body forces (9,) (eq. 8).
            f_ee_ned: Force ON the end effector in map_ned (3,) (N), or None.
            dt: Step (s), positive.
            method: 'rk4' or 'semi_implicit_euler'; None uses ``integration.method``.

        Returns:
            (q, w) at t + dt.

        Raises:
            StateError: For a wrong shape, a non-finite input or a non-finite result.
            SingularAttitudeError: If the pitch reaches +-90 deg.
        """
        q_arr = np.asarray(q, dtype=float)
        w_arr = np.asarray(w, dtype=float)
        tau_arr = np.asarray(tau_b, dtype=float)
        if (
            q_arr.shape != (N_DOF,)
            or w_arr.shape != (N_DOF,)
            or tau_arr.shape != (N_DOF,)
            or not math.isfinite(sum(q_arr.tolist()) + sum(w_arr.tolist()) + sum(tau_arr.tolist()))
        ):
            # Slow path, only to name the offending argument.
            _vector('q', q, N_DOF)
            _vector('w', w, N_DOF)
            _vector('tau_b', tau_b, N_DOF)
        f = None if f_ee_ned is None else _vector('f_ee_ned', f_ee_ned, 3).tolist()
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0.0):
            raise StateError(f'dt must be a positive finite number of seconds, got {dt!r}')
        method = self._method if method is None else method
        self._tau_b[:] = tau_arr
        dt = float(dt)
        if method == 'rk4':
            q_new, w_new = self._rk4(q_arr.tolist(), w_arr, f, dt)
        elif method == 'semi_implicit_euler':
            q_list = q_arr.tolist()
            rot = _rotation(q_list[3], q_list[4], q_list[5])
            w_new = w_arr + dt * self._w_dot(q_list, w_arr, self._f_body(rot, f))
            q_new = q_arr + dt * np.array(self._q_dot(q_list, w_new.tolist()))
        else:
            raise ModelError(f"method = {method!r} must be 'rk4' or 'semi_implicit_euler'")
        if not math.isfinite(sum(q_new.tolist()) + sum(w_new.tolist())):
            raise StateError(
                f'the state diverged in one step of dt = {dt!r} s from q = {q_arr.tolist()!r}, '
                f'w = {w_arr.tolist()!r}'
            )
        return q_new, w_new

    def _stage(
        self, q: list[float], w: FloatArray, f_ned: list[float] | None
    ) -> tuple[list[float], FloatArray]:
        """(q_dot, w_dot) of eq. 4 and eq. 8 at (q, w)."""
        rot = _rotation(q[3], q[4], q[5])
        w_list = w.tolist()
        return self._q_dot(q, w_list, rot), self._w_dot(q, w, self._f_body(rot, f_ned))

    def _rk4(
        self, q: list[float], w: FloatArray, f: list[float] | None, dt: float
    ) -> tuple[FloatArray, FloatArray]:
        """Classical fourth-order Runge-Kutta step of (q_dot, w_dot) = (B w, M_b^-1 (...))."""
        half = 0.5 * dt
        p1, a1 = self._stage(q, w, f)
        p2, a2 = self._stage([x + half * d for x, d in zip(q, p1, strict=True)], w + half * a1, f)
        p3, a3 = self._stage([x + half * d for x, d in zip(q, p2, strict=True)], w + half * a2, f)
        p4, a4 = self._stage([x + dt * d for x, d in zip(q, p3, strict=True)], w + dt * a3, f)
        sixth = dt / 6.0
        q_new = np.array(
            [
                x + sixth * (d1 + d4 + 2.0 * (d2 + d3))
                for x, d1, d2, d3, d4 in zip(q, p1, p2, p3, p4, strict=True)
            ]
        )
        w_new: FloatArray = w + sixth * (a1 + a4 + 2.0 * (a2 + a3))
        return q_new, w_new

    def _q_dot(self, q: list[float], w: list[float], rot: Mat3 | None = None) -> list[float]:
        """q_dot = B(q) w (eq. 4) as a list; ``rot`` is rot_ned_from_body(q) if known."""
        phi, theta, psi = q[3], q[4], q[5]
        c5 = check_pitch(theta, 'q (during integration)')
        if rot is None:
            rot = _rotation(phi, theta, psi)
        c4, s4 = math.cos(phi), math.sin(phi)
        t5 = math.sin(theta) / c5
        p, qq, r = w[3], w[4], w[5]
        return [
            *_mat_vec(rot, w),
            p + (s4 * qq + c4 * r) * t5,
            c4 * qq - s4 * r,
            (s4 * qq + c4 * r) / c5,
            w[6],
            w[7],
            w[8],
        ]

    # ------------------------------------------------------------------ generalized coordinates

    def velocity_transform(self, q: ArrayLike) -> FloatArray:
        """B(q) (9, 9) of eq. 4, q_dot = B w: blockdiag(J1, J2, I) (paper sec. 3.2).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
            StateError: If q is not a finite (9,) vector.
        """
        q = self._check_q(q)
        return self._velocity_transform(q.tolist())

    @staticmethod
    def _velocity_transform(q: Sequence[float]) -> FloatArray:
        phi, theta, psi = q[3], q[4], q[5]
        c5 = check_pitch(theta)
        c4, s4 = math.cos(phi), math.sin(phi)
        t5 = math.sin(theta) / c5
        r0, r1, r2, r3, r4, r5, r6, r7, r8 = _rotation(phi, theta, psi)
        return np.array((
            r0, r1, r2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            r3, r4, r5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            r6, r7, r8, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 1.0, s4 * t5, c4 * t5, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, c4, -s4, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, s4 / c5, c4 / c5, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        )).reshape(N_DOF, N_DOF)  # fmt: skip

    @staticmethod
    def _velocity_transform_inverse(q: Sequence[float]) -> FloatArray:
        """B^-1 = blockdiag(J1^T, J2^-1, I) (regular at any pitch)."""
        c4, s4 = math.cos(q[3]), math.sin(q[3])
        c5, s5 = math.cos(q[4]), math.sin(q[4])
        r0, r1, r2, r3, r4, r5, r6, r7, r8 = _rotation(q[3], q[4], q[5])
        return np.array((
            r0, r3, r6, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            r1, r4, r7, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            r2, r5, r8, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 1.0, 0.0, -s5, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, c4, s4 * c5, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, -s4, c4 * c5, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        )).reshape(N_DOF, N_DOF)  # fmt: skip

    @staticmethod
    def _w_from_q_dot(q: Sequence[float], q_dot: Sequence[float], rot: Mat3) -> list[float]:
        """Quasi-velocities w = B^-1 q_dot = [R^T p_dot; J2^-1 eta_dot; q_m_dot] (any pitch)."""
        c4, s4 = math.cos(q[3]), math.sin(q[3])
        c5, s5 = math.cos(q[4]), math.sin(q[4])
        phi_dot, theta_dot, psi_dot = q_dot[3], q_dot[4], q_dot[5]
        return [
            *_mat_t_vec(rot, q_dot),
            phi_dot - s5 * psi_dot,
            c4 * theta_dot + s4 * c5 * psi_dot,
            -s4 * theta_dot + c4 * c5 * psi_dot,
            q_dot[6],
            q_dot[7],
            q_dot[8],
        ]

    @staticmethod
    def _b_inverse_b_dot_w(q: Sequence[float], w: Sequence[float]) -> list[float]:
        """B^-1 B_dot w (9,) = [omega x v; J2^-1 J2_dot omega; 0] with eta_dot = J2 omega."""
        c4, s4 = math.cos(q[3]), math.sin(q[3])
        c5 = check_pitch(q[4])
        s5 = math.sin(q[4])
        w1, w2 = w[4], w[5]
        a = s4 * w1 + c4 * w2
        b = c4 * w1 - s4 * w2
        phi_dot = w[3] + a * s5 / c5
        theta_dot = b
        u0 = phi_dot * b * s5 / c5 + theta_dot * a / (c5 * c5)
        u1 = -phi_dot * a
        u2 = phi_dot * b / c5 + theta_dot * s5 * a / (c5 * c5)
        return [
            *_cross(w[3:6], w[0:3]),
            u0 - s5 * u2,
            c4 * u1 + s4 * c5 * u2,
            -s4 * u1 + c4 * c5 * u2,
            0.0,
            0.0,
            0.0,
        ]

    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """M(q) = B^-T M_b B^-1 (9, 9) in generalized coordinates (eq. 18).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg (the Euler-angle form of eq. 18).
        """
        q = self._check_q(q)
        q_list = q.tolist()
        check_pitch(q_list[4])
        b_inv = self._velocity_transform_inverse(q_list)
        mass = self._mass_and_bias(q_list, self._zero_v)[0]
        result: FloatArray = b_inv.T.dot(mass.dot(b_inv))
        return result

    def bias(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """zeta(q, q_dot) = C q_dot + D q_dot + G (9,) of eq. 19, so M q_ddot + zeta = tau.

        zeta = B^-T (C_b w + D_b w + G_b - M_b B^-1 B_dot w) with w = B^-1 q_dot (eq. 18).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
        """
        q = self._check_q(q)
        q_dot = _vector('q_dot', q_dot, N_DOF)
        return self.task_space_terms(q, q_dot).zeta

    # ------------------------------------------------------------------ end effector

    def _pose_kinematics(self, q: Sequence[float]) -> None:
        """Set the kinematic configuration (base pose from x, y, z and the Euler angles)."""
        config = self._q_kin
        config[0], config[1], config[2] = q[0], q[1], q[2]
        config[3], config[4], config[5], config[6] = _quaternion_xyzw(q[3], q[4], q[5])
        config[7], config[8], config[9] = q[6], q[7], q[8]

    def _frame(self, q: Sequence[float], name: str) -> tuple[FloatArray, FloatArray]:
        """(p_ned, rot_ned_from_frame) of one frame, by forward kinematics."""
        self._pose_kinematics(q)
        pin.forwardKinematics(self._kin, self._kin_data, self._q_kin)
        placement = pin.updateFramePlacement(self._kin, self._kin_data, self._frame_ids[name])
        return placement.translation.copy(), placement.rotation.copy()

    def ee_position(self, q: ArrayLike) -> FloatArray:
        """End-effector position X (3,) in map_ned (ee_link, the tip of link 3)."""
        q = self._check_q(q)
        return self._frame(q.tolist(), EE_LINK)[0]

    def ee_rotation(self, q: ArrayLike) -> FloatArray:
        """rot_ned_from_ee (3, 3): ee_link axes, aligned with link 3 (x along the link)."""
        q = self._check_q(q)
        return self._frame(q.tolist(), EE_LINK)[1]

    def _ee_motion(
        self, q: Sequence[float], w: Sequence[float] | FloatArray
    ) -> tuple[FloatArray, ...]:
        """X, rot_ned_from_ee, J_w (3, 9) and J_w_dot w (3,) of the EE, map_ned, w-based."""
        self._pose_kinematics(q)
        model, data = self._kin, self._kin_data
        pin.forwardKinematics(model, data, self._q_kin, np.asarray(w, dtype=float), self._zero_v)
        pin.computeJointJacobians(model, data)
        placement = pin.updateFramePlacement(model, data, self._ee_frame)
        jac = pin.getFrameJacobian(model, data, self._ee_frame, pin.LOCAL_WORLD_ALIGNED)[:3]
        acc = pin.getFrameClassicalAcceleration(
            model, data, self._ee_frame, pin.LOCAL_WORLD_ALIGNED
        ).linear
        return placement.translation.copy(), placement.rotation.copy(), jac, acc

    def ee_jacobian(self, q: ArrayLike) -> FloatArray:
        """EE Jacobian J (3, 9) in map_ned with respect to q_dot: X_dot = J q_dot (eq. 22).

        J = J_w B^-1 with J_w the Jacobian with respect to the quasi-velocities w.

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg (the Euler-angle form of eq. 18).
        """
        q = self._check_q(q)
        q_list = q.tolist()
        check_pitch(q_list[4])
        jac_w = self._ee_motion(q_list, self._zero_v)[2]
        result: FloatArray = jac_w.dot(self._velocity_transform_inverse(q_list))
        return result

    def ee_jacobian_dot_qdot(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """J_dot q_dot (3,) in map_ned, so that X_ddot = J q_ddot + J_dot q_dot (eq. 23).

        X_ddot = J_w w_dot + J_w_dot w with w_dot = B^-1 (q_ddot - B_dot w), so
        J_dot q_dot = J_w_dot w - J_w B^-1 B_dot w; J_w_dot w is the classical acceleration
        of the EE point at w_dot = 0 (Pinocchio's frame classical acceleration).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
        """
        q = self._check_q(q)
        q_dot = _vector('q_dot', q_dot, N_DOF)
        return self.task_space_terms(q, q_dot).J_dot_q_dot

    def task_space_terms(
        self, q: ArrayLike, q_dot: ArrayLike | None = None, *, w: ArrayLike | None = None
    ) -> TaskSpaceTerms:
        """X, J, J_dot q_dot (eq. 22-23), M, zeta (eq. 18-19) and B at one state, in one pass.

        Args:
            q: Generalized coordinates (9,), finite.
            q_dot: Generalized velocities (9,), finite; or None with ``w``.
            w: Quasi-velocities (9,) instead of ``q_dot`` (q_dot = B w, eq. 4).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
        """
        q_list = np.asarray(q, dtype=float).tolist()
        check_pitch(q_list[4])
        rot = _rotation(q_list[3], q_list[4], q_list[5])
        b = self._velocity_transform(q_list)
        if w is None:
            q_dot_arr = np.asarray(q_dot, dtype=float)
            w_list = self._w_from_q_dot(q_list, q_dot_arr.tolist(), rot)
            w_arr = np.array(w_list)
        else:
            w_arr = np.asarray(w, dtype=float)
            w_list = w_arr.tolist()
            q_dot_arr = b.dot(w_arr)
        mass_b, bias_b = self._mass_and_bias(q_list, w_arr)
        correction = np.array(self._b_inverse_b_dot_w(q_list, w_list))
        b_inv = self._velocity_transform_inverse(q_list)
        x, rot_ee, jac_w, acc = self._ee_motion(q_list, w_arr)
        b_inv_t = b_inv.T
        return TaskSpaceTerms(
            X=x,
            J=jac_w.dot(b_inv),
            J_dot_q_dot=acc - jac_w.dot(correction),
            M=b_inv_t.dot(mass_b.dot(b_inv)),
            zeta=b_inv_t.dot(bias_b - mass_b.dot(correction)),
            B=b,
            rot_ned_from_ee=rot_ee,
            q_dot=q_dot_arr,
        )

    # ------------------------------------------------------------------ poses and IK

    def frame_poses(
        self, q: ArrayLike, frames: Sequence[str] = FRAME_NAMES
    ) -> dict[str, tuple[FloatArray, FloatArray]]:
        """Poses of base_link_frd, link_1..3, ee_link, ft_sensor_link in map_ned.

        Args:
            q: Generalized coordinates (9,).
            frames: The frames to pose, a subset of ``FRAME_NAMES`` (default: all).

        Returns:
            {frame: (p_ned (3,), rot_ned_from_frame (3, 3))}; link_i sits at joint i,
            ee_link and ft_sensor_link at the tip of link 3 with link 3's axes.

        Raises:
            ModelError: For a frame name not in ``FRAME_NAMES``.
        """
        q = self._check_q(q)
        for name in frames:
            if name not in self._frame_ids:
                raise ModelError(f'frame {name!r} is not one of {FRAME_NAMES}')
        self._pose_kinematics(q.tolist())
        model, data = self._kin, self._kin_data
        pin.forwardKinematics(model, data, self._q_kin)
        poses = {}
        for name in frames:
            placement = pin.updateFramePlacement(model, data, self._frame_ids[name])
            poses[name] = (placement.translation.copy(), placement.rotation.copy())
        return poses

    def joint_positions_for_ee_position(
        self,
        q_vehicle: ArrayLike,
        x_ned: ArrayLike,
        q_arm_guess: ArrayLike,
        *,
        tolerance_m: float = 1e-9,
        max_iterations: int = 200,
        damping: float = 1e-2,
    ) -> FloatArray:
        """Arm joint angles (3,) that put the end effector at ``x_ned`` (damped least squares).

        Args:
            q_vehicle: Vehicle pose (6,): position in map_ned and roll, pitch, yaw.
            x_ned: Desired end-effector position in map_ned (3,) (m).
            q_arm_guess: Initial joint angles (3,) (rad); selects the branch (elbow up/down).
            tolerance_m: Position error at which to stop (m).
            max_iterations: Iteration limit.
            damping: Damping lambda of dq = J^T (J J^T + lambda^2 I)^-1 e (m).

        Raises:
            UnreachableError: If the error stays above 1e-6 m (point out of reach).
        """
        q_vehicle = _vector('q_vehicle', q_vehicle, 6)
        target = _vector('x_ned', x_ned, 3)
        qm = _vector('q_arm_guess', q_arm_guess, N_JOINTS).copy()
        error = np.full(3, np.inf)
        for _ in range(max_iterations):
            q_list = [*q_vehicle.tolist(), *qm.tolist()]
            x, _, jac_w, _ = self._ee_motion(q_list, self._zero_v)
            error = target - x
            if float(np.linalg.norm(error)) < tolerance_m:
                break
            jac = jac_w[:, 6:]
            step = jac.T @ np.linalg.solve(jac @ jac.T + damping**2 * np.eye(3), error)
            qm = qm + step
        residual = float(np.linalg.norm(error))
        if residual > 1e-6:
            raise UnreachableError(
                f'x_ned = {target.tolist()!r} is out of reach of the arm from the vehicle pose '
                f'q_vehicle = {q_vehicle.tolist()!r}: residual {residual:.3g} m after '
                f'{max_iterations} iterations'
            )
        result: FloatArray = np.arctan2(np.sin(qm), np.cos(qm))
        return result

