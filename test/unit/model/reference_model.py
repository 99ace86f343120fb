"""The previous pure-Python implementation of uvms_model, kept as the test oracle.

It computes the same dynamics as ``uvms_model.UvmsModel`` (paper eq. 8, 18-20, 22-23) by
hand-written spatial-vector algorithms (Featherstone, Rigid Body Dynamics Algorithms, 2008)
instead of Pinocchio, from the paper's numbers written out here instead of the URDF: an
oracle independent of what runs. It was the model until Pinocchio took over the hot path.

Four bodies: the vehicle (body 0, frame base_link_frd at the hull centre O) and links 1-3
(frame link_i at joint i). Spatial vectors are ordered [linear; angular] like the
quasi-velocities w of eq. 8. With J_i the body Jacobian of body i in its own frame (twist
nu_i = J_i w) and I_i its constant spatial inertia (rigid + added mass):
- M_b = sum_i J_i^T I_i J_i, the composite-rigid-body mass matrix;
- the bias is the recursive Newton-Euler force f_i = I_i a_i + nu_i x* I_i nu_i at
  w_dot = 0 (a_i = J_dot_i w), minus gravity, buoyancy and drag, mapped by J_i^T.
Added mass enters as extra (non rigid-body) spatial inertia of each body, which gives exactly
M = M_RB + sum J_i^T M_A,i J_i and bias sum J_i^T (M_A,i J_dot_i w + nu_i x* M_A,i nu_i).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import lapack  # type: ignore[import-untyped]
from uvms_model.parameters import UvmsParameters

# Only the parameter values come from uvms_model; every closed form below is written out here.

FloatArray = NDArray[np.float64]


class ModelError(Exception):
    """The reference model cannot do what was asked (a bad frame, a bad method)."""


class StateError(ModelError):
    """A state or input of the wrong shape or not finite."""


class UnreachableError(ModelError):
    """An end-effector position out of the arm's reach."""


class SingularAttitudeError(StateError):
    """Pitch within a milliradian of +-90 deg, where J2 of sec. 3.2 is singular."""


#: |cos(pitch)| below which the Euler-angle rate matrix J2 counts as singular.
SINGULAR_COS_PITCH = 1e-3


def check_pitch(theta: float, name: str = 'q') -> float:
    """cos(theta), raising SingularAttitudeError near pitch = +-90 deg (paper sec. 3.2)."""
    c = math.cos(theta)
    if abs(c) < SINGULAR_COS_PITCH:
        raise SingularAttitudeError(f'{name}: pitch theta = {theta!r} rad is at +-90 deg')
    return c


class TaskSpaceTerms(NamedTuple):
    """What the controller needs at one state, field for field as uvms_model's."""

    X: NDArray[np.float64]
    J: NDArray[np.float64]
    J_dot_q_dot: NDArray[np.float64]
    M: NDArray[np.float64]
    zeta: NDArray[np.float64]
    B: NDArray[np.float64]
    rot_ned_from_ee: NDArray[np.float64]
    q_dot: NDArray[np.float64]


def _lamb_factors(a: float, b: float) -> tuple[float, float, float]:
    """Lamb's (1932, sec. 373) k1 (axial), k2 (lateral), k' (rotation) of a prolate spheroid.

    e = sqrt(1 - b^2/a^2), alpha0 = 2 (1 - e^2)/e^3 (artanh e - e),
    beta0 = 1/e^2 - (1 - e^2)/e^3 artanh e; k1 = alpha0/(2 - alpha0), k2 = beta0/(2 - beta0),
    k' = (b^2 - a^2)^2 (alpha0 - beta0) / ((2 (b^2 - a^2) + (b^2 + a^2)(beta0 - alpha0))
    (a^2 + b^2)).
    """
    e = math.sqrt(1.0 - (b / a) ** 2)
    artanh = math.atanh(e)
    alpha0 = 2.0 * (1.0 - e * e) / e**3 * (artanh - e)
    beta0 = 1.0 / (e * e) - (1.0 - e * e) / e**3 * artanh
    a2, b2 = a * a, b * b
    k_rot = (b2 - a2) ** 2 * (alpha0 - beta0) / (
        (2.0 * (b2 - a2) + (b2 + a2) * (beta0 - alpha0)) * (a2 + b2))
    return alpha0 / (2.0 - alpha0), beta0 / (2.0 - beta0), k_rot


def spheroid_added_mass(a: float, b: float, rho: float) -> FloatArray:
    """M_A (6, 6) of a prolate spheroid (semi-axes a along x, b) at its centre, by Lamb.

    Displaced mass m_f = 4/3 pi rho a b^2: k1 m_f in surge, k2 m_f in sway and heave, none in
    roll (a body of revolution), k' m_f (a^2 + b^2)/5 in pitch and yaw.
    """
    m_f = 4.0 / 3.0 * math.pi * rho * a * b * b
    k1, k2, k_rot = _lamb_factors(a, b)
    rotary = k_rot * m_f * (a * a + b * b) / 5.0
    return np.diag([k1 * m_f, k2 * m_f, k2 * m_f, 0.0, rotary, rotary])


def cylinder_added_mass(length: float, radius: float, rho: float) -> FloatArray:
    """M_A (6, 6) of a slender cylinder along x over [0, L], at x = 0, by strip theory.

    Each strip dx carries rho pi r^2 dx across the axis and moves sideways with v + r x,
    vertically with w - q x: int_0^L (1, x, x^2) dx = (L, L^2/2, L^3/3) gives the lateral,
    coupling and rotary terms. Along the axis: Lamb's k1 of the spheroid of semi-axes L/2, r
    times the cylinder's displaced mass. Roll: none (a circular section).
    """
    per_metre = rho * math.pi * radius * radius
    lateral = per_metre * length
    coupling = per_metre * length**2 / 2.0
    rotary = per_metre * length**3 / 3.0
    added = np.zeros((6, 6))
    added[0, 0] = _lamb_factors(0.5 * length, radius)[0] * lateral
    added[1, 1] = added[2, 2] = lateral
    added[1, 5] = added[5, 1] = coupling  # sway force from yaw rate: v + r x
    added[2, 4] = added[4, 2] = -coupling  # heave force from pitch rate: w - q x
    added[4, 4] = added[5, 5] = rotary
    return added


def rigid_body_inertia(mass: float, com: FloatArray, inertia_com: FloatArray) -> FloatArray:
    """Spatial inertia at the frame origin, [linear; angular]: parallel-axis theorem written out.

    [[m I, -m [c]x], [m [c]x, I_c - m [c]x [c]x]] with [c]x the cross-product matrix.
    """
    cx, cy, cz = (float(v) for v in com)
    skew = np.array([[0.0, -cz, cy], [cz, 0.0, -cx], [-cy, cx, 0.0]])
    spatial = np.zeros((6, 6))
    spatial[:3, :3] = mass * np.eye(3)
    spatial[:3, 3:] = -mass * skew
    spatial[3:, :3] = mass * skew
    spatial[3:, 3:] = inertia_com - mass * skew @ skew
    return spatial


