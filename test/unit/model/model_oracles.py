"""Oracles for the uvms_model tests: random states and a hand-built Pinocchio model.

The hand-built model takes the paper's numbers as ``reference_model.ReferenceRobot`` writes
them out, not the URDF: it checks that the URDF, as Pinocchio reads it for uvms_model, holds
the same bodies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray
from reference_model import ReferenceRobot
from uvms_model.hydrodynamics import cylinder_inertia
from uvms_model.kinematics import rot_ned_from_body

FloatArray = NDArray[np.float64]


def random_state(seed: int, max_pitch: float = 1.4) -> tuple[FloatArray, FloatArray]:
    """Random (q, w): positions +-5 m, any roll, yaw and joint angle, |pitch| < max_pitch."""
    rng = np.random.default_rng(seed)
    q = np.concatenate(
        (
            rng.uniform(-5.0, 5.0, 3),
            [rng.uniform(-np.pi, np.pi), rng.uniform(-max_pitch, max_pitch)],
            [rng.uniform(-np.pi, np.pi)],
            rng.uniform(-np.pi, np.pi, 3),
        )
    )
    w = rng.normal(0.0, 1.0, 9)
    return q, w


@dataclass
class PinocchioOracle:
    """Pinocchio model of the same rigid bodies: free-flyer vehicle + 3 revolute joints."""

    model: pin.Model
    data: pin.Data

    def configuration(self, q: FloatArray) -> FloatArray:
        """Pinocchio configuration [x, y, z, quaternion (x, y, z, w), q1, q2, q3] from q."""
        quat = pin.Quaternion(rot_ned_from_body(q[3], q[4], q[5])).coeffs()
        return np.concatenate((q[:3], quat, q[6:]))

    def mass_matrix(self, q: FloatArray) -> FloatArray:
        """CRBA mass matrix in the free-flyer velocity w (symmetrized)."""
        upper = pin.crba(self.model, self.data, self.configuration(q))
        return np.triu(upper) + np.triu(upper, 1).T

    def bias(self, q: FloatArray, w: FloatArray) -> FloatArray:
        """RNEA at zero acceleration: Coriolis, centrifugal and gravity forces."""
        return pin.rnea(self.model, self.data, self.configuration(q), w, np.zeros(9))

    def body_jacobians(self, q: FloatArray) -> list[FloatArray]:
        """Body Jacobians (6, 9) [linear; angular] of the vehicle and links, local frames."""
        config = self.configuration(q)
        pin.computeJointJacobians(self.model, self.data, config)
        return [
            pin.getJointJacobian(self.model, self.data, joint, pin.ReferenceFrame.LOCAL)
            for joint in range(1, 5)
        ]

    def body_motion(self, q: FloatArray, w: FloatArray) -> list[tuple[FloatArray, FloatArray]]:
        """Body twists and spatial accelerations at w_dot = 0 (J_dot w), local frames."""
        pin.forwardKinematics(self.model, self.data, self.configuration(q), w, np.zeros(9))
        return [
            (self.data.v[joint].vector.copy(), self.data.a[joint].vector.copy())
            for joint in range(1, 5)
        ]


def build_oracle(robot: ReferenceRobot, gravity_m_s2: float = 9.81) -> PinocchioOracle:
    """Build the Pinocchio model of the rigid bodies of ``robot`` (gravity +z in map_ned)."""
    model = pin.Model()
    model.gravity = pin.Motion(np.array([0.0, 0.0, gravity_m_s2, 0, 0, 0]))
    vehicle = robot.vehicle
    root = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), 'base_link_frd')
    model.appendBodyToJoint(
        root,
        pin.Inertia(
            vehicle.mass_kg, np.array(vehicle.center_of_gravity_m), np.diag(vehicle.inertia_kg_m2)
        ),
        pin.SE3.Identity(),
    )
    arm = robot.arm
    axes = np.array(arm.joint_axes).reshape(3, 3)
    parent, placement = root, np.array(arm.mount_position_m)
    for i in range(3):
        length, radius, mass = arm.link_lengths_m[i], arm.link_radii_m[i], arm.link_masses_kg[i]
        joint = model.addJoint(
            parent,
            pin.JointModelRevoluteUnaligned(axes[i]),
            pin.SE3(np.eye(3), placement),
            arm.joint_names[i],
        )
        model.appendBodyToJoint(
            joint,
            pin.Inertia(
                mass, np.array([0.5 * length, 0.0, 0.0]), cylinder_inertia(mass, length, radius)
            ),
            pin.SE3.Identity(),
        )
        parent, placement = joint, np.array([length, 0.0, 0.0])
    return PinocchioOracle(model, model.createData())
