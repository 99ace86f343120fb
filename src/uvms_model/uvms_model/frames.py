"""Frame kinematics of the UVMS on the URDF's Pinocchio model: poses, the EE Jacobian, IK.

Everything is posed in map_ned from q = [x, y, z, phi, theta, psi, q_1 .. q_n]: the
kinematic model's free-flyer configuration is [p (3), quaternion x y z w (4), q_m (3)] and its
velocity the quasi-velocities w (body twist in base_link_frd, joint rates). Pinocchio's names
glossed: ``oMf`` placement of a frame in the world, ``LOCAL_WORLD_ALIGNED`` a frame's origin
with the world's axes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin  # type: ignore[import-untyped]
from numpy.typing import NDArray

from uvms_model.coordinates import quaternion_xyzw
from uvms_model.description import EE_LINK
from uvms_model.errors import ModelError, UnreachableError

FloatArray = NDArray[np.float64]


class FrameKinematics:
    """Poses and end-effector motion of the URDF's frames, on one Pinocchio workspace.

    Not thread-safe. Arrays returned are new.

    Args:
        model: The kinematic Pinocchio model (``pinocchio_models.kinematic_model``).
        frame_names: The frames to pose (``RobotDescription.frame_names``).
    """

    def __init__(self, model: pin.Model, frame_names: Sequence[str]) -> None:
        self.model = model
        self._data = model.createData()
        self.frame_names = tuple(frame_names)
        self.frame_ids = {name: model.getFrameId(name) for name in self.frame_names}
        self._ee_frame = self.frame_ids[EE_LINK]
        self._config = pin.neutral(model)
        self._zero = np.zeros(model.nv)
        self._w = np.zeros(model.nv)

    def _pose(self, q: Sequence[float]) -> None:
        """Set the configuration (base pose from x, y, z and the Euler angles)."""
        self._config[:] = (q[0], q[1], q[2], *quaternion_xyzw(q[3], q[4], q[5]), *q[6:])

    def frame(self, q: Sequence[float], name: str) -> tuple[FloatArray, FloatArray]:
        """(p_ned, rot_ned_from_frame) of one frame, by forward kinematics."""
        self._pose(q)
        pin.forwardKinematics(self.model, self._data, self._config)
        placement = pin.updateFramePlacement(self.model, self._data, self.frame_ids[name])
        return placement.translation.copy(), placement.rotation.copy()

    def poses(
        self, q: Sequence[float], frames: Sequence[str]
    ) -> dict[str, tuple[FloatArray, FloatArray]]:
        """{frame: (p_ned, rot_ned_from_frame)} of the named frames.

        Raises:
            ModelError: For a frame name not in ``frame_names``.
        """
        for name in frames:
            if name not in self.frame_ids:
                raise ModelError(f'frame {name!r} is not one of {self.frame_names}')
        self._pose(q)
        model, data = self.model, self._data
        pin.forwardKinematics(model, data, self._config)
        poses = {}
        for name in frames:
            placement = pin.updateFramePlacement(model, data, self.frame_ids[name])
            poses[name] = (placement.translation.copy(), placement.rotation.copy())
        return poses

    def ee_motion(
        self, q: Sequence[float], w: Sequence[float] | FloatArray | None
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """X, rot_ned_from_ee, J_w (3, 6 + n) and J_w_dot w (3,) of the EE in map_ned (w-based).

        J_w_dot w is the classical acceleration of the EE point at w_dot = 0 (Pinocchio's
        frame classical acceleration); None for w means at rest.
        """
        self._pose(q)
        model, data = self.model, self._data
        if w is None:
            velocity = self._zero
        else:
            velocity = self._w
            velocity[:] = w
        pin.forwardKinematics(model, data, self._config, velocity, self._zero)
        pin.computeJointJacobians(model, data)
        placement = pin.updateFramePlacement(model, data, self._ee_frame)
        jac = pin.getFrameJacobian(model, data, self._ee_frame, pin.LOCAL_WORLD_ALIGNED)[:3]
        acc = pin.getFrameClassicalAcceleration(
            model, data, self._ee_frame, pin.LOCAL_WORLD_ALIGNED
        ).linear
        return placement.translation.copy(), placement.rotation.copy(), jac, acc

    def joint_positions_for_ee_position(
        self,
        q_vehicle: FloatArray,
        target: FloatArray,
        q_arm_guess: FloatArray,
        tolerance_m: float,
        max_iterations: int,
        damping: float,
    ) -> FloatArray:
        """Arm joint angles (3,) that put the end effector at ``target`` (damped least squares).

        dq = J^T (J J^T + lambda^2 I)^-1 e with the arm's columns of J.

        Raises:
            UnreachableError: If the error stays above 1e-6 m (point out of reach).
        """
        qm = q_arm_guess.copy()
        error = np.full(3, np.inf)
        for _ in range(max_iterations):
            x, _, jac_w, _ = self.ee_motion([*q_vehicle.tolist(), *qm.tolist()], None)
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
                f'{max_iterations} iterations', residual
            )
        result: FloatArray = np.arctan2(np.sin(qm), np.cos(qm))
        return result
