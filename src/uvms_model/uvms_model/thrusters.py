"""Thruster layout and the thruster-actuator configuration matrix E of the paper's eq. 9.

tau_b = E F_td with F_td = [thrusts (N); joint torques (N m)]: thruster i at r_i pushing
along the unit d_i adds the body wrench [d_i; r_i x d_i] about the base_link_frd origin; the
arm's direct-drive motors act on their own joint rows only (a joint torque is an internal
torque between two links, so it has no vehicle row in the generalized forces).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uvms_model.errors import ParameterError
from uvms_model.parameters import ThrusterParameters

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ThrusterLayout:
    """Positions, unit directions and thrust limits of the vehicle's thrusters.

    Attributes:
        positions_m: Thruster positions in base_link_frd, shape (p, 3) (m).
        directions: Unit thrust directions in base_link_frd, shape (p, 3).
        max_thrust_n: Thrust magnitude limit of each thruster, shape (p,) (N).
    """

    positions_m: FloatArray
    directions: FloatArray
    max_thrust_n: FloatArray

    @classmethod
    def from_parameters(cls, params: ThrusterParameters | None = None) -> ThrusterLayout:
        """Layout from the ``thrusters.*`` parameters (the default 8-thruster layout if None)."""
        params = params if params is not None else ThrusterParameters()
        positions = np.array(params.positions_m, dtype=float).reshape(-1, 3)
        directions = np.array(params.directions, dtype=float).reshape(-1, 3)
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        return cls(positions, directions, np.array(params.max_thrust_n, dtype=float))

    @property
    def count(self) -> int:
        """Number of thrusters p."""
        return int(self.positions_m.shape[0])

    def thrust_matrix(self) -> FloatArray:
        """Vehicle block T (6, p) of E: column i is [d_i; r_i x d_i]."""
        return np.vstack((self.directions.T, np.cross(self.positions_m, self.directions).T))

    def configuration_matrix(self, n_joints: int) -> FloatArray:
        """Thruster-actuator configuration matrix E (6 + n, p + n) of eq. 9.

        Args:
            n_joints: Number of arm joints n, each driven by one direct-drive motor.

        Returns:
            E = [[T, 0], [0, I_n]] so that tau_b = E [thrusts; joint torques].

        Raises:
            ParameterError: If E has rank below 6 + n (the thrusters cannot produce every
                vehicle wrench).
        """
        p = self.count
        e = np.zeros((6 + n_joints, p + n_joints))
        e[:6, :p] = self.thrust_matrix()
        e[6:, p:] = np.eye(n_joints)
        rank = int(np.linalg.matrix_rank(e))
        if rank < 6 + n_joints:
            raise ParameterError(
                f'thrusters.positions_m/thrusters.directions give a configuration matrix E of '
                f'rank {rank}, expected full row rank {6 + n_joints} (paper eq. 9)'
            )
        return e


def configuration_matrix(params: ThrusterParameters | None, n_joints: int) -> FloatArray:
    """E (6 + n, p + n) of eq. 9 for the ``thrusters.*`` parameters; see ThrusterLayout."""
    return ThrusterLayout.from_parameters(params).configuration_matrix(n_joints)