def cylinder_inertia(mass: float, length: float, radius: float) -> FloatArray:
    """Solid cylinder about its centre, axis x: m r^2/2 axial, m (3 r^2 + L^2)/12 across."""
    across = mass * (3.0 * radius * radius + length * length) / 12.0
    return np.diag([0.5 * mass * radius * radius, across, across])


def hull_quadratic_drag(
    a: float, b: float, rho: float, cd_trans: float, cd_rot: float
) -> FloatArray:
    """Quadratic drag coefficients (6,) of the spheroid hull, 1/2 rho C_D times a silhouette.

    Surge: the disc pi b^2; sway, heave: the ellipse pi a b. Pitch, yaw: int |x|^3 of the
    strips 2 b sqrt(1 - x^2/a^2) over [-a, a] = 8/15 a^4 b; roll: a and b exchanged.
    """
    half = 0.5 * rho
    return np.array([
        half * cd_trans * math.pi * b * b,
        half * cd_trans * math.pi * a * b,
        half * cd_trans * math.pi * a * b,
        half * cd_rot * 8.0 / 15.0 * a * b**4,
        half * cd_rot * 8.0 / 15.0 * a**4 * b,
        half * cd_rot * 8.0 / 15.0 * a**4 * b,
    ])


def strip_nodes(length: float, count: int) -> tuple[FloatArray, FloatArray]:
    """Gauss-Legendre nodes mapped from [-1, 1] to [0, L]: strip centres and widths (m)."""
    xi, weights = np.polynomial.legendre.leggauss(count)
    return 0.5 * length * (xi + 1.0), 0.5 * length * weights


@dataclass(frozen=True)
class ReferenceVehicle:
    """The paper's vehicle (sec. 5.1) and the project's documented choices, written out."""

    mass_kg: float = 530.0
    length_m: float = 1.0
    diameter_m: float = 0.5
    inertia_kg_m2: tuple[float, ...] = (13.25, 33.125, 33.125)
    center_of_gravity_m: tuple[float, ...] = (0.0, 0.0, 0.05)
    center_of_buoyancy_m: tuple[float, ...] = (0.028, 0.0, 0.0)
    buoyancy_ratio: float = 1.0
    linear_drag_translation_n_s_m: float = 0.0
    linear_drag_rotation_n_m_s: float = 0.81
    drag_coefficient_translation: float = 1.05
    drag_coefficient_rotation: float = 1.0
    #: A hull given by coefficients (Fossen's magnitudes) instead of the spheroid: M_A =
    #: diag(added_mass_kg), drag (D_l + D_q |nu|) nu, buoyancy rho V (None: the spheroid).
    added_mass_kg: tuple[float, ...] | None = None
    linear_damping: tuple[float, ...] | None = None
    quadratic_damping: tuple[float, ...] | None = None
    displaced_volume_m3: float | None = None


@dataclass(frozen=True)
class ReferenceArm:
    """The paper's arm (sec. 5.1): mount point and joint axes as the project chose them."""

    joint_names: tuple[str, ...] = ('joint_1', 'joint_2', 'joint_3')
    mount_position_m: tuple[float, ...] = (0.5, 0.0, 0.0)
    joint_axes: tuple[float, ...] = (0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0)
    link_lengths_m: tuple[float, ...] = (0.5, 0.5, 0.5)
    link_radii_m: tuple[float, ...] = (0.05, 0.04, 0.035)
    link_masses_kg: tuple[float, ...] = (10.0, 8.0, 5.0)
    drag_coefficient: float = 1.1


@dataclass(frozen=True)
class ReferenceRobot:
    """The robot's numbers of the oracle, independent of the URDF."""

    vehicle: ReferenceVehicle = field(default_factory=ReferenceVehicle)
    arm: ReferenceArm = field(default_factory=ReferenceArm)


N_JOINTS = 3
N_DOF = 6 + N_JOINTS
FRAME_NAMES = ('base_link_frd', 'link_1', 'link_2', 'link_3', 'ee_link', 'ft_sensor_link')
"""Frames of ``UvmsModel.frame_poses``, all posed in map_ned."""

Vec3 = tuple[float, float, float]
Mat3 = tuple[float, float, float, float, float, float, float, float, float]  # row-major


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


def _mat_vec(r: Mat3, v: Vec3 | list[float]) -> Vec3:
    return (
        r[0] * v[0] + r[1] * v[1] + r[2] * v[2],
        r[3] * v[0] + r[4] * v[1] + r[5] * v[2],
        r[6] * v[0] + r[7] * v[1] + r[8] * v[2],
    )


def _mat_t_vec(r: Mat3, v: Vec3 | list[float]) -> Vec3:
    return (
        r[0] * v[0] + r[3] * v[1] + r[6] * v[2],
        r[1] * v[0] + r[4] * v[1] + r[7] * v[2],
        r[2] * v[0] + r[5] * v[1] + r[8] * v[2],
    )


def _mat_mat(a: Mat3, b: Mat3) -> Mat3:
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = a
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = b
    return (
        a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8,
        a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8,
        a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7, a6 * b2 + a7 * b5 + a8 * b8,
    )  # fmt: skip


def _force_cross_map() -> FloatArray:
    """Constant map T (36, 6) with (u outer f).ravel() @ T = u x* f (spatial force cross).

    u x* f = [w x f_v; w x f_w + v x f_v] for the twist u = [v; w] and the wrench
    f = [f_v; f_w] (Featherstone's cross product, reordered [linear; angular]).
    """
    force = np.zeros((6, 6, 6))
    # (a x b)_row = sign * a_k * b_col over the entries of the cross-product matrix [a]x.
    entries = ((0, 1, 2, -1.0), (0, 2, 1, 1.0), (1, 0, 2, 1.0), (1, 2, 0, -1.0),
               (2, 0, 1, -1.0), (2, 1, 0, 1.0))  # fmt: skip
    for row, col, k, sign in entries:
        force[3 + k, col, row] += sign  # w x f_v
        force[3 + k, 3 + col, 3 + row] += sign  # w x f_w
        force[k, col, 3 + row] += sign  # v x f_v
    return force.reshape(36, 6)


def _transform_maps(n_links: int) -> FloatArray:
    """Constant maps (n_links, 18, 36): link data [rot^T (9), B (9)] -> X_i.ravel().

    X_i = [[rot^T, B], [0, rot^T]] moves motion vectors from frame 0 to link i; it is linear
    in the data, hence a constant map, and one batched product gives all links' X_i.
    """
    unit = np.zeros((18, 6, 6))  # data of one link -> X
    for r in range(3):
        for c in range(3):
            unit[3 * r + c, r, c] = unit[3 * r + c, r + 3, c + 3] = 1.0
            unit[9 + 3 * r + c, r, c + 3] = 1.0
    maps: FloatArray = np.broadcast_to(unit.reshape(18, 36), (n_links, 18, 36)).copy()
    return maps


