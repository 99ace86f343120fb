"""UVMS dynamics (paper eq. 4, 8, 18-20, 22-23) on Pinocchio, from the robot's URDF.

``UvmsModel`` is the public face of the model: it checks its inputs, maps between the
generalized coordinates (q, q_dot) of eq. 18 and the body form (q, w) of eq. 8, and
integrates. The work is done by

- ``uvms_model.frames``: poses, the EE Jacobian and its time derivative on the URDF's
  Pinocchio model;
- ``uvms_model.body_dynamics``: M_b, the bias and w_dot of eq. 8 by CRBA, RNEA and ABA on the
  dynamic model (rigid bodies plus added mass, ``uvms_model.pinocchio_models``), with drag,
  net weights and the contact force as external forces (``uvms_model.body_forces``);
- ``uvms_model.integration``: the fixed-step integrators;
- ``uvms_model.coordinates``: B, B^-1 and their products in plain floats.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uvms_model.added_mass import AddedMass, added_masses, hull_added_mass_matrix
from uvms_model.body_dynamics import BodyDynamics
from uvms_model.coordinates import (
    Vec3,
    mat_t_vec,
    rotation,
    velocity_transform,
    velocity_transform_inverse,
)
from uvms_model.description import EE_LINK, RobotDescription, load_description
from uvms_model.errors import ModelError, StateError
from uvms_model.frames import FrameKinematics
from uvms_model.generalized_terms import TaskSpaceTerms, generalized_terms
from uvms_model.integration import Rk4Integrator, semi_implicit_euler_step
from uvms_model.kinematics import check_pitch
from uvms_model.parameters import UvmsParameters
from uvms_model.pinocchio_models import kinematic_model

FloatArray = NDArray[np.float64]


__all__ = ['TaskSpaceTerms', 'UvmsModel']


def _vector(name: str, value: ArrayLike, size: int) -> FloatArray:
    """Return ``value`` as a finite float vector of ``size`` or raise StateError naming it."""
    array = np.asarray(value, dtype=float)
    if array.shape != (size,):
        raise StateError(f'{name} must have shape ({size},), got {array.shape}')
    if not math.isfinite(sum(array.tolist())):  # sum of floats: cheaper than ndarray.sum
        raise StateError(f'{name} must be finite, got {array.tolist()!r}')
    return array


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
        >>> q = np.zeros(model.n_dof); w = np.zeros(model.n_dof); tau_b = np.zeros(model.n_dof)
        >>> q, w = model.step(q, w, tau_b, None, 1e-3)
    """

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
        """The arm's revolute joints, base to tip (from the URDF)."""
        self.n_joints = description.n_joints
        """n, the number of arm joints."""
        self.n_dof = 6 + self.n_joints
        """Generalized coordinates: vehicle position and ZYX Euler angles (6), n joints."""
        self.frame_names: tuple[str, ...] = description.frame_names
        """Frames of ``frame_poses``: root, arm links, ee_link, ft_sensor_link."""
        self._method = p.integration.method
        kin = kinematic_model(description)
        self.frames = FrameKinematics(kin, self.frame_names)
        """Poses and end-effector motion on the URDF's Pinocchio model."""
        hydro = p.hydrodynamics
        added: list[AddedMass | None] = (
            added_masses(description, hydro.water_density_kg_m3)
            if hydro.added_mass_enabled
            else [None] * (1 + self.n_joints)
        )
        hull_added = hull_added_mass_matrix(description) if hydro.added_mass_enabled else None
        self.added_mass_vehicle: FloatArray = (
            added[0].matrix() if added[0] is not None
            else hull_added if hull_added is not None else np.zeros((6, 6))
        )
        """Added-mass matrix M_A (6, 6) of the hull at O, base_link_frd axes."""
        self.added_mass_links: FloatArray = np.array(
            [a.matrix() if a is not None else np.zeros((6, 6)) for a in added[1:]]
        )
        """Added-mass matrices (n, 6, 6) of the links at their joint, link axes."""
        self.dynamics = BodyDynamics(description, hydro, kin, added, hull_added)
        """Eq. 8 in body form on Pinocchio's dynamic model."""
        self.hull_displaced_mass_kg = self.dynamics.forces.hull_displaced_mass_kg
        """Mass of water displaced by the hull (kg), set by the hull's ``buoyancy_ratio``."""
        self._g = hydro.gravity_m_s2
        self._rk4 = Rk4Integrator(self.dynamics, self._g)
        self._load_kernels()

    def _load_kernels(self) -> None:
        """Run every compiled kernel once at rest, so no later call pays its loading.

        A process's first call of a Numba kernel loads it from the cache (about 0.3 s for all
        of them, a few s to compile when the cache is cold): at construction, not in the
        first control period of a real-time run.
        """
        rest = np.zeros(self.n_dof)
        self.step(rest, rest, rest, (0.0, 0.0, 0.0), 1e-3)
        self.step(rest, rest, rest, None, 1e-3)
        self.step(rest, rest, rest, None, 1e-3, current_ned=(0.1, 0.0, 0.0))
        self.task_space_terms(rest, w=rest)

    def _gravity_body(self, rot: Sequence[float]) -> Vec3:
        """Gravitational acceleration (m/s^2) in base_link_frd: g R^T e_z (NED: z down)."""
        g = self._g
        return (g * rot[6], g * rot[7], g * rot[8])

    def _check_q(self, q: ArrayLike) -> FloatArray:
        return _vector('q', q, self.n_dof)

    # ------------------------------------------------------------------ body form (eq. 8)

    def mass_matrix_body(self, q: ArrayLike) -> FloatArray:
        """M_b(q_m) (6 + n, 6 + n) of eq. 8: rigid bodies and added mass, in quasi-velocities w."""
        q = self._check_q(q)
        return self.dynamics.mass(q.tolist()[6:])

    def bias_body(self, q: ArrayLike, w: ArrayLike,
                  current_ned: ArrayLike | None = None) -> FloatArray:
        """C_b(q_m, w) w + D_b(q_m, w) w + G_b(q) (6 + n,) of eq. 8 (`mass_and_bias_body`)."""
        return self.mass_and_bias_body(q, w, current_ned)[1]

    def mass_and_bias_body(self, q: ArrayLike, w: ArrayLike, current_ned: ArrayLike | None = None
                           ) -> tuple[FloatArray, FloatArray]:
        """M_b (6 + n, 6 + n) and C_b(q_m, w) w + D_b(q_m, w) w + G_b(q) (6 + n,) of eq. 8.

        One pass; M_b w_dot + bias = tau_b. With ``current_ned`` (the water's velocity v_c in
        map_ned, m/s) the drag and the added mass's terms are those of the relative velocity
        nu_r = nu - nu_c, and the bias holds the current's term -M_A nu_c_dot (Fossen 2011,
        sec. 8.3; ``uvms_model.relative_flow``).
        """
        q_list = self._check_q(q).tolist()
        w = _vector('w', w, self.n_dof)
        rot = rotation(q_list[3], q_list[4], q_list[5])
        current = self._current_body(rot, current_ned)
        return self.dynamics.mass_and_bias(q_list[6:], w, self._gravity_body(rot), current)

    def _current_body(self, rot: Sequence[float], current_ned: ArrayLike | None) -> Vec3 | None:
        """R^T v_c (base_link_frd) of a current in map_ned, or None (still water)."""
        if current_ned is None:
            return None
        return mat_t_vec(rot, _vector('current_ned', current_ned, 3).tolist())

    def gravity_body(self, q: ArrayLike) -> FloatArray:
        """G_b(q) (6 + n,) of eq. 8: gravity and buoyancy as generalized body forces."""
        return self.bias_body(q, np.zeros(self.n_dof))

    def kinetic_energy(self, q: ArrayLike, w: ArrayLike) -> float:
        """Kinetic energy T = 1/2 w^T M_b w (J) of bodies and entrained water (added mass)."""
        w = _vector('w', w, self.n_dof)
        return 0.5 * float(w @ self.mass_matrix_body(q) @ w)

    def forward_dynamics(self, q: ArrayLike, w: ArrayLike, tau_b: ArrayLike,
                         f_ee_ned: ArrayLike | None = None,
                         current_ned: ArrayLike | None = None) -> FloatArray:
        """Quasi-accelerations w_dot (6 + n,) from eq. 8: M_b w_dot = tau_b + J_w^T f - bias.

        Args:
            q: Generalized coordinates (6 + n,).
            w: Quasi-velocities (6 + n,).
            tau_b: Generalized body forces (6 + n,): vehicle force and moment in base_link_frd
                about the body origin, then joint torques.
            f_ee_ned: Force acting ON the end effector, in map_ned (3,) (N); None for none.
                A wall contact force F_e exerted BY the end effector enters as -F_e.
            current_ned: The water's velocity v_c in map_ned (3,) (m/s), or None for still
                water (``bias_body``).
        """
        q_list = self._check_q(q).tolist()
        w = _vector('w', w, self.n_dof)
        tau_b = _vector('tau_b', tau_b, self.n_dof)
        f = None if f_ee_ned is None else _vector('f_ee_ned', f_ee_ned, 3).tolist()
        rot = rotation(q_list[3], q_list[4], q_list[5])
        self.dynamics.set_tau_b(tau_b)
        f_body = None if f is None else mat_t_vec(rot, f)
        w_dot: FloatArray = self.dynamics.w_dot(q_list[6:], w, self._gravity_body(rot), f_body,
                                                self._current_body(rot, current_ned))
        return w_dot[:self.n_dof]

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
        current_ned: ArrayLike | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """Advance (q, w) by one fixed step dt with tau_b, f_ee_ned and the current held.

        Args:
            q: Generalized coordinates (6 + n,).
            w: Quasi-velocities (6 + n,).
            tau_b: Generalized body forces (6 + n,) (eq. 8).
            f_ee_ned: Force ON the end effector in map_ned (3,) (N), or None.
            dt: Step (s), positive.
            method: 'rk4' or 'semi_implicit_euler'; None uses ``integration.method``.
            current_ned: The water's velocity v_c in map_ned (3,) (m/s), uniform and held over
                the step, or None for still water (``bias_body``).

        Returns:
            (q, w) at t + dt.

        Raises:
            StateError: For a wrong shape, a non-finite input or a non-finite result.
            SingularAttitudeError: If the pitch reaches +-90 deg.
        """
        current = None if current_ned is None else _vector('current_ned', current_ned, 3)
        q_arr = np.asarray(q, dtype=float)
        w_arr = np.asarray(w, dtype=float)
        tau_arr = np.asarray(tau_b, dtype=float)
        q_list = q_arr.tolist()
        if (
            q_arr.shape != (self.n_dof,)
            or w_arr.shape != (self.n_dof,)
            or tau_arr.shape != (self.n_dof,)
            or not math.isfinite(sum(q_list) + sum(w_arr.tolist()) + sum(tau_arr.tolist()))
        ):
            # Slow path, only to name the offending argument.
            _vector('q', q, self.n_dof)
            _vector('w', w, self.n_dof)
            _vector('tau_b', tau_b, self.n_dof)
        f = None if f_ee_ned is None else _vector('f_ee_ned', f_ee_ned, 3).tolist()
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0.0):
            raise StateError(f'dt must be a positive finite number of seconds, got {dt!r}')
        method = self._method if method is None else method
        self.dynamics.set_tau_b(tau_arr)
        dt = float(dt)
        if method == 'rk4':
            q_new, w_new = self._rk4.step(q_arr, w_arr, f, dt, current)
        elif method == 'semi_implicit_euler':
            q_new, w_new = semi_implicit_euler_step(self.dynamics, self._g, q_list, w_arr, f, dt,
                                                    current)
        else:
            raise ModelError(f"method = {method!r} must be 'rk4' or 'semi_implicit_euler'")
        if not math.isfinite(sum(q_new.tolist()) + sum(w_new.tolist())):
            raise StateError(
                f'the state diverged in one step of dt = {dt!r} s from q = {q_arr.tolist()!r}, '
                f'w = {w_arr.tolist()!r}'
            )
        return q_new, w_new

    # ------------------------------------------------------------------ generalized coordinates

    def velocity_transform(self, q: ArrayLike) -> FloatArray:
        """B(q) (6 + n, 6 + n) of eq. 4, q_dot = B w: blockdiag(J1, J2, I) (paper sec. 3.2).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
            StateError: If q is not a finite (6 + n,) vector.
        """
        return velocity_transform(self._check_q(q))

    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """M(q) = B^-T M_b B^-1 (6 + n, 6 + n) in generalized coordinates (eq. 18).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg (the Euler-angle form of eq. 18).
        """
        q_arr = self._check_q(q)
        check_pitch(float(q_arr[4]))
        b_inv = velocity_transform_inverse(q_arr)
        mass = self.dynamics.mass(q_arr.tolist()[6:])
        result: FloatArray = b_inv.T.dot(mass.dot(b_inv))
        return result

    def bias(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """zeta(q, q_dot) = C q_dot + D q_dot + G (6 + n,) of eq. 19, so M q_ddot + zeta = tau.

        zeta = B^-T (C_b w + D_b w + G_b - M_b B^-1 B_dot w) with w = B^-1 q_dot (eq. 18).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
        """
        q = self._check_q(q)
        q_dot = _vector('q_dot', q_dot, self.n_dof)
        return self.task_space_terms(q, q_dot).zeta

    # ------------------------------------------------------------------ end effector

    def ee_position(self, q: ArrayLike) -> FloatArray:
        """End-effector position X (3,) in map_ned (ee_link, at the tip of the arm)."""
        return self.frames.frame(self._check_q(q).tolist(), EE_LINK)[0]

    def ee_rotation(self, q: ArrayLike) -> FloatArray:
        """rot_ned_from_ee (3, 3): ee_link axes, aligned with link 3 (x along the link)."""
        return self.frames.frame(self._check_q(q).tolist(), EE_LINK)[1]

    def ee_jacobian(self, q: ArrayLike) -> FloatArray:
        """EE Jacobian J (3, 6 + n) in map_ned with respect to q_dot: X_dot = J q_dot (eq. 22).

        J = J_w B^-1 with J_w the Jacobian with respect to the quasi-velocities w.

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg (the Euler-angle form of eq. 18).
        """
        q_arr = self._check_q(q)
        check_pitch(float(q_arr[4]))
        jac_w = self.frames.ee_motion(q_arr.tolist(), None)[2]
        b_inv = velocity_transform_inverse(q_arr)
        result: FloatArray = jac_w.dot(b_inv)
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
        q_dot = _vector('q_dot', q_dot, self.n_dof)
        return self.task_space_terms(q, q_dot).J_dot_q_dot

    def task_space_terms(
        self, q: ArrayLike, q_dot: ArrayLike | None = None, *, w: ArrayLike | None = None
    ) -> TaskSpaceTerms:
        """X, J, J_dot q_dot (eq. 22-23), M, zeta (eq. 18-19) and B at one state, in one pass.

        M = B^-T M_b B^-1 and zeta = B^-T (bias_b - M_b B^-1 B_dot w) (eq. 18); J = J_w B^-1
        and J_dot q_dot = J_w_dot w - J_w B^-1 B_dot w (eq. 22-23).

        Args:
            q: Generalized coordinates (6 + n,), finite.
            q_dot: Generalized velocities (6 + n,), finite; or None with ``w``.
            w: Quasi-velocities (6 + n,) instead of ``q_dot`` (q_dot = B w, eq. 4).

        Raises:
            SingularAttitudeError: Near pitch = +-90 deg.
        """
        q_arr = np.asarray(q, dtype=float)
        q_list = q_arr.tolist()
        check_pitch(q_list[4])
        rot = rotation(q_list[3], q_list[4], q_list[5])
        if w is None:
            w_arr = velocity_transform_inverse(q_arr).dot(np.asarray(q_dot, dtype=float))
        else:
            w_arr = np.asarray(w, dtype=float)
        mass, bias = self.dynamics.mass_and_bias(q_list[6:], w_arr, self._gravity_body(rot))
        x, rot_ee, jac_w, acc = self.frames.ee_motion(q_list, w_arr)
        jac, j_dot_q_dot, mass_q, zeta, b, q_dot_arr = generalized_terms(
            q_arr, w_arr, mass, bias, jac_w, acc
        )
        return TaskSpaceTerms(
            X=x,
            J=jac,
            J_dot_q_dot=j_dot_q_dot,
            M=mass_q,
            zeta=zeta,
            B=b,
            rot_ned_from_ee=rot_ee,
            q_dot=q_dot_arr,
        )

    # ------------------------------------------------------------------ poses and IK

    def frame_poses(
        self, q: ArrayLike, frames: Sequence[str] | None = None
    ) -> dict[str, tuple[FloatArray, FloatArray]]:
        """Poses of base_link_frd, the arm links, ee_link, ft_sensor_link in map_ned.

        Args:
            q: Generalized coordinates (6 + n,).
            frames: The frames to pose, a subset of ``frame_names`` (None: all).

        Returns:
            {frame: (p_ned (3,), rot_ned_from_frame (3, 3))}; an arm link sits at its joint,
            ee_link and ft_sensor_link where the URDF puts them.

        Raises:
            ModelError: For a frame name not in ``frame_names``.
        """
        return self.frames.poses(self._check_q(q).tolist(),
                                 self.frame_names if frames is None else frames)

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
        """Arm joint angles (n,) that put the end effector at ``x_ned`` (damped least squares).

        Args:
            q_vehicle: Vehicle pose (6,): position in map_ned and roll, pitch, yaw.
            x_ned: Desired end-effector position in map_ned (3,) (m).
            q_arm_guess: Initial joint angles (n,) (rad); selects the branch (elbow up/down).
            tolerance_m: Position error at which to stop (m).
            max_iterations: Iteration limit.
            damping: Damping lambda of dq = J^T (J J^T + lambda^2 I)^-1 e (m).

        Raises:
            UnreachableError: If the error stays above 1e-6 m (point out of reach).
        """
        return self.frames.joint_positions_for_ee_position(
            _vector('q_vehicle', q_vehicle, 6),
            _vector('x_ned', x_ned, 3),
            _vector('q_arm_guess', q_arm_guess, self.n_joints),
            tolerance_m,
            max_iterations,
            damping,
        )
