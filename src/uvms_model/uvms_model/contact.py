"""Contact environment: a frictionless, unilateral spring wall normal to map_ned x (paper 5.1).

The wall starts at x = ``contact.wall_position_m`` (1.7771 m in the paper) and, if
``contact.wall_speed_m_s`` is not zero, moves along +x at that speed from the first contact
on (paper Case III: 0.05 m/s). The force F_e is the one the end effector exerts ON the wall,
in map_ned: F_e = [max(0, K_e delta + D delta_dot), 0, 0] while the penetration
delta = x_ee - x_wall is positive; the robot feels -F_e.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uvms_model.errors import StateError
from uvms_model.parameters import ContactParameters

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ContactState:
    """Contact ground truth at one instant.

    Attributes:
        in_contact: True while the end effector penetrates the wall.
        force_ned: Force exerted by the end effector on the wall, map_ned (3,) (N).
        penetration_m: Penetration depth (m), >= 0.
        wall_position_m: Wall surface position along map_ned x (m).
        wall_velocity_m_s: Wall speed along map_ned x (m/s).
    """

    in_contact: bool
    force_ned: FloatArray
    penetration_m: float
    wall_position_m: float
    wall_velocity_m_s: float


def _point(name: str, value: ArrayLike) -> FloatArray:
    array = np.asarray(value, dtype=float)
    if array.shape != (3,):
        raise StateError(f'{name} must have shape (3,), got {array.shape}')
    # A finite sum is the cheap test (a huge finite sum may overflow: then look again).
    if not math.isfinite(sum(array.tolist())) and not np.isfinite(array).all():
        raise StateError(f'{name} must be finite, got {array.tolist()!r}')
    return array


class WallContact:
    """Spring(-damper) wall normal to map_ned x, optionally moving after the first contact.

    Example:
        >>> wall = WallContact(ContactParameters(stiffness_n_m=1e4))
        >>> wall.update(0.0, [1.7871, 0.0, 0.0]).force_ned  # 1 cm in: 100 N  # doctest: +SKIP
        array([100.,   0.,   0.])
    """

    def __init__(self, params: ContactParameters | None = None) -> None:
        self.params = params if params is not None else ContactParameters()
        self._contact_time_s: float | None = None

    @property
    def contact_time_s(self) -> float | None:
        """Time of the first contact (s), None before it."""
        return self._contact_time_s

    def reset(self) -> None:
        """Forget the first contact: the wall returns to its initial position."""
        self._contact_time_s = None

    def wall_velocity(self, t: float) -> float:
        """Wall speed along map_ned x at time t (m/s): zero until the first contact."""
        if self._contact_time_s is None or t < self._contact_time_s:
            return 0.0
        return self.params.wall_speed_m_s

    def wall_position(self, t: float) -> float:
        """Wall position along map_ned x at time t (m)."""
        x0 = self.params.wall_position_m
        if self._contact_time_s is None:
            return x0
        return x0 + self.params.wall_speed_m_s * max(0.0, t - self._contact_time_s)

    def evaluate(
        self, t: float, x_ee_ned: ArrayLike, v_ee_ned: ArrayLike | None = None
    ) -> ContactState:
        """Contact state for the end effector at x_ee_ned (m) moving at v_ee_ned (m/s).

        Pure: does not latch the first contact (use ``update`` once per simulation step).

        Raises:
            StateError: For a non-finite time, position or velocity, or a wrong shape.
        """
        if not math.isfinite(t):
            raise StateError(f't must be finite, got {t!r}')
        x = _point('x_ee_ned', x_ee_ned)
        v_x = 0.0 if v_ee_ned is None else float(_point('v_ee_ned', v_ee_ned)[0])
        wall_x = self.wall_position(t)
        wall_v = self.wall_velocity(t)
        penetration = float(x[0]) - wall_x
        force = np.zeros(3)
        if penetration <= 0.0:
            return ContactState(False, force, 0.0, wall_x, wall_v)
        normal = self.params.stiffness_n_m * penetration + self.params.damping_n_s_m * (
            v_x - wall_v
        )
        force[0] = max(0.0, normal)
        return ContactState(True, force, penetration, wall_x, wall_v)

    def update(
        self, t: float, x_ee_ned: ArrayLike, v_ee_ned: ArrayLike | None = None
    ) -> ContactState:
        """Evaluate the contact at time t and latch the first contact (starts a moving wall)."""
        state = self.evaluate(t, x_ee_ned, v_ee_ned)
        if state.in_contact and self._contact_time_s is None:
            self._contact_time_s = float(t)
        return state