class _Configuration:
    """Quantities that depend on the joint angles only."""

    __slots__ = (
        'axes',
        'ee',
        'jac_local',
        'key',
        'mass',
        'origins',
        'relatives',
        'rotations',
        'subspaces',
    )

    key: tuple[float, float, float]
    rotations: list[Mat3]  # rot_body_from_link_i
    relatives: list[Mat3]  # rot_{i-1, i}: link i axes in link i-1 (the body for i = 1)
    origins: list[Vec3]  # joint i position in frame 0
    axes: list[Vec3]  # joint i axis in frame 0
    ee: Vec3  # end effector in frame 0
    subspaces: FloatArray  # (3, 6) s_j in frame 0
    jac_local: FloatArray  # (24, 9) J_i stacked: body twists in the bodies' own frames
    mass: FloatArray | None  # M_b, computed on demand


class ReferenceModel:
    """Dynamics and kinematics of the UVMS of the paper (sec. 3 and 5.1).

    Coordinates (docs/architecture.md): q = [x, y, z, phi, theta, psi, q1, q2, q3] with the
    vehicle origin in map_ned and ZYX Euler angles; quasi-velocities w = [u, v, w, p, q, r,
    q1_dot, q2_dot, q3_dot] in base_link_frd; q_dot = B(q) w (eq. 4). Arrays returned are
    new arrays owned by the caller. Not thread-safe (one cache per instance).

    Example:
        >>> model = ReferenceModel()
        >>> q = np.zeros(9); w = np.zeros(9); tau_b = np.zeros(9)
        >>> q, w = model.step(q, w, tau_b, None, 1e-3)
    """

    n_dof: int = N_DOF
    n_joints: int = N_JOINTS

    def __init__(
        self, params: UvmsParameters | None = None, robot: ReferenceRobot | None = None
    ) -> None:
        self.params = params if params is not None else UvmsParameters()
        p = self.params
        robot = robot if robot is not None else ReferenceRobot()
        self.joint_names: tuple[str, ...] = tuple(robot.arm.joint_names)
        hydro = p.hydrodynamics
        rho = hydro.water_density_kg_m3
        self._g = hydro.gravity_m_s2
        self._method = p.integration.method
        lengths = [float(v) for v in robot.arm.link_lengths_m]
        radii = [float(v) for v in robot.arm.link_radii_m]
        masses = [float(v) for v in robot.arm.link_masses_kg]
        self._lengths = lengths
        self._mount: Vec3 = tuple(float(v) for v in robot.arm.mount_position_m)  # type: ignore[assignment]
        axes = np.array(robot.arm.joint_axes, dtype=float).reshape(3, 3)
        axes /= np.linalg.norm(axes, axis=1, keepdims=True)
        self._joint_axes: list[Vec3] = [tuple(a) for a in axes.tolist()]
        # Rodrigues' formula, with the closed forms for +x, +y, +z (0, 1, 2; -1: general).
        self._axis_kinds = [
            next((k for k in range(3) if a[k] == 1.0), -1) for a in self._joint_axes
        ]

        # Spatial inertias: vehicle at the hull centre O, links at their joint, own axes.
        veh = robot.vehicle
        a_hull, b_hull = 0.5 * veh.length_m, 0.5 * veh.diameter_m
        r_g = np.array(veh.center_of_gravity_m, dtype=float)
        r_b = np.array(veh.center_of_buoyancy_m, dtype=float)
        rigid_vehicle = rigid_body_inertia(veh.mass_kg, r_g, np.diag(veh.inertia_kg_m2))
        rigid_links = np.array(
            [
                rigid_body_inertia(
                    masses[i],
                    np.array([0.5 * lengths[i], 0.0, 0.0]),
                    cylinder_inertia(masses[i], lengths[i], radii[i]),
                )
                for i in range(N_JOINTS)
            ]
        )
        if hydro.added_mass_enabled:
            added_vehicle = (spheroid_added_mass(a_hull, b_hull, rho) if veh.added_mass_kg is None
                             else np.diag(np.array(veh.added_mass_kg, dtype=float)))
            added_links = np.array(
                [cylinder_added_mass(lengths[i], radii[i], rho) for i in range(N_JOINTS)]
            )
        else:
            added_vehicle = np.zeros((6, 6))
            added_links = np.zeros((N_JOINTS, 6, 6))
        self.added_mass_vehicle: FloatArray = added_vehicle
        """Added-mass matrix M_A (6, 6) of the hull at O, base_link_frd axes."""
        self.added_mass_links: FloatArray = added_links
        """Added-mass matrices (3, 6, 6) of the links at their joint, link axes."""
        self._inertia_blocks = np.zeros((4 * 6, 4 * 6))  # blockdiag(I_0, I_1, I_2, I_3)
        self._inertia_blocks[:6, :6] = rigid_vehicle + added_vehicle
        for i in range(N_JOINTS):
            block = slice(6 * i + 6, 6 * i + 12)
            self._inertia_blocks[block, block] = rigid_links[i] + added_links[i]
        self._inertia_link_blocks = self._inertia_blocks[6:, 6:].copy()
        # Added mass alone, for the current's relative velocity (Fossen 2011, sec. 8.3).
        self._added_blocks = np.zeros((4 * 6, 4 * 6))
        self._added_blocks[:6, :6] = added_vehicle
        for i in range(N_JOINTS):
            block = slice(6 * i + 6, 6 * i + 12)
            self._added_blocks[block, block] = added_links[i]
        self._rigid_blocks = self._inertia_blocks - self._added_blocks

        # Gravity and buoyancy as net ("wet") masses W_i and first moments W_i c_i.
        total_mass = veh.mass_kg + sum(masses)
        link_volumes = [math.pi * radii[i] ** 2 * lengths[i] for i in range(N_JOINTS)]
        if hydro.buoyancy_enabled:
            link_displaced = [rho * v for v in link_volumes]
            # Non-negative: UvmsParameters checks the ratio against the links' displacement.
            hull_displaced = (veh.buoyancy_ratio * total_mass - sum(link_displaced)
                              if veh.displaced_volume_m3 is None
                              else rho * veh.displaced_volume_m3)
        else:
            link_displaced = [0.0] * N_JOINTS
            hull_displaced = 0.0
        self.hull_displaced_mass_kg = hull_displaced
        """Mass of water displaced by the hull (kg), set by ``vehicle.buoyancy_ratio``."""
        self._wet_vehicle = veh.mass_kg - hull_displaced
        self._wet_links = [masses[i] - link_displaced[i] for i in range(N_JOINTS)]
        self._first_moment_vehicle: Vec3 = tuple(
            (veh.mass_kg * r_g - hull_displaced * r_b).tolist()
        )

        # Drag: hull coefficients per quasi-velocity; links by Gauss-Legendre strips.
        self._drag_enabled = hydro.drag_enabled
        self._hull_linear_drag = [veh.linear_drag_translation_n_s_m] * 3 + [
            veh.linear_drag_rotation_n_m_s
        ] * 3
        self._hull_quadratic_drag = hull_quadratic_drag(
            a_hull, b_hull, rho, veh.drag_coefficient_translation, veh.drag_coefficient_rotation
        ).tolist()
        if veh.linear_damping is not None and veh.quadratic_damping is not None:
            self._hull_linear_drag = [float(v) for v in veh.linear_damping]
            self._hull_quadratic_drag = [float(v) for v in veh.quadratic_damping]
        nodes = [strip_nodes(length, hydro.drag_strips_per_link) for length in lengths]
        strip_x = np.array([x for x, _ in nodes])  # (3, N)
        strip_dx = np.array([dx for _, dx in nodes])
        # 1/2 rho C_D (2 r) dx per strip.
        self._strip_gain = 0.5 * rho * robot.arm.drag_coefficient * 2.0 * np.array(radii)[:, None]
        self._strip_gain = self._strip_gain * strip_dx
        # Rows mapping a link-frame twist to the normal velocity (y, z) at each strip centre:
        # v_y + w_z x and v_z - w_y x; all y rows of a link first, then all z rows.
        count = hydro.drag_strips_per_link
        strip_rows = np.zeros((N_JOINTS, 2 * count, 6))
        strip_rows[:, :count, 1] = 1.0
        strip_rows[:, :count, 5] = strip_x
        strip_rows[:, count:, 2] = 1.0
        strip_rows[:, count:, 4] = -strip_x
        self._strip_count = count
        # blockdiag of the links' strip rows, transposed (18, 6N): link twists -> strip normal
        # velocities (nu @ map), strip forces -> link wrenches (map @ f).
        rows = 2 * count
        self._strip_map = np.zeros((6 * N_JOINTS, rows * N_JOINTS))
        for i in range(N_JOINTS):
            self._strip_map[6 * i : 6 * i + 6, rows * i : rows * (i + 1)] = strip_rows[i].T
        self._transform_maps = _transform_maps(N_JOINTS)

        # Constant maps.
        self._force_cross = _force_cross_map()
        self._jac_template = np.zeros((4, 6, N_DOF))
        self._jac_template[:, :, :6] = np.eye(6)
        self._jac_local_template = self._jac_template.reshape(4 * 6, N_DOF).copy()
        self._joint_mask = np.tril(np.ones((N_JOINTS, N_JOINTS)))[:, None, :]  # (3, 1, 3)
        self._half_lengths = [0.5 * length for length in lengths]
        self._cache: _Configuration | None = None

    # ------------------------------------------------------------------ configuration

    def _configuration(self, q1: float, q2: float, q3: float) -> _Configuration:
        """Arm kinematics, transforms, inertias and Jacobians in frame 0 (cached)."""
        cached = self._cache
        key = (q1, q2, q3)
        if cached is not None and cached.key == key:
            return cached
        cfg = _Configuration()
        cfg.key = key
        rotations: list[Mat3] = []
        relatives: list[Mat3] = []
        origins: list[Vec3] = []
        axes: list[Vec3] = []
        flat: list[float] = []
        subspaces: list[float] = []
        ox, oy, oz = self._mount
        parent: Mat3 | None = None
        for j, angle in enumerate(key):
            x, y, z = self._joint_axes[j]
            c, s = math.cos(angle), math.sin(angle)
            kind = self._axis_kinds[j]
            relative: Mat3
            if kind == 2:
                relative = (c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
            elif kind == 1:
                relative = (c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
            elif kind == 0:
                relative = (1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
            else:
                k = 1.0 - c
                relative = (
                    c + k * x * x, k * x * y - s * z, k * x * z + s * y,
                    k * x * y + s * z, c + k * y * y, k * y * z - s * x,
                    k * x * z - s * y, k * y * z + s * x, c + k * z * z,
                )  # fmt: skip
            relatives.append(relative)
            if parent is None:
                rot, axis = relative, (x, y, z)
            else:
                rot, axis = _mat_mat(parent, relative), _mat_vec(parent, (x, y, z))
            r0, r1, r2, r3, r4, r5, r6, r7, r8 = rot
            ax, ay, az = axis
            rotations.append(rot)
            origins.append((ox, oy, oz))
            axes.append(axis)
            # X_j = [[rot^T, B], [0, rot^T]], row k of B is o x e_k (e_k: column k of rot).
            flat += (
                r0, r3, r6, r1, r4, r7, r2, r5, r8,
                oy * r6 - oz * r3, oz * r0 - ox * r6, ox * r3 - oy * r0,
                oy * r7 - oz * r4, oz * r1 - ox * r7, ox * r4 - oy * r1,
                oy * r8 - oz * r5, oz * r2 - ox * r8, ox * r5 - oy * r2,
            )  # fmt: skip
            subspaces += (oy * az - oz * ay, oz * ax - ox * az, ox * ay - oy * ax, ax, ay, az)
            length = self._lengths[j]
            ox, oy, oz = ox + length * r0, oy + length * r3, oz + length * r6
            parent = rot
        flat += subspaces
        origin = (ox, oy, oz)
        data = np.array(flat)
        cfg.rotations, cfg.relatives, cfg.origins, cfg.axes, cfg.ee = (
            rotations, relatives, origins, axes, origin,
        )  # fmt: skip
        cfg.subspaces = data[54:].reshape(N_JOINTS, 6)
        transforms = (data[:54].reshape(N_JOINTS, 1, 18) @ self._transform_maps).reshape(
            N_JOINTS, 6, 6
        )
        jac0 = self._jac_template.copy()
        jac0[1:, :, 6:] = cfg.subspaces.T * self._joint_mask
        links = transforms @ jac0[1:]  # (3, 6, 9): J_i
        jac_local = self._jac_local_template.copy()
        jac_local[6:] = links.reshape(3 * 6, N_DOF)
        cfg.jac_local = jac_local
        cfg.mass = None
        self._cache = cfg
        return cfg

    def _mass(self, cfg: _Configuration) -> FloatArray:
        """M_b = sum_i J_i^T I_i J_i (composite-rigid-body matrix), cached per configuration."""
        if cfg.mass is None:
            cfg.mass = cfg.jac_local.T.dot(self._inertia_blocks.dot(cfg.jac_local))
        return cfg.mass

    def _bias(
        self,
        cfg: _Configuration,
        q: list[float],
        w_list: list[float],
        w: FloatArray,
        f_ee_ned: list[float] | None,
        rot: Mat3 | None = None,
        current_ned: list[float] | None = None,
    ) -> FloatArray:
        """C_b w + D_b w + G_b - J_ee^T f_ee (9,): RNEA at w_dot = 0 (eq. 8).

        ``rot`` is rot_ned_from_body of q when the caller has it already. With a current
        (``current_ned``, m/s, uniform and constant), each body's velocity relative to the
        water nu_r,i = nu_i - [u_i; 0], u_i = R_i^T v_c, replaces nu_i in drag and added mass:
        f_i = I_i a_i + nu_i x* I_RB,i nu_i + nu_r,i x* M_A,i nu_r,i - M_A,i nu_c_dot,i with
        nu_c_dot,i = [-omega_i x u_i; 0] (Fossen 2011, sec. 8.3).
        """
        nu = cfg.jac_local.dot(w)  # body twists, own frames (24,)
        bias_acc = self._bias_accelerations(cfg, nu.tolist(), w_list)
        if rot is None:
            rot = _rotation(q[3], q[4], q[5])
        nu_r, drag_w = nu, w_list
        if current_ned is None:
            # f_i = I_i a_i + nu_i x* I_i nu_i.
            momenta = self._inertia_blocks.dot(nu).reshape(4, 1, 6)
            forces = (nu.reshape(4, 6, 1) * momenta).reshape(4, 36).dot(self._force_cross)
        else:
            u_body = _mat_t_vec(rot, current_ned)
            flows = [u_body] + [_mat_t_vec(cfg.rotations[i], u_body) for i in range(N_JOINTS)]
            flow = np.zeros((4, 6))
            nu_c_dot = np.zeros((4, 6))
            for i, u in enumerate(flows):
                flow[i, :3] = u
                nu_c_dot[i, :3] = [-c for c in _cross(nu[6 * i + 3 : 6 * i + 6].tolist(), u)]
            nu_r = nu - flow.reshape(-1)
            drag_w = [w_list[k] - u_body[k] if k < 3 else w_list[k] for k in range(N_DOF)]
            rigid = self._rigid_blocks.dot(nu).reshape(4, 1, 6)
            added = self._added_blocks.dot(nu_r).reshape(4, 1, 6)
            forces = (nu.reshape(4, 6, 1) * rigid).reshape(4, 36).dot(self._force_cross)
            forces += (nu_r.reshape(4, 6, 1) * added).reshape(4, 36).dot(self._force_cross)
            forces -= self._added_blocks.dot(nu_c_dot.reshape(-1)).reshape(4, 6)
        forces[1:] += self._inertia_link_blocks.dot(bias_acc).reshape(N_JOINTS, 6)
        forces -= np.array(self._body_wrenches(cfg, rot, drag_w, f_ee_ned)).reshape(4, 6)
        if self._drag_enabled:
            # Cross-flow strips: dF = -1/2 rho C_D (2 r) |v_n| v_n dx. The strip rows map a
            # link twist to the normal velocities at the strips, their transpose the strip
            # forces back to a link wrench.
            normal = nu_r[6:].dot(self._strip_map).reshape(N_JOINTS, 2, self._strip_count)
            normal *= (self._strip_gain * np.hypot(normal[:, 0], normal[:, 1]))[:, None, :]
            forces[1:] += self._strip_map.dot(normal.reshape(-1)).reshape(N_JOINTS, 6)
        result: FloatArray = forces.reshape(4 * 6).dot(cfg.jac_local)
        return result

    def _bias_accelerations(
        self, cfg: _Configuration, nu: list[float], w: list[float]
    ) -> list[float]:
        """Link accelerations a_i = J_dot_i w (18,) in link frames (Featherstone's RNEA pass).

        a_1 = c_1, a_i = X_{i,i-1} a_{i-1} + c_i with c_i = nu_i x [0; a_i] q_dot_i
        = [v_i x a_i; w_i x a_i] q_dot_i (joint axis a_i fixed in link i) and X_{i,i-1} the
        joint transform: rotation rot_{i-1,i}^T, offset (L_{i-1}, 0, 0).
        """
        out: list[float] = []
        acc_v: Vec3 = (0.0, 0.0, 0.0)
        acc_w: Vec3 = (0.0, 0.0, 0.0)
        for j in range(N_JOINTS):
            base = 6 * j + 6
            vx, vy, vz, wx, wy, wz = nu[base : base + 6]
            ax, ay, az = self._joint_axes[j]
            rate = w[6 + j]
            cv = (
                (vy * az - vz * ay) * rate,
                (vz * ax - vx * az) * rate,
                (vx * ay - vy * ax) * rate,
            )
            cw = (
                (wy * az - wz * ay) * rate,
                (wz * ax - wx * az) * rate,
                (wx * ay - wy * ax) * rate,
            )
            if j == 0:
                acc_v, acc_w = cv, cw
            else:
                e0, e1, e2, e3, e4, e5, e6, e7, e8 = cfg.relatives[j]
                offset = self._lengths[j - 1]
                m0 = acc_v[0]
                m1 = acc_v[1] + acc_w[2] * offset
                m2 = acc_v[2] - acc_w[1] * offset
                n0, n1, n2 = acc_w
                acc_v = (
                    e0 * m0 + e3 * m1 + e6 * m2 + cv[0],
                    e1 * m0 + e4 * m1 + e7 * m2 + cv[1],
                    e2 * m0 + e5 * m1 + e8 * m2 + cv[2],
                )
                acc_w = (
                    e0 * n0 + e3 * n1 + e6 * n2 + cw[0],
                    e1 * n0 + e4 * n1 + e7 * n2 + cw[1],
                    e2 * n0 + e5 * n1 + e8 * n2 + cw[2],
                )
            out += acc_v
            out += acc_w
        return out

    def _body_wrenches(
        self, cfg: _Configuration, rot: Mat3, w: list[float], f_ee_ned: list[float] | None
    ) -> list[float]:
        """Gravity, buoyancy, hull drag and EE force on the 4 bodies, own frames (24,)."""
        out = [0.0] * 24
        g = self._g
        if g != 0.0:
            # Gravity in base_link_frd: g times the last row of rot_ned_from_body.
            gx, gy, gz = g * rot[6], g * rot[7], g * rot[8]
            wet = self._wet_vehicle
            hx, hy, hz = self._first_moment_vehicle
            out[0:6] = (
                wet * gx, wet * gy, wet * gz,
                hy * gz - hz * gy, hz * gx - hx * gz, hx * gy - hy * gx,
            )  # fmt: skip
            for i in range(N_JOINTS):
                # Link frame: weight and buoyancy act at the centre (L/2, 0, 0).
                r0, r1, r2, r3, r4, r5, r6, r7, r8 = cfg.rotations[i]
                wet = self._wet_links[i]
                fx = wet * (r0 * gx + r3 * gy + r6 * gz)
                fy = wet * (r1 * gx + r4 * gy + r7 * gz)
                fz = wet * (r2 * gx + r5 * gy + r8 * gz)
                half = self._half_lengths[i]
                out[6 * i + 6 : 6 * i + 12] = (fx, fy, fz, 0.0, -half * fz, half * fy)
        if self._drag_enabled:
            linear, quadratic = self._hull_linear_drag, self._hull_quadratic_drag
            for k in range(6):
                out[k] -= (linear[k] + quadratic[k] * abs(w[k])) * w[k]
        if f_ee_ned is not None:
            # Link 3 frame: the force acts at the tip (L3, 0, 0).
            fx, fy, fz = _mat_t_vec(cfg.rotations[2], _mat_t_vec(rot, f_ee_ned))
            length = self._lengths[2]
            out[18] += fx
            out[19] += fy
            out[20] += fz
            out[22] -= length * fz
            out[23] += length * fy
        return out

    def _solve(self, mass: FloatArray, rhs: FloatArray) -> FloatArray:
        """Solve M_b x = rhs by Cholesky (LAPACK dposv); M_b is symmetric positive definite."""
        _, solution, info = lapack.dposv(mass, rhs)
        if info != 0:
            raise ModelError(f'M_b is not positive definite (dposv info {info})')
        result: FloatArray = solution
        return result

    def _w_dot(
        self, q: FloatArray, w: FloatArray, tau_b: FloatArray, f_ee_ned: list[float] | None,
        current_ned: list[float] | None = None,
    ) -> FloatArray:
        q_list = q.tolist()
        cfg = self._configuration(q_list[6], q_list[7], q_list[8])
        bias = self._bias(cfg, q_list, w.tolist(), w, f_ee_ned, None, current_ned)
        return self._solve(self._mass(cfg), tau_b - bias)

    def _derivative(
        self, state: FloatArray, tau_b: FloatArray, f_ee_ned: list[float] | None,
        current_ned: list[float] | None = None,
    ) -> FloatArray:
        """(q_dot, w_dot) (18,) of the state (q, w) (18,): eq. 4 and eq. 8."""
        values = state.tolist()
        q, w = values[:9], values[9:]
        cfg = self._configuration(q[6], q[7], q[8])
        rot = _rotation(q[3], q[4], q[5])
        bias = self._bias(cfg, q, w, state[9:], f_ee_ned, rot, current_ned)
        derivative = np.empty(2 * N_DOF)
        derivative[:9] = self._q_dot(q, w, rot)
        derivative[9:] = self._solve(self._mass(cfg), tau_b - bias)
        return derivative

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

    # ------------------------------------------------------------------ public: dynamics

    def _check_q(self, q: ArrayLike) -> FloatArray:
        return _vector('q', q, N_DOF)

    def mass_matrix_body(self, q: ArrayLike) -> FloatArray:
        """M_b(q_m) (9, 9) of eq. 8: rigid bodies plus added mass, in quasi-velocities w."""
        q = self._check_q(q)
        return self._mass(self._configuration(*q[6:].tolist())).copy()

    def bias_body(
        self, q: ArrayLike, w: ArrayLike, current_ned: ArrayLike | None = None
    ) -> FloatArray:
        """C_b(q_m, w) w + D_b(q_m, w) w + G_b(q) (9,) of eq. 8, so M_b w_dot + bias = tau_b."""
        q = self._check_q(q)
        w = _vector('w', w, N_DOF)
        q_list = q.tolist()
        cfg = self._configuration(*q_list[6:])
        current = None if current_ned is None else _vector('current_ned', current_ned, 3).tolist()
        return self._bias(cfg, q_list, w.tolist(), w, None, None, current)

    def gravity_body(self, q: ArrayLike) -> FloatArray:
        """G_b(q) (9,) of eq. 8: gravity and buoyancy as generalized body forces."""
        q = self._check_q(q)
        q_list = q.tolist()
        cfg = self._configuration(*q_list[6:])
        # At w = 0 the hull drag in _body_wrenches vanishes: only gravity and buoyancy remain.
        rot = _rotation(q_list[3], q_list[4], q_list[5])
        wrenches = np.array(self._body_wrenches(cfg, rot, [0.0] * N_DOF, None))
        result: FloatArray = -wrenches.dot(cfg.jac_local)
        return result

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
        current_ned: ArrayLike | None = None,
    ) -> FloatArray:
        """Quasi-accelerations w_dot (9,) from eq. 8: M_b w_dot = tau_b + J_w^T f - bias.

        Args:
            q: Generalized coordinates (9,).
            w: Quasi-velocities (9,).
            tau_b: Generalized body forces (9,): vehicle force and moment in base_link_frd
                about the body origin, then joint torques.
            f_ee_ned: Force acting ON the end effector, in map_ned (3,) (N); None for none.
                A wall contact force F_e exerted BY the end effector enters as -F_e.
            current_ned: The water's velocity in map_ned (3,) (m/s), or None (still water).
        """
        q = self._check_q(q)
        w = _vector('w', w, N_DOF)
        tau_b = _vector('tau_b', tau_b, N_DOF)
        f = None if f_ee_ned is None else _vector('f_ee_ned', f_ee_ned, 3).tolist()
        current = None if current_ned is None else _vector('current_ned', current_ned, 3).tolist()
        return self._w_dot(q, w, tau_b, f, current)

    def step(
        self,
        q: ArrayLike,
        w: ArrayLike,
        tau_b: ArrayLike,
        f_ee_ned: ArrayLike | None,
        dt: float,
        *,
        method: str | None = None,
        current_ned: ArrayLike | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """Advance (q, w) by one fixed step dt with tau_b, f_ee_ned and the current held.

        Args:
            q: Generalized coordinates (9,).
            w: Quasi-velocities (9,).
            tau_b: Generalized body forces (9,) (eq. 8).
            f_ee_ned: Force ON the end effector in map_ned (3,) (N), or None.
            dt: Step (s), positive.
            method: 'rk4' or 'semi_implicit_euler'; None uses ``integration.method``.
            current_ned: The water's velocity in map_ned (3,) (m/s), or None (still water).

        Returns:
            (q, w) at t + dt.

        Raises:
            StateError: For a wrong shape, a non-finite input or a non-finite result.
            SingularAttitudeError: If the pitch reaches +-90 deg.
        """
        state = np.concatenate((np.asarray(q, dtype=float), np.asarray(w, dtype=float)))
        tau_b = np.asarray(tau_b, dtype=float)
        if (
            state.shape != (2 * N_DOF,)
            or tau_b.shape != (N_DOF,)
            or not math.isfinite(sum(state.tolist()) + sum(tau_b.tolist()))
        ):
            # Slow path, only to name the offending argument.
            _vector('q', q, N_DOF)
            _vector('w', w, N_DOF)
            _vector('tau_b', tau_b, N_DOF)
        f = None if f_ee_ned is None else _vector('f_ee_ned', f_ee_ned, 3).tolist()
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0.0):
            raise StateError(f'dt must be a positive finite number of seconds, got {dt!r}')
        method = self._method if method is None else method
        current = None if current_ned is None else _vector('current_ned', current_ned, 3).tolist()
        if method == 'rk4':
            state_new = self._rk4(state, tau_b, f, float(dt), current)
        elif method == 'semi_implicit_euler':
            q, w = state[:N_DOF], state[N_DOF:]
            w_new = w + dt * self._w_dot(q, w, tau_b, f, current)
            q_new = q + dt * np.array(self._q_dot(q.tolist(), w_new.tolist()))
            state_new = np.concatenate((q_new, w_new))
        else:
            raise ModelError(f"method = {method!r} must be 'rk4' or 'semi_implicit_euler'")
        q_new, w_new = state_new[:N_DOF], state_new[N_DOF:]
        if not math.isfinite(sum(state_new.tolist())):
            q, w = state[:N_DOF], state[N_DOF:]
            raise StateError(
                f'the state diverged in one step of dt = {dt!r} s from q = {q.tolist()!r}, '
                f'w = {w.tolist()!r}'
            )
        return q_new, w_new

    def _rk4(
        self, state: FloatArray, tau_b: FloatArray, f: list[float] | None, dt: float,
        current: list[float] | None = None,
    ) -> FloatArray:
        """Classical fourth-order Runge-Kutta step of (q_dot, w_dot) = (B w, M_b^-1 (...))."""
        half = 0.5 * dt
        k1 = self._derivative(state, tau_b, f, current)
        k2 = self._derivative(state + half * k1, tau_b, f, current)
        k3 = self._derivative(state + half * k2, tau_b, f, current)
        k4 = self._derivative(state + dt * k3, tau_b, f, current)
        result: FloatArray = state + (dt / 6.0) * (k1 + k4 + 2.0 * (k2 + k3))
        return result

    # ------------------------------------------------------------------ generalized coordinates

    def velocity_transform(self, q: ArrayLike) -> FloatArray:
        """B(q) (9, 9) of eq. 4, q_dot = B w: blockdiag(J1, J2, I) (paper sec. 3.2).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
            StateError: If q is not a finite (9,) vector.
        """
        q = self._check_q(q)
        phi, theta, psi = float(q[3]), float(q[4]), float(q[5])
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

    def _w_from_q_dot(self, q: list[float], q_dot: list[float], rot: Mat3) -> list[float]:
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

    def _b_inverse_b_dot_w(self, q: list[float], w: list[float], eta_dot: list[float]) -> Vec3:
        """Angular part J2^-1 J2_dot omega of B^-1 B_dot w = [omega x v; J2^-1 J2_dot omega; 0]."""
        c4, s4 = math.cos(q[3]), math.sin(q[3])
        c5 = check_pitch(q[4])
        s5 = math.sin(q[4])
        phi_dot, theta_dot = eta_dot[0], eta_dot[1]
        w1, w2 = w[4], w[5]
        a = s4 * w1 + c4 * w2
        b = c4 * w1 - s4 * w2
        u0 = phi_dot * b * s5 / c5 + theta_dot * a / (c5 * c5)
        u1 = -phi_dot * a
        u2 = phi_dot * b / c5 + theta_dot * s5 * a / (c5 * c5)
        return (u0 - s5 * u2, c4 * u1 + s4 * c5 * u2, -s4 * u1 + c4 * c5 * u2)

    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """M(q) = B^-T M_b B^-1 (9, 9) in generalized coordinates (eq. 18).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg (the Euler-angle form of eq. 18).
        """
        q = self._check_q(q)
        q_list = q.tolist()
        check_pitch(q_list[4])
        c4, s4 = math.cos(q_list[3]), math.sin(q_list[3])
        c5, s5 = math.cos(q_list[4]), math.sin(q_list[4])
        # B^-1 = blockdiag(R^T, J2^-1, I).
        r0, r1, r2, r3, r4, r5, r6, r7, r8 = _rotation(*q_list[3:6])
        b_inv = np.array((
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
        mass = self._mass(self._configuration(*q_list[6:]))
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
        q_list, q_dot_list = q.tolist(), q_dot.tolist()
        check_pitch(q_list[4])
        rot = _rotation(*q_list[3:6])
        w_list = self._w_from_q_dot(q_list, q_dot_list, rot)
        w = np.array(w_list)
        cfg = self._configuration(*q_list[6:])
        bias_b = self._bias(cfg, q_list, w_list, w, None, rot)
        correction = [
            *_cross(w_list[3:6], w_list[0:3]),
            *self._b_inverse_b_dot_w(q_list, w_list, q_dot_list[3:6]),
            0.0,
            0.0,
            0.0,
        ]
        y = (bias_b - self._mass(cfg).dot(correction)).tolist()
        c4, s4 = math.cos(q_list[3]), math.sin(q_list[3])
        c5, s5 = math.cos(q_list[4]), math.sin(q_list[4])
        # zeta = B^-T y = [R y_v; J2^-T y_w; y_m].
        return np.array(
            (
                *_mat_vec(rot, y),
                y[3],
                c4 * y[4] - s4 * y[5],
                -s5 * y[3] + s4 * c5 * y[4] + c4 * c5 * y[5],
                y[6],
                y[7],
                y[8],
            )
        )

    # ------------------------------------------------------------------ end effector

    def ee_position(self, q: ArrayLike) -> FloatArray:
        """End-effector position X (3,) in map_ned (tip of link 3)."""
        q = self._check_q(q)
        q_list = q.tolist()
        cfg = self._configuration(*q_list[6:])
        offset = _mat_vec(_rotation(*q_list[3:6]), cfg.ee)
        return np.array((q_list[0] + offset[0], q_list[1] + offset[1], q_list[2] + offset[2]))

    def ee_rotation(self, q: ArrayLike) -> FloatArray:
        """rot_ned_from_ee (3, 3): ee_link axes, aligned with link 3 (x along the link)."""
        q = self._check_q(q)
        q_list = q.tolist()
        cfg = self._configuration(*q_list[6:])
        return np.array(_mat_mat(_rotation(*q_list[3:6]), cfg.rotations[2])).reshape(3, 3)

    def _ee_joint_columns(self, cfg: _Configuration) -> list[Vec3]:
        """a_j x (r_ee - o_j): EE velocity per unit joint rate, base_link_frd."""
        ex, ey, ez = cfg.ee
        return [
            _cross(
                cfg.axes[j],
                (ex - cfg.origins[j][0], ey - cfg.origins[j][1], ez - cfg.origins[j][2]),
            )
            for j in range(N_JOINTS)
        ]

    def _ee_jacobian_body(self, cfg: _Configuration) -> FloatArray:
        """Jacobian (3, 9) of the EE velocity in base_link_frd with respect to w."""
        ex, ey, ez = cfg.ee
        c0, c1, c2 = self._ee_joint_columns(cfg)
        return np.array(
            (
                (1.0, 0.0, 0.0, 0.0, ez, -ey, c0[0], c1[0], c2[0]),
                (0.0, 1.0, 0.0, -ez, 0.0, ex, c0[1], c1[1], c2[1]),
                (0.0, 0.0, 1.0, ey, -ex, 0.0, c0[2], c1[2], c2[2]),
            )
        )

    def ee_jacobian(self, q: ArrayLike) -> FloatArray:
        """EE Jacobian J (3, 9) in map_ned with respect to q_dot: X_dot = J q_dot (eq. 22).

        J = [I, -R [r_ee]x J2^-1, R (a_j x (r_ee - o_j))], r_ee the EE in base_link_frd.

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg (the Euler-angle form of eq. 18).
        """
        q = self._check_q(q)
        q_list = q.tolist()
        check_pitch(q_list[4])
        rot = _rotation(*q_list[3:6])
        cfg = self._configuration(*q_list[6:])
        ex, ey, ez = cfg.ee
        c4, s4 = math.cos(q_list[3]), math.sin(q_list[3])
        c5, s5 = math.cos(q_list[4]), math.sin(q_list[4])
        j2_inv = ((1.0, 0.0, -s5), (0.0, c4, s4 * c5), (0.0, -s4, c4 * c5))
        # -[r]x J2^-1 column k = -(r x j2_inv[:, k]) = j2_inv[:, k] x r.
        cols = [_cross((j2_inv[0][k], j2_inv[1][k], j2_inv[2][k]), (ex, ey, ez)) for k in range(3)]
        cols += self._ee_joint_columns(cfg)
        ned = [_mat_vec(rot, col) for col in cols]
        return np.array(
            (1.0, 0.0, 0.0, *[c[0] for c in ned], 0.0, 1.0, 0.0, *[c[1] for c in ned],
             0.0, 0.0, 1.0, *[c[2] for c in ned])
        ).reshape(3, N_DOF)  # fmt: skip

    def ee_jacobian_dot_qdot(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """J_dot q_dot (3,) in map_ned, so that X_ddot = J q_ddot + J_dot q_dot (eq. 23).

        X_ddot = J_w w_dot + J_w_dot w with w_dot = B^-1 (q_ddot - B_dot w), so
        J_dot q_dot = R (a_ee - c_v - c_w x r_ee): a_ee the EE point's acceleration at
        w_dot = 0 and [c_v; c_w] = B^-1 B_dot w.

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
        """
        q = self._check_q(q)
        q_dot = _vector('q_dot', q_dot, N_DOF)
        q_list, q_dot_list = q.tolist(), q_dot.tolist()
        check_pitch(q_list[4])
        rot = _rotation(*q_list[3:6])
        w = self._w_from_q_dot(q_list, q_dot_list, rot)
        cfg = self._configuration(*q_list[6:])
        # Twist of link 3 and its acceleration at w_dot = 0, base_link_frd at O (fixed now):
        # a = sum_j (V_{j-1} x s_j) q_dot_j, V_j = V_{j-1} + s_j q_dot_j.
        vx, vy, vz, wx, wy, wz = w[0:6]
        avx = avy = avz = awx = awy = awz = 0.0
        for (sx, sy, sz, tx, ty, tz), rate in zip(cfg.subspaces.tolist(), w[6:9], strict=True):
            # (omega x s_v + v x s_w) and omega x s_w, written out.
            avx += ((wy * sz - wz * sy) + (vy * tz - vz * ty)) * rate
            avy += ((wz * sx - wx * sz) + (vz * tx - vx * tz)) * rate
            avz += ((wx * sy - wy * sx) + (vx * ty - vy * tx)) * rate
            awx += (wy * tz - wz * ty) * rate
            awy += (wz * tx - wx * tz) * rate
            awz += (wx * ty - wy * tx) * rate
            vx, vy, vz = vx + sx * rate, vy + sy * rate, vz + sz * rate
            wx, wy, wz = wx + tx * rate, wy + ty * rate, wz + tz * rate
        acc_v, acc_w, v, omega = (avx, avy, avz), (awx, awy, awz), (vx, vy, vz), (wx, wy, wz)
        ee = cfg.ee
        rel = _cross(acc_w, ee)
        omega_r = _cross(omega, ee)
        cent = _cross(omega, [v[k] + omega_r[k] for k in range(3)])
        c_v = _cross(w[3:6], w[0:3])
        c_w = self._b_inverse_b_dot_w(q_list, w, q_dot_list[3:6])
        c_wr = _cross(c_w, ee)
        total = [acc_v[k] + rel[k] + cent[k] - c_v[k] - c_wr[k] for k in range(3)]
        return np.array(_mat_vec(rot, total))

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
        q_list = q.tolist()
        rot = _rotation(*q_list[3:6])
        cfg = self._configuration(*q_list[6:])
        x0, y0, z0 = q_list[:3]
        identity: Mat3 = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
        # Each frame: its origin in base_link_frd and rot_base_from_frame.
        sources = {
            'base_link_frd': ((0.0, 0.0, 0.0), identity),
            'link_1': (cfg.origins[0], cfg.rotations[0]),
            'link_2': (cfg.origins[1], cfg.rotations[1]),
            'link_3': (cfg.origins[2], cfg.rotations[2]),
            'ee_link': (cfg.ee, cfg.rotations[2]),
            'ft_sensor_link': (cfg.ee, cfg.rotations[2]),
        }
        # One array for all poses (3 + 9 values each): one conversion instead of twelve.
        flat: list[float] = []
        for name in frames:
            source = sources.get(name)
            if source is None:
                raise ModelError(f'frame {name!r} is not one of {FRAME_NAMES}')
            ox, oy, oz = _mat_vec(rot, source[0])
            flat += (x0 + ox, y0 + oy, z0 + oz)
            flat += _mat_mat(rot, source[1])
        data = np.array(flat).reshape(len(frames), 12)
        return {name: (data[i, :3], data[i, 3:].reshape(3, 3)) for i, name in enumerate(frames)}

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
        rot = np.reshape(_rotation(*q_vehicle[3:6].tolist()), (3, 3))
        target_body = rot.T @ (target - q_vehicle[:3])
        error = np.full(3, np.inf)
        for _ in range(max_iterations):
            cfg = self._configuration(*qm.tolist())
            error = target_body - np.array(cfg.ee)
            if float(np.linalg.norm(error)) < tolerance_m:
                break
            jac = self._ee_jacobian_body(cfg)[:, 6:]
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

    def task_space_terms(
        self, q: ArrayLike, q_dot: ArrayLike | None = None, *, w: ArrayLike | None = None
    ) -> TaskSpaceTerms:
        """The controller's terms by the separate calls the previous controller made."""
        b = self.velocity_transform(q)
        q_dot = b @ np.asarray(w, dtype=float) if q_dot is None else np.asarray(q_dot, float)
        return TaskSpaceTerms(
            X=self.ee_position(q),
            J=self.ee_jacobian(q),
            J_dot_q_dot=self.ee_jacobian_dot_qdot(q, q_dot),
            M=self.mass_matrix(q),
            zeta=self.bias(q, q_dot),
            B=b,
            rot_ned_from_ee=self.ee_rotation(q),
            q_dot=q_dot,
        )
