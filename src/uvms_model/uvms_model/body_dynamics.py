"""The UVMS's equations of motion in body form (paper eq. 8) on Pinocchio's compiled algorithms.

M_b(q_m) w_dot + C_b(q_m, w) w + D_b(q_m, w) w + G_b(q) = tau_b, in the quasi-velocities w of
eq. 4. The dynamic model (``uvms_model.pinocchio_models``) is posed with its base at the origin
of base_link_frd, so its "world" is the body frame and the attitude enters only through the
gravity direction; drag, slider corrections, net weights and the end-effector force are its
external forces (``uvms_model.body_forces``).

Pinocchio's terse names, glossed: ``crba`` composite-rigid-body algorithm (mass matrix),
``rnea`` recursive Newton-Euler (inverse dynamics), ``aba`` articulated-body algorithm
(forward dynamics), ``fext`` external forces per joint in its local frame, ``oMi`` joint
placements in the world (o: origin), ``v`` joint twists in their local frames.

Speed: per evaluation a fixed handful of compiled calls on preallocated arrays, read and
written through strided numpy views of Pinocchio's workspace (no per-call Pinocchio objects).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin  # type: ignore[import-untyped]
from numpy.typing import NDArray

from uvms_model.added_mass import AddedMass
from uvms_model.body_forces import BodyForces
from uvms_model.coordinates import Vec3
from uvms_model.description import RobotDescription
from uvms_model.jit import kernel
from uvms_model.loop_products import spatial_cross_force
from uvms_model.parameters import HydrodynamicsParameters
from uvms_model.pinocchio_models import dynamic_model, strided_rows

FloatArray = NDArray[np.float64]


class BodyDynamics:
    """M_b, the bias of eq. 8 and w_dot at a state, on one preallocated Pinocchio workspace.

    Not thread-safe. Arrays returned are new.

    Args:
        description: The robot description.
        hydro: Hydrodynamic switches and constants.
        kin: The kinematic model (the URDF as written).
        added: Added mass of the hull and each arm link (None: none).
        hull_added: M_A (6, 6) of a hull given by coefficients (``hull_added_mass_matrix``),
            None otherwise. The hull is the free-flyer root, whose body Jacobian is [I 0]:
            M_A enters the mass matrix as its top-left block and ν₀ ×* M_A ν₀ the bias
            (Kirchhoff), so w_dot is solved from M_b (CRBA and RNEA) instead of by ABA.
    """

    def __init__(
        self,
        description: RobotDescription,
        hydro: HydrodynamicsParameters,
        kin: pin.Model,
        added: list[AddedMass | None],
        hull_added: FloatArray | None = None,
    ) -> None:
        model, bodies, sliders = dynamic_model(description, kin, added)
        self._hull_added = hull_added
        self.model = model
        """The Pinocchio model: rigid bodies, added mass (rigid part + sliders), no gravity."""
        data = model.createData()
        self._data = data
        self._config = pin.neutral(model)  # base at the origin, identity attitude, always
        self.n_dof = n_dof = 6 + description.n_joints
        """Quasi-velocities w: the vehicle's 6 and the n arm joints' rates."""
        self._arm_config: FloatArray = self._config[7:1 + n_dof]  # a view: the arm's angles
        self._v = np.zeros(model.nv)
        self._w = self._v[:n_dof]  # views: the quasi-velocities w ...
        self._tau = np.zeros(model.nv)
        self._tau_b = self._tau[:n_dof]  # ... and the generalized body forces tau_b
        self._zero = np.zeros(model.nv)
        self._fext = pin.StdVec_Force()
        for _ in range(model.njoints):
            self._fext.append(pin.Force.Zero())
        pin.forwardKinematics(model, data, self._config, self._v)
        n = model.njoints
        self.forces = BodyForces(
            description,
            hydro,
            added,
            kin,
            bodies,
            strided_rows([data.v[k].vector for k in range(n)], 6),
            strided_rows([data.oMi[k].rotation[:, 0] for k in range(n)], 12),
            strided_rows([self._fext[k].vector for k in range(n)], 6),
            hull_added,
        )
        # Sliders: M_ss is diagonal and constant (each carries its point mass only).
        self._slider_mass_inverse = 1.0 / np.array([model.inertias[j].mass for j in sliders])

    @property
    def arm_angles(self) -> FloatArray:
        """The arm joints' angles (n,) of the posed configuration: a view to write into."""
        return self._arm_config

    @property
    def quasi_velocities(self) -> FloatArray:
        """The quasi-velocities w (6 + n,) of the posed state: a view to write into."""
        return self._w

    def accelerations_as_posed(self, vectors: FloatArray) -> FloatArray:
        """ABA at the state written into ``arm_angles`` and ``quasi_velocities`` (w_dot first).

        Args:
            vectors: (3, 2) gravitational acceleration (m/s^2) and the force ON the end
                effector (N), both in base_link_frd, as columns.
        """
        model, data = self.model, self._data
        pin.forwardKinematics(model, data, self._config, self._v)
        self.forces.apply_vectors(vectors)
        if self._hull_added is not None:
            return self._solved_w_dot()
        result: FloatArray = pin.aba(model, data, self._config, self._v, self._tau, self._fext)
        return result

    def set_tau_b(self, tau_b: FloatArray) -> None:
        """Hold the generalized body forces tau_b (6 + n,) for the following ``w_dot`` calls."""
        self._tau_b[:] = tau_b

    def w_dot(
        self,
        q_m: list[float],
        w: FloatArray | list[float],
        gravity_body: Vec3,
        f_ee_body: Vec3 | None,
        current_body: Vec3 | None = None,
    ) -> FloatArray:
        """Accelerations of eq. 8 by ABA at (q_m, w) with the held tau_b: w_dot is ``[:6 + n]``.

        Args:
            q_m: Arm joint angles (n,) (rad).
            w: Quasi-velocities (6 + n,).
            gravity_body: Gravitational acceleration in base_link_frd (m/s^2).
            f_ee_body: Force ON the end effector in base_link_frd (N), or None.
            current_body: The water's velocity in base_link_frd (m/s), or None (still water).

        Returns:
            A new array of the dynamic model's accelerations: w_dot (6 + n,), then the sliders'.
        """
        self._arm_config[:] = q_m
        self._w[:] = w
        model, data = self.model, self._data
        pin.forwardKinematics(model, data, self._config, self._v)
        self.forces.apply(gravity_body, f_ee_body, current_body)
        if self._hull_added is not None:
            return self._solved_w_dot()
        result: FloatArray = pin.aba(model, data, self._config, self._v, self._tau, self._fext)
        return result

    def _solved_w_dot(self) -> FloatArray:
        """w_dot = M_b⁻¹ (tau_b - bias_b) at the posed state and forces, hull M_A included."""
        model, data = self.model, self._data
        full = pin.crba(model, data, self._config)
        tau = pin.rnea(model, data, self._config, self._v, self._zero, self._fext)
        assert self._hull_added is not None
        return solve_with_hull(full, tau, self._slider_mass_inverse, self._hull_added,
                               self._w, self._tau_b)

    def _with_hull(self, mass_b: FloatArray, bias_b: FloatArray) -> tuple[FloatArray, FloatArray]:
        """M_b and bias_b with a coefficient hull's M_A and ν₀ ×* M_A ν₀ (none: unchanged)."""
        if self._hull_added is not None:
            mass_b[:6, :6] += self._hull_added
            bias_b[:6] += spatial_cross_force(self._w[:6], self._hull_added @ self._w[:6])
        return mass_b, bias_b

    def mass(self, q_m: list[float]) -> FloatArray:
        """M_b(q_m) (6 + n, 6 + n) by CRBA with the sliders eliminated (``eliminate_sliders``)."""
        self._arm_config[:] = q_m
        full = pin.crba(self.model, self._data, self._config)  # a new symmetric array
        mass_b = eliminate_sliders(full, self._zero, self._slider_mass_inverse)[0]
        if self._hull_added is not None:
            mass_b[:6, :6] += self._hull_added
        return mass_b

    def mass_and_bias(
        self, q_m: list[float], w: FloatArray, gravity_body: Vec3,
        current_body: Vec3 | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """M_b(q_m) and C_b w + D_b w + G_b (eq. 8): CRBA and RNEA, sliders eliminated.

        With ``current_body`` (v_c in base_link_frd, m/s) the bias is the relative-velocity
        form's (``uvms_model.relative_flow``).
        """
        self._w[:] = w
        self._arm_config[:] = q_m
        model, data = self.model, self._data
        full = pin.crba(model, data, self._config)  # a new symmetric array
        pin.forwardKinematics(model, data, self._config, self._v)
        self.forces.apply(gravity_body, None, current_body)
        tau = pin.rnea(model, data, self._config, self._v, self._zero, self._fext)
        return self._with_hull(*eliminate_sliders(full, tau, self._slider_mass_inverse))


@kernel
def eliminate_sliders(
    mass_full: FloatArray, bias_full: FloatArray, slider_mass_inverse: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """M_b and bias_b of eq. 8 from the dynamic model's M and bias, the sliders eliminated.

    With the sliders' rows s (past the body rows r) and M_ss diagonal, eliminating their
    accelerations (they transmit no force) gives M_b = M_rr - M_rs M_ss⁻¹ M_sr and
    bias_b = b_r - M_rs M_ss⁻¹ b_s. New arrays; compiled.
    """
    n = mass_full.shape[0] - slider_mass_inverse.shape[0]
    mass_b = np.empty((n, n))
    bias_b = np.empty(n)
    for i in range(n):
        total = bias_full[i]
        for s in range(slider_mass_inverse.shape[0]):
            total -= mass_full[i, n + s] * slider_mass_inverse[s] * bias_full[n + s]
        bias_b[i] = total
        for j in range(n):
            total = mass_full[i, j]
            for s in range(slider_mass_inverse.shape[0]):
                total -= mass_full[i, n + s] * slider_mass_inverse[s] * mass_full[j, n + s]
            mass_b[i, j] = total
    return mass_b, bias_b


@kernel
def solve_with_hull(
    mass_full: FloatArray, bias_full: FloatArray, slider_mass_inverse: FloatArray,
    hull_added: FloatArray, w: FloatArray, tau_b: FloatArray,
) -> FloatArray:
    """w_dot of eq. 8 with a coefficient hull: sliders eliminated, M_A and ν₀ ×* M_A ν₀ added.

    (M_b + [M_A 0; 0 0]) w_dot = tau_b - bias_b - [ν₀ ×* M_A ν₀; 0]; compiled.
    """
    mass_b, bias_b = eliminate_sliders(mass_full, bias_full, slider_mass_inverse)
    nu = w[:6].copy()
    bias_b[:6] += spatial_cross_force(nu, hull_added @ nu)
    mass_b[:6, :6] += hull_added
    result: FloatArray = np.linalg.solve(mass_b, tau_b - bias_b)  # type: ignore[assignment]
    return result
