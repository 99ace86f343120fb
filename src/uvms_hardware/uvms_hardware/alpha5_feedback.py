"""What the Alpha 5's devices reported, as the bridge's core keeps it and hands it out.

``DeviceFeedback`` is one device's last answers with their arrival times; ``JointSample`` one
joint state made of fresh answers only (``alpha5_core.Alpha5Core.next_joint_state``). The
protocol has no device clock, so an arrival time on the bridge's clock is the only stamp.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ['DeviceFeedback', 'JointSample']


@dataclass
class DeviceFeedback:
    """What a device last reported (SI) and when it arrived (s of the bridge's clock)."""

    position: float = math.nan
    velocity: float = math.nan
    position_s: float = -math.inf
    velocity_s: float = -math.inf
    status: bytes = b''
    status_s: float = -math.inf

    @property
    def answer_s(self) -> float:
        """Arrival of the device's last feedback answer (-inf before the first)."""
        return max(self.position_s, self.velocity_s)

    @property
    def oldest_s(self) -> float:
        """Arrival of the older of its last position and velocity (-inf before both)."""
        return min(self.position_s, self.velocity_s)


@dataclass(frozen=True)
class JointSample:
    """One joint state of fresh answers only, in drive order.

    Attributes:
        names: Joint names.
        positions: rad (jaw m).
        velocities: rad/s (jaw m/s).
        oldest_answer_s: Arrival of the oldest answer it holds (s of the bridge's clock): the
            stamp it deserves, as the protocol has no device clock.
    """

    names: list[str]
    positions: list[float]
    velocities: list[float]
    oldest_answer_s: float
