"""What the markers of the 3-D view show, as numpy geometry in map_ned (no rclpy, no messages).

The visualizer node turns a ``MarkerScene`` into a visualization_msgs/MarkerArray
(``uvms_viz.conversions``); this module decides what is drawn and where:

- the wall: a thin slab whose face is the plane x = ``wall_position`` of /uvms/contact
  (it moves in Case III), drawn over ``wall_size_m`` around ``wall_center_yz_m``;
- the contact force the end effector exerts on the wall, an arrow from the end effector,
  ``force_scale_m_per_n`` metres per newton;
- the reference X_d of /uvms/controller/state, a sphere;
- the end effector's trail, the last ``trail_length`` positions X at the marker rate.

All positions are metres in ``map_ned`` (x north, y east, z down).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np
from numpy.typing import NDArray

T = TypeVar('T')

FloatArray = NDArray[np.float64]

#: Thickness of the drawn wall slab behind its face (m); the face is the contact plane.
WALL_THICKNESS_M = 0.02


class MarkerGeometryError(ValueError):
    """A marker setting is out of range; the message names it and its value."""


@dataclass(frozen=True)
class MarkerSettings:
    """How the markers are drawn.

    Attributes:
        force_scale_m_per_n: Arrow length per newton of contact force (m/N).
        trail_length: Most end-effector positions kept in the trail.
        wall_size_m: Drawn extent of the wall along map_ned y and z (m).
        wall_center_yz_m: Centre of the drawn wall on its plane, map_ned y and z (m).
    """

    force_scale_m_per_n: float = 0.02
    trail_length: int = 400
    wall_size_m: tuple[float, float] = (2.0, 2.0)
    wall_center_yz_m: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        """Check every setting.

        Raises:
            MarkerGeometryError: A setting is out of range, named with its value.
        """
        if not (math.isfinite(self.force_scale_m_per_n) and self.force_scale_m_per_n > 0.0):
            msg = f'force_scale_m_per_n must be finite and > 0, got {self.force_scale_m_per_n!r}'
            raise MarkerGeometryError(msg)
        if self.trail_length < 2:
            msg = f'trail_length must be >= 2 points, got {self.trail_length!r}'
            raise MarkerGeometryError(msg)
        if len(self.wall_size_m) != 2 or not all(
                math.isfinite(s) and s > 0.0 for s in self.wall_size_m):
            msg = f'wall_size_m must be two finite sizes > 0 (m), got {self.wall_size_m!r}'
            raise MarkerGeometryError(msg)
        if len(self.wall_center_yz_m) != 2 or not all(
                math.isfinite(c) for c in self.wall_center_yz_m):
            msg = f'wall_center_yz_m must be two finite values (m), got {self.wall_center_yz_m!r}'
            raise MarkerGeometryError(msg)


@dataclass(frozen=True)
class Box:
    """An axis-aligned box in map_ned: centre and full size along x, y, z (m)."""

    center: FloatArray
    size: FloatArray


@dataclass(frozen=True)
class MarkerScene:
    """Everything the markers draw at one instant, in map_ned (m).

    Attributes:
        wall: The wall slab, or None when there is no wall (free motion).
        force_tail: Start of the contact force arrow, the end-effector position.
        force_tip: End of the arrow: ``force_tail + force_scale_m_per_n * F``.
        reference: The reference position X_d.
        trail: The end-effector positions of the trail, oldest first, shape (n, 3).
    """

    wall: Box | None
    force_tail: FloatArray
    force_tip: FloatArray
    reference: FloatArray
    trail: FloatArray


def wall_box(wall_position_m: float, settings: MarkerSettings) -> Box | None:
    """The drawn wall: its face on the plane x = wall_position_m, the slab beyond it.

    Returns:
        The box, or None when ``wall_position_m`` is not finite (no wall in the run).
    """
    if not math.isfinite(wall_position_m):
        return None
    width_y, height_z = settings.wall_size_m
    center = np.array([wall_position_m + 0.5 * WALL_THICKNESS_M, *settings.wall_center_yz_m])
    return Box(center=center, size=np.array([WALL_THICKNESS_M, width_y, height_z]))


class Trail:
    """The last positions of the end effector, at most ``length`` of them."""

    def __init__(self, length: int) -> None:
        self._points: deque[tuple[float, float, float]] = deque(maxlen=length)

    def append(self, p_ned: Sequence[float] | FloatArray) -> None:
        """Add one position (m, map_ned)."""
        self._points.append((float(p_ned[0]), float(p_ned[1]), float(p_ned[2])))

    def points(self) -> FloatArray:
        """The positions, oldest first, shape (n, 3)."""
        return np.array(self._points, dtype=float).reshape(-1, 3)

    def __len__(self) -> int:
        return len(self._points)


class ContactHistory(Generic[T]):
    """The contacts of the last few stamps (any payload, e.g. serialized), looked up by stamp.

    The markers of a controller state stamped t use the contact stamped t when it has
    arrived, so that their content does not depend on which of the two topics arrived
    first (lockstep across processes); otherwise the newest contact before t (timer mode,
    where the stamps differ), else the oldest kept, else none.
    """

    def __init__(self, capacity: int = 64) -> None:
        self._by_stamp: dict[int, T] = {}
        self._capacity = capacity

    def add(self, stamp_ns: int, contact: T) -> None:
        """Keep the contact of one stamp, dropping the oldest beyond the capacity."""
        self._by_stamp[stamp_ns] = contact
        while len(self._by_stamp) > self._capacity:
            del self._by_stamp[min(self._by_stamp)]

    def at(self, stamp_ns: int) -> T | None:
        """The contact for a stamp, as the class docstring says; None if none was kept."""
        if stamp_ns in self._by_stamp:
            return self._by_stamp[stamp_ns]
        before = [stamp for stamp in self._by_stamp if stamp <= stamp_ns]
        if before:
            return self._by_stamp[max(before)]
        if self._by_stamp:
            return self._by_stamp[min(self._by_stamp)]
        return None


def marker_scene(
    p_ee_ned: Sequence[float] | FloatArray,
    p_ref_ned: Sequence[float] | FloatArray,
    contact_force_ned: Sequence[float] | FloatArray,
    wall_position_m: float,
    trail: Trail,
    settings: MarkerSettings,
) -> MarkerScene:
    """The scene of one marker instant.

    Args:
        p_ee_ned: End-effector position X (m).
        p_ref_ned: Reference position X_d (m).
        contact_force_ned: Force the end effector exerts on the wall (N), map_ned.
        wall_position_m: Wall face position along map_ned x (m); NaN when there is no wall.
        trail: The trail, already holding ``p_ee_ned`` if it is to be drawn.
        settings: How to draw.
    """
    tail = np.asarray(p_ee_ned, dtype=float).reshape(3)
    force = np.asarray(contact_force_ned, dtype=float).reshape(3)
    return MarkerScene(
        wall=wall_box(wall_position_m, settings),
        force_tail=tail,
        force_tip=tail + settings.force_scale_m_per_n * force,
        reference=np.asarray(p_ref_ned, dtype=float).reshape(3),
        trail=trail.points(),
    )
