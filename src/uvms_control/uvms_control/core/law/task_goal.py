"""The goal of a contact task as plain arrays: what the controller's reference follows.

Here, in ``core.law``, because the reference (``task_reference``) and the controller start a
goal's path from it; its checks, limits and results stay in ``core.task.contact_task``,
which re-exports it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class ContactTaskGoal:
    """A ContactTask goal as arrays (map_ned, SI units).

    Attributes:
        path: waypoints X_d (n, 3) (m).
        times: time of each waypoint from the path's start (n,) (s).
        velocities: Ẋ_d at each waypoint (n, 3) (m/s), or None (chosen by the path).
        accelerations: Ẍ_d at each waypoint (n, 3) (m/s²), or None (zero).
        normal: force direction into the surface (3,) (-), not necessarily unit.
        force_n: F_d along the normal while in contact (N); 0: motion only.
        force_ramp_s: ramp of F_d after first contact and down at release (s).
        require_contact: end with NO_CONTACT if the path ends without contact.
        start_time_s: when the path's time 0 is on the controller's clock (s); None: at once.
    """

    path: FloatArray
    times: FloatArray
    velocities: FloatArray | None
    accelerations: FloatArray | None
    normal: FloatArray
    force_n: float
    force_ramp_s: float
    require_contact: bool = False
    start_time_s: float | None = None
