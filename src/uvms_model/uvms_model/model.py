"""UVMS dynamics (paper eq. 8 and 18-20): floating vehicle + 3-link arm with hydrodynamics.

Spatial-vector algorithms (Featherstone, Rigid Body Dynamics Algorithms, 2008) over four
bodies: the vehicle (body 0) and links 1-3. Every spatial quantity is expressed in
base_link_frd at the body origin O ("frame 0") at the current instant, ordered
[linear; angular] like the quasi-velocities w of eq. 8. Then
- the body twist of link i is V_i = nu_0 + sum_{j<=i} s_j q_dot_j, with the joint motion
  vectors s_j = [o_j x a_j; a_j];
- M_b is the composite-rigid-body matrix of the inertias I_i (rigid + added mass);
- C_b w is the recursive Newton-Euler force I_i a_i + V_i x* I_i V_i at w_dot = 0.

Added mass enters as extra (non rigid-body) spatial inertia of each body, which gives exactly
M = M_RB + sum J_i^T M_A,i J_i and bias sum J_i^T (M_A,i J_dot_i w + nu_i x* M_A,i nu_i)
(Kirchhoff's equations of a body in ideal fluid at rest); it is never applied as a force from
a past acceleration. Gravity and buoyancy act as forces, so they never see the added mass.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uvms_model.errors import ModelError, ParameterError, StateError, UnreachableError
from uvms_model.hydrodynamics import (
    cylinder_added_mass,
    cylinder_inertia,
    hull_quadratic_drag,
    rigid_body_inertia,
    spheroid_added_mass,
    strip_nodes,
)
from uvms_model.kinematics import (
    check_pitch,
    euler_rate_matrix,
    euler_rate_matrix_inverse,
    rot_ned_from_body,
    rotation_about_axis,
    skew,
)
from uvms_model.parameters import UvmsParameters

FloatArray = NDArray[np.float64]

N_JOINTS = 3
N_DOF = 6 + N_JOINTS
FRAME_NAMES = ('base_link_frd', 'link_1', 'link_2', 'link_3', 'ee_link', 'ft_sensor_link')
"""Frames of ``UvmsModel.frame_poses``, all posed in map_ned."""


def _vector(name: str, value: ArrayLike, size: int) -> FloatArray:
    """Return ``value`` as a finite float vector of ``size`` or raise StateError naming it."""
    array = np.asarray(value, dtype=float)
    if array.shape != (size,):
        raise StateError(f'{name} must have shape ({size},), got {array.shape}')
    if not math.isfinite(float(array.sum())):
        raise StateError(f'{name} must be finite, got {array.tolist()!r}')
    return array


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise cross product of (..., 3) arrays (cheaper than np.cross for small arrays)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0), axis=-1)


def _motion_cross(v: FloatArray, m: FloatArray) -> FloatArray:
    """Spatial motion cross product v x m of (..., 6) twists [linear; angular]."""
    return np.concatenate(
        (
            _cross(v[..., 3:], m[..., :3]) + _cross(v[..., :3], m[..., 3:]),
            _cross(v[..., 3:], m[..., 3:]),
        ),
        axis=-1,
    )


def _force_cross(v: FloatArray, f: FloatArray) -> FloatArray:
    """Spatial force cross product v x* f of a (..., 6) twist and wrench [linear; angular]."""
    return np.concatenate(
        (
            _cross(v[..., 3:], f[..., :3]),
            _cross(v[..., 3:], f[..., 3:]) + _cross(v[..., :3], f[..., :3]),
        ),
        axis=-1,
    )


class _ArmKinematics:
    """Pose of the arm in frame 0 for one set of joint angles."""

    __slots__ = ('axes', 'ee', 'origins', 'rotations', 'subspaces')

    def __init__(
        self,
        rotations: FloatArray,
        origins: FloatArray,
        axes: FloatArray,
        ee: FloatArray,
    ) -> None:
        self.rotations = rotations  # (3, 3, 3) rot_body_from_link_i
        self.origins = origins  # (3, 3) joint i position in frame 0
        self.axes = axes  # (3, 3) joint i axis in frame 0
        self.ee = ee  # (3,) end effector in frame 0
        self.subspaces = np.concatenate((_cross(origins, axes), axes), axis=1)  # (3, 6)


class UvmsModel:
    """Dynamics and kinematics of the UVMS of the paper (sec. 3 and 5.1).

    Coordinates (docs/architecture.md): q = [x, y, z, phi, theta, psi, q1, q2, q3] with the
    vehicle origin in map_ned and ZYX Euler angles; quasi-velocities w = [u, v, w, p, q, r,
    q1_dot, q2_dot, q3_dot] in base_link_frd; q_dot = B(q) w (eq. 4).

    Example:
        >>> model = UvmsModel()
        >>> q = np.zeros(9); w = np.zeros(9); tau_b = np.zeros(9)
        >>> q, w = model.step(q, w, tau_b, None, 1e-3)
    """

    n_dof: int = N_DOF
    n_joints: int = N_JOINTS

    def __init__(self, params: UvmsParameters | None = None) -> None:
        self.params = params if params is not None else UvmsParameters()
        p = self.params
        self.joint_names: tuple[str, ...] = tuple(p.arm.joint_names)
        hydro = p.hydrodynamics
        rho = hydro.water_density_kg_m3
        self._g = hydro.gravity_m_s2
        self._mount = np.array(p.arm.mount_position_m, dtype=float)
        self._joint_axes = np.array(p.arm.joint_axes, dtype=float).reshape(3, 3)
        self._joint_axes /= np.linalg.norm(self._joint_axes, axis=1, keepdims=True)
        self._lengths = np.array(p.arm.link_lengths_m, dtype=float)
        self._radii = np.array(p.arm.link_radii_m, dtype=float)
        self._link_masses = np.array(p.arm.link_masses_kg, dtype=float)
        for i in range(N_JOINTS):
            if self._lengths[i] <= 2.0 * self._radii[i]:
                raise ParameterError(
                    f'arm.link_lengths_m[{i}] = {self._lengths[i]!r} must exceed twice '
                    f'arm.link_radii_m[{i}] = {self._radii[i]!r}: links are slender cylinders'
                )

        # Vehicle: rigid body about the hull centre, plus the spheroid's added mass.
        veh = p.vehicle
        a_hull, b_hull = 0.5 * veh.length_m, 0.5 * veh.diameter_m
        r_g = np.array(veh.center_of_gravity_m, dtype=float)
        r_b = np.array(veh.center_of_buoyancy_m, dtype=float)
        self._rigid_inertia_vehicle = rigid_body_inertia(
            veh.mass_kg, r_g, np.diag(veh.inertia_kg_m2)
        )
        self._added_mass_vehicle = spheroid_added_mass(a_hull, b_hull, rho)
        # Links: uniform cylinders about their joint, plus strip-theory added mass.
        self._rigid_inertia_links = np.empty((N_JOINTS, 6, 6))
        self._added_mass_links = np.empty((N_JOINTS, 6, 6))
        link_volumes = math.pi * self._radii**2 * self._lengths
        for i in range(N_JOINTS):
            length, radius, mass = self._lengths[i], self._radii[i], self._link_masses[i]
            self._rigid_inertia_links[i] = rigid_body_inertia(
                mass, np.array([0.5 * length, 0.0, 0.0]), cylinder_inertia(mass, length, radius)
            )
            self._added_mass_links[i] = cylinder_added_mass(length, radius, rho)
        if not hydro.added_mass_enabled:
            self._added_mass_vehicle = np.zeros((6, 6))
            self._added_mass_links = np.zeros((N_JOINTS, 6, 6))
        self._inertia_vehicle = self._rigid_inertia_vehicle + self._added_mass_vehicle
        self._inertia_links = self._rigid_inertia_links + self._added_mass_links

        # Gravity and buoyancy: net "wet" mass W_i and first moment H_i = m c - m_disp b.
        total_mass = veh.mass_kg + float(self._link_masses.sum())
        if hydro.buoyancy_enabled:
            link_displaced = rho * link_volumes
            hull_displaced = veh.buoyancy_ratio * total_mass - float(link_displaced.sum())
            if hull_displaced < 0.0:
                raise ParameterError(
                    f'vehicle.buoyancy_ratio = {veh.buoyancy_ratio!r} is below what the links '
                    f'alone provide ({float(link_displaced.sum()) / total_mass:.4g})'
                )
        else:
            link_displaced = np.zeros(N_JOINTS)
            hull_displaced = 0.0
        self.hull_displaced_mass_kg = hull_displaced
        self._wet_mass = np.concatenate(
            ([veh.mass_kg - hull_displaced], self._link_masses - link_displaced)
        )
        self._first_moment_vehicle = veh.mass_kg * r_g - hull_displaced * r_b
        self._first_moment_links_local = np.zeros((N_JOINTS, 3))
        self._first_moment_links_local[:, 0] = self._wet_mass[1:] * 0.5 * self._lengths

        # Drag.
        self._drag_enabled = hydro.drag_enabled
        self._hull_linear_drag = np.array(
            [veh.linear_drag_translation_n_s_m] * 3 + [veh.linear_drag_rotation_n_m_s] * 3
        )
        self._hull_quadratic_drag = hull_quadratic_drag(
            a_hull, b_hull, rho, veh.drag_coefficient_translation, veh.drag_coefficient_rotation
        )
        nodes = [strip_nodes(float(ln), hydro.drag_strips_per_link) for ln in self._lengths]
        self._strip_x = np.array([x for x, _ in nodes])  # (3, N)
        strip_dx = np.array([dx for _, dx in nodes])
        self._strip_gain = (
            0.5 * rho * p.arm.drag_coefficient * 2.0 * self._radii[:, None] * strip_dx
        )  # (3, N): 1/2 rho C_D (2 r) dx
        self._method = p.integration.method

    # ------------------------------------------------------------------ kinematics

    def _arm(self, qm: FloatArray) -> _ArmKinematics:
        """Arm kinematics in frame 0 for joint angles ``qm`` (3,)."""
        axes_local = self._joint_axes
        r1 = rotation_about_axis(axes_local[0], float(qm[0]))
        r2 = r1 @ rotation_about_axis(axes_local[1], float(qm[1]))
        r3 = r2 @ rotation_about_axis(axes_local[2], float(qm[2]))
        rotations = np.stack((r1, r2, r3))
        axes = np.stack((axes_local[0], r1 @ axes_local[1], r2 @ axes_local[2]))
        o1 = self._mount
        o2 = o1 + self._lengths[0] * r1[:, 0]
        o3 = o2 + self._lengths[1] * r2[:, 0]
        ee = o3 + self._lengths[2] * r3[:, 0]
        return _ArmKinematics(rotations, np.stack((o1, o2, o3)), axes, ee)

    def _link_inertias(self, arm: _ArmKinematics) -> FloatArray:
        """Spatial inertias (3, 6, 6) of the links in frame 0 at O: X_i^T I_i X_i."""
        rot_t = arm.rotations.transpose(0, 2, 1)  # rot_link_from_body
        x = np.zeros((N_JOINTS, 6, 6))
        x[:, :3, :3] = rot_t
        x[:, 3:, 3:] = rot_t
        x[:, :3, 3:] = -rot_t @ np.stack([skew(o) for o in arm.origins])
        result: FloatArray = x.transpose(0, 2, 1) @ self._inertia_links @ x
        return result

    def _check_q(self, q: ArrayLike) -> FloatArray:
        return _vector('q', q, N_DOF)

    def velocity_transform(self, q: ArrayLike) -> FloatArray:
        """B(q) (9, 9) of eq. 4, q_dot = B w, from J1 and J2 (paper sec. 3.2).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
            StateError: If q is not a finite (9,) vector.
        """
        q = self._check_q(q)
        b = np.eye(N_DOF)
        b[0:3, 0:3] = rot_ned_from_body(float(q[3]), float(q[4]), float(q[5]))
        b[3:6, 3:6] = euler_rate_matrix(float(q[3]), float(q[4]))
        return b

    def _velocity_transform_inverse(self, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(R, J2^-1) so that B^-1 = blockdiag(R^T, J2^-1, I)."""
        rot = rot_ned_from_body(float(q[3]), float(q[4]), float(q[5]))
        return rot, euler_rate_matrix_inverse(float(q[3]), float(q[4]))

    def ee_position(self, q: ArrayLike) -> FloatArray:
        """End-effector position X (3,) in map_ned (tip of link 3)."""
        q = self._check_q(q)
        rot = rot_ned_from_body(float(q[3]), float(q[4]), float(q[5]))
        result: FloatArray = q[:3] + rot @ self._arm(q[6:]).ee
        return result

    def ee_rotation(self, q: ArrayLike) -> FloatArray:
        """rot_ned_from_ee (3, 3): ee_link axes, aligned with link 3 (x along the link)."""
        q = self._check_q(q)
        rot = rot_ned_from_body(float(q[3]), float(q[4]), float(q[5]))
        result: FloatArray = rot @ self._arm(q[6:]).rotations[2]
        return result

    def _ee_jacobian_body(self, arm: _ArmKinematics) -> FloatArray:
        """Jacobian (3, 9) of the end-effector velocity in frame 0 with respect to w."""
        jac = np.zeros((3, N_DOF))
        jac[:, 0:3] = np.eye(3)
        jac[:, 3:6] = -skew(arm.ee)
        jac[:, 6:] = _cross(arm.axes, arm.ee - arm.origins).T
        return jac

    def ee_jacobian(self, q: ArrayLike) -> FloatArray:
        """EE Jacobian J (3, 9) in map_ned with respect to q_dot: X_dot = J q_dot (eq. 22).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg (the Euler-angle form of eq. 18).
        """
        q = self._check_q(q)
        check_pitch(float(q[4]))
        rot, j2_inv = self._velocity_transform_inverse(q)
        jac_w = rot @ self._ee_jacobian_body(self._arm(q[6:]))
        jac = jac_w.copy()
        jac[:, 0:3] = np.eye(3)
        jac[:, 3:6] = jac_w[:, 3:6] @ j2_inv
        return jac

    def _euler_rate_matrix_dot_omega(self, q: FloatArray, eta_dot: FloatArray) -> FloatArray:
        """J2_dot omega, with J2_dot from the Euler-angle rates eta_dot = (phi_dot, ...)."""
        phi, theta = float(q[3]), float(q[4])
        c4, s4 = math.cos(phi), math.sin(phi)
        c5 = check_pitch(theta)
        s5 = math.sin(theta)
        t5 = s5 / c5
        phi_dot, theta_dot = float(eta_dot[0]), float(eta_dot[1])
        d_phi = np.array([[0.0, c4 * t5, -s4 * t5], [0.0, -s4, -c4], [0.0, c4 / c5, -s4 / c5]])
        d_theta = np.array(
            [
                [0.0, s4 / c5**2, c4 / c5**2],
                [0.0, 0.0, 0.0],
                [0.0, s4 * s5 / c5**2, c4 * s5 / c5**2],
            ]
        )
        omega = euler_rate_matrix_inverse(phi, theta) @ eta_dot
        result: FloatArray = (phi_dot * d_phi + theta_dot * d_theta) @ omega
        return result

    def _binv_bdot_w(self, q: FloatArray, w: FloatArray, q_dot: FloatArray) -> FloatArray:
        """B^-1 B_dot w (9,): [omega x v; J2^-1 J2_dot omega; 0]."""
        out = np.zeros(N_DOF)
        out[0:3] = _cross(w[3:6], w[0:3])
        j2_dot_omega = self._euler_rate_matrix_dot_omega(q, q_dot[3:6])
        out[3:6] = euler_rate_matrix_inverse(float(q[3]), float(q[4])) @ j2_dot_omega
        return out

    def ee_jacobian_dot_qdot(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """J_dot q_dot (3,) in map_ned, so that X_ddot = J q_ddot + J_dot q_dot (eq. 23).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
        """
        q = self._check_q(q)
        q_dot = _vector('q_dot', q_dot, N_DOF)
        check_pitch(float(q[4]))
        rot, j2_inv = self._velocity_transform_inverse(q)
        w = np.concatenate((rot.T @ q_dot[:3], j2_inv @ q_dot[3:6], q_dot[6:]))
        arm = self._arm(q[6:])
        # Classical acceleration of the EE point at w_dot = 0 (frame 0, fixed at this instant).
        twists, accelerations = self._link_twists(arm, w)
        v3, a3 = twists[3], accelerations[3]
        point_velocity = v3[:3] + _cross(v3[3:], arm.ee)
        ee_acc = a3[:3] + _cross(a3[3:], arm.ee) + _cross(v3[3:], point_velocity)
        binv_bdot_w = self._binv_bdot_w(q, w, q_dot)
        # X_ddot = J_w w_dot + J_w_dot w and w_dot = B^-1 (q_ddot - B_dot w).
        jac_w = rot @ self._ee_jacobian_body(arm)
        result: FloatArray = rot @ ee_acc - jac_w @ binv_bdot_w
        return result

    # ------------------------------------------------------------------ dynamics

    def _link_twists(self, arm: _ArmKinematics, w: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Twists V (4, 6) and velocity-product accelerations (4, 6) of the 4 bodies."""
        s = arm.subspaces
        qd = w[6:]
        twists = np.empty((4, 6))
        twists[0] = w[:6]
        twists[1:] = w[:6] + np.cumsum(s * qd[:, None], axis=0)
        accelerations = np.zeros((4, 6))
        accelerations[1:] = np.cumsum(_motion_cross(twists[:3], s) * qd[:, None], axis=0)
        return twists, accelerations

    def _body_inertias(self, arm: _ArmKinematics) -> FloatArray:
        """Spatial inertias (4, 6, 6) of vehicle and links in frame 0 at O."""
        inertias = np.empty((4, 6, 6))
        inertias[0] = self._inertia_vehicle
        inertias[1:] = self._link_inertias(arm)
        return inertias

    def _mass_matrix_from(self, arm: _ArmKinematics, inertias: FloatArray) -> FloatArray:
        """Composite-rigid-body M_b (9, 9) from the body inertias in frame 0."""
        composite = np.cumsum(inertias[::-1], axis=0)[::-1]
        s = arm.subspaces
        forces = (composite[1:] @ s[:, :, None])[:, :, 0]  # (3, 6): F_j = Ic_j s_j
        mass = np.empty((N_DOF, N_DOF))
        mass[:6, :6] = composite[0]
        mass[:6, 6:] = forces.T
        mass[6:, :6] = forces
        proj = s @ forces.T  # proj[j, k] = s_j . Ic_k s_k, valid for j <= k
        upper = np.triu(proj)
        mass[6:, 6:] = upper + np.triu(proj, 1).T
        return mass

    def _external_wrenches(
        self, q: FloatArray, w: FloatArray, arm: _ArmKinematics, twists: FloatArray
    ) -> FloatArray:
        """Gravity, buoyancy and drag wrenches (4, 6) on each body, frame 0 at O."""
        wrenches = np.zeros((4, 6))
        if self._g != 0.0:
            phi, theta = float(q[3]), float(q[4])
            cth = math.cos(theta)
            g_body = self._g * np.array(
                [-math.sin(theta), math.sin(phi) * cth, math.cos(phi) * cth]
            )
            first_moments = np.empty((4, 3))
            first_moments[0] = self._first_moment_vehicle
            first_moments[1:] = (
                self._wet_mass[1:, None] * arm.origins
                + (arm.rotations @ self._first_moment_links_local[:, :, None])[:, :, 0]
            )
            wrenches[:, :3] = self._wet_mass[:, None] * g_body
            wrenches[:, 3:] = _cross(first_moments, g_body[None, :])
        if self._drag_enabled:
            nu = w[:6]
            wrenches[0] -= (self._hull_linear_drag + self._hull_quadratic_drag * np.abs(nu)) * nu
            link_axes = arm.rotations[:, :, 0]  # (3, 3) unit axes e_i in frame 0
            v_o = twists[1:, :3] + _cross(twists[1:, 3:], arm.origins)  # at joint origins
            v_o_normal = v_o - np.sum(v_o * link_axes, axis=1, keepdims=True) * link_axes
            v_rate = _cross(twists[1:, 3:], link_axes)  # d v_n / d x, normal to the axis
            v_n = v_o_normal[:, None, :] + self._strip_x[:, :, None] * v_rate[:, None, :]
            speed = np.sqrt(np.sum(v_n * v_n, axis=2))
            d_force = -(self._strip_gain * speed)[:, :, None] * v_n  # (3, N, 3)
            force = d_force.sum(axis=1)
            force_x = np.sum(self._strip_x[:, :, None] * d_force, axis=1)
            wrenches[1:, :3] += force
            wrenches[1:, 3:] += _cross(arm.origins, force) + _cross(link_axes, force_x)
        return wrenches

    def _bias_from(
        self,
        q: FloatArray,
        w: FloatArray,
        arm: _ArmKinematics,
        inertias: FloatArray,
        extra_wrench_link3: FloatArray | None = None,
    ) -> FloatArray:
        """Recursive Newton-Euler bias C_b w + D_b w + G_b (9,) at w_dot = 0 (eq. 8)."""
        twists, accelerations = self._link_twists(arm, w)
        momenta = (inertias @ twists[:, :, None])[:, :, 0]
        forces = (inertias @ accelerations[:, :, None])[:, :, 0] + _force_cross(twists, momenta)
        forces -= self._external_wrenches(q, w, arm, twists)
        if extra_wrench_link3 is not None:
            forces[3] -= extra_wrench_link3
        composite = np.cumsum(forces[::-1], axis=0)[::-1]
        bias = np.empty(N_DOF)
        bias[:6] = composite[0]
        bias[6:] = np.sum(arm.subspaces * composite[1:], axis=1)
        return bias

    def mass_matrix_body(self, q: ArrayLike) -> FloatArray:
        """M_b(q_m) (9, 9) of eq. 8: rigid bodies plus added mass, in quasi-velocities w."""
        q = self._check_q(q)
        arm = self._arm(q[6:])
        return self._mass_matrix_from(arm, self._body_inertias(arm))

    def bias_body(self, q: ArrayLike, w: ArrayLike) -> FloatArray:
        """C_b(q_m, w) w + D_b(q_m, w) w + G_b(q) (9,) of eq. 8, so M_b w_dot + bias = tau_b."""
        q = self._check_q(q)
        w = _vector('w', w, N_DOF)
        arm = self._arm(q[6:])
        return self._bias_from(q, w, arm, self._body_inertias(arm))

    def gravity_body(self, q: ArrayLike) -> FloatArray:
        """G_b(q) (9,) of eq. 8: gravity and buoyancy as generalized body forces."""
        q = self._check_q(q)
        arm = self._arm(q[6:])
        wrenches = -self._external_wrenches_gravity_only(q, arm)
        composite = np.cumsum(wrenches[::-1], axis=0)[::-1]
        out = np.empty(N_DOF)
        out[:6] = composite[0]
        out[6:] = np.sum(arm.subspaces * composite[1:], axis=1)
        return out

    def _external_wrenches_gravity_only(self, q: FloatArray, arm: _ArmKinematics) -> FloatArray:
        drag = self._drag_enabled
        try:
            self._drag_enabled = False
            return self._external_wrenches(q, np.zeros(N_DOF), arm, np.zeros((4, 6)))
        finally:
            self._drag_enabled = drag

    def kinetic_energy(self, q: ArrayLike, w: ArrayLike) -> float:
        """Kinetic energy T = 1/2 w^T M_b w (J) of bodies and entrained water (added mass)."""
        w = _vector('w', w, N_DOF)
        return 0.5 * float(w @ self.mass_matrix_body(q) @ w)

    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """M(q) = B^-T M_b B^-1 (9, 9) in generalized coordinates (eq. 18)."""
        q = self._check_q(q)
        check_pitch(float(q[4]))
        binv = self._binv(q)
        result: FloatArray = binv.T @ self.mass_matrix_body(q) @ binv
        return result

    def _binv(self, q: FloatArray) -> FloatArray:
        rot, j2_inv = self._velocity_transform_inverse(q)
        binv = np.eye(N_DOF)
        binv[0:3, 0:3] = rot.T
        binv[3:6, 3:6] = j2_inv
        return binv

    def bias(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """zeta(q, q_dot) = C q_dot + D q_dot + G (9,) of eq. 19, so M q_ddot + zeta = tau.

        zeta = B^-T (C_b w + D_b w + G_b - M_b B^-1 B_dot w) with w = B^-1 q_dot (eq. 18).
        """
        q = self._check_q(q)
        q_dot = _vector('q_dot', q_dot, N_DOF)
        check_pitch(float(q[4]))
        binv = self._binv(q)
        w = binv @ q_dot
        arm = self._arm(q[6:])
        inertias = self._body_inertias(arm)
        mass_b = self._mass_matrix_from(arm, inertias)
        bias_b = self._bias_from(q, w, arm, inertias)
        result: FloatArray = binv.T @ (bias_b - mass_b @ self._binv_bdot_w(q, w, q_dot))
        return result

    def _ee_wrench(self, q: FloatArray, arm: _ArmKinematics, f_ee_ned: FloatArray) -> FloatArray:
        """Wrench (6,) in frame 0 at O of a force on the end effector given in map_ned."""
        rot = rot_ned_from_body(float(q[3]), float(q[4]), float(q[5]))
        f_body = rot.T @ f_ee_ned
        return np.concatenate((f_body, _cross(arm.ee, f_body)))

    def _w_dot(
        self, q: FloatArray, w: FloatArray, tau_b: FloatArray, f_ee_ned: FloatArray | None
    ) -> FloatArray:
        arm = self._arm(q[6:])
        inertias = self._body_inertias(arm)
        mass = self._mass_matrix_from(arm, inertias)
        extra = None if f_ee_ned is None else self._ee_wrench(q, arm, f_ee_ned)
        bias = self._bias_from(q, w, arm, inertias, extra)
        result: FloatArray = np.linalg.solve(mass, tau_b - bias).astype(np.float64, copy=False)
        return result

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
        f = None if f_ee_ned is None else _vector('f_ee_ned', f_ee_ned, 3)
        return self._w_dot(q, w, tau_b, f)

    def _q_dot(self, q: FloatArray, w: FloatArray) -> FloatArray:
        """q_dot = B(q) w (eq. 4)."""
        phi, theta, psi = float(q[3]), float(q[4]), float(q[5])
        check_pitch(theta, 'q (during integration)')
        q_dot = np.empty(N_DOF)
        q_dot[0:3] = rot_ned_from_body(phi, theta, psi) @ w[0:3]
        q_dot[3:6] = euler_rate_matrix(phi, theta) @ w[3:6]
        q_dot[6:] = w[6:]
        return q_dot

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
        q = self._check_q(q)
        w = _vector('w', w, N_DOF)
        tau_b = _vector('tau_b', tau_b, N_DOF)
        f = None if f_ee_ned is None else _vector('f_ee_ned', f_ee_ned, 3)
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0.0):
            raise StateError(f'dt must be a positive finite number of seconds, got {dt!r}')
        method = self._method if method is None else method
        if method == 'rk4':
            q_new, w_new = self._rk4(q, w, tau_b, f, dt)
        elif method == 'semi_implicit_euler':
            w_new = w + dt * self._w_dot(q, w, tau_b, f)
            q_new = q + dt * self._q_dot(q, w_new)
        else:
            raise ModelError(f"method = {method!r} must be 'rk4' or 'semi_implicit_euler'")
        if not (np.isfinite(q_new).all() and np.isfinite(w_new).all()):
            raise StateError(
                f'the state diverged in one step of dt = {dt!r} s from q = {q.tolist()!r}, '
                f'w = {w.tolist()!r}'
            )
        return q_new, w_new

    def _rk4(
        self, q: FloatArray, w: FloatArray, tau_b: FloatArray, f: FloatArray | None, dt: float
    ) -> tuple[FloatArray, FloatArray]:
        def rhs(qq: FloatArray, ww: FloatArray) -> tuple[FloatArray, FloatArray]:
            return self._q_dot(qq, ww), self._w_dot(qq, ww, tau_b, f)

        k1q, k1w = rhs(q, w)
        k2q, k2w = rhs(q + 0.5 * dt * k1q, w + 0.5 * dt * k1w)
        k3q, k3w = rhs(q + 0.5 * dt * k2q, w + 0.5 * dt * k2w)
        k4q, k4w = rhs(q + dt * k3q, w + dt * k3w)
        sixth = dt / 6.0
        return (
            q + sixth * (k1q + 2.0 * k2q + 2.0 * k3q + k4q),
            w + sixth * (k1w + 2.0 * k2w + 2.0 * k3w + k4w),
        )

    # ------------------------------------------------------------------ poses and IK

    def frame_poses(self, q: ArrayLike) -> dict[str, tuple[FloatArray, FloatArray]]:
        """Poses of base_link_frd, link_1..3, ee_link, ft_sensor_link in map_ned.

        Returns:
            {frame: (p_ned (3,), rot_ned_from_frame (3, 3))}; link_i sits at joint i,
            ee_link and ft_sensor_link at the tip of link 3 with link 3's axes.
        """
        q = self._check_q(q)
        rot = rot_ned_from_body(float(q[3]), float(q[4]), float(q[5]))
        arm = self._arm(q[6:])
        p0 = q[:3].copy()
        poses = {'base_link_frd': (p0, rot)}
        for i in range(N_JOINTS):
            poses[f'link_{i + 1}'] = (p0 + rot @ arm.origins[i], rot @ arm.rotations[i])
        ee = (p0 + rot @ arm.ee, rot @ arm.rotations[2])
        poses['ee_link'] = ee
        poses['ft_sensor_link'] = (ee[0].copy(), ee[1].copy())
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
        rot = rot_ned_from_body(float(q_vehicle[3]), float(q_vehicle[4]), float(q_vehicle[5]))
        target_body = rot.T @ (target - q_vehicle[:3])
        error = np.full(3, np.inf)
        for _ in range(max_iterations):
            arm = self._arm(qm)
            error = target_body - arm.ee
            if float(np.linalg.norm(error)) < tolerance_m:
                break
            jac = _cross(arm.axes, arm.ee - arm.origins).T
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
