"""A pilot's demand (-1 to 1 per input axis) scaled by the speed gear and the pilot limits.

Every input tool (keys, gamepad) produces a ``Demand``: one number in [-1, 1] per input axis,
the fraction of the robot's pilot limit asked for. ``command`` scales it by the speed gear and
the limits into SI velocities in the frames of the pilot topics (docs/piloting.md):

- vehicle body velocity in base_link_frd (x forward, y right, z down): surge u (m/s), sway v
  (m/s), heave w (m/s, + down) and yaw rate r (rad/s, + turning right seen from above);
- end-effector velocity (m/s) in the frame the pilot chose (the vehicle body or map_ned);
- jaw opening velocity (m/s, + opens).

Example::

    >>> limits = PilotLimits(vehicle_m_s=(0.4, 0.4, 0.3), yaw_rad_s=0.5,
    ...                      ee_m_s=(0.05, 0.05, 0.05), jaw_m_s=0.01)
    >>> cmd = command(Demand(surge=1.0, yaw=-0.5), limits, gear=0.5)
    >>> cmd.vehicle_twist
    (0.2, 0.0, 0.0, 0.0, 0.0, -0.125)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

#: Input axes of a demand, in this order everywhere (keys, gamepad mapping, tests).
INPUT_AXES = ('surge', 'sway', 'heave', 'yaw', 'arm_x', 'arm_y', 'arm_z', 'jaw')
#: Speed gears: fractions of the pilot limits. A session starts in the first (the slowest).
GEARS = (0.25, 0.5, 1.0)


@dataclass(frozen=True)
class PilotLimits:
    """The robot's pilot limits: the demand 1.0 at gear 1.0 on each axis (0: axis held).

    Attributes:
        vehicle_m_s: Surge, sway and heave speed limits (m/s), each >= 0.
        yaw_rad_s: Yaw rate limit (rad/s), >= 0.
        ee_m_s: End-effector speed limits per axis of the pilot's frame (m/s), each >= 0.
        jaw_m_s: Jaw opening speed limit (m/s), >= 0.
    """

    vehicle_m_s: tuple[float, float, float]
    yaw_rad_s: float
    ee_m_s: tuple[float, float, float]
    jaw_m_s: float

    def __post_init__(self) -> None:
        values = {'vehicle_m_s': self.vehicle_m_s, 'yaw_rad_s': (self.yaw_rad_s,),
                  'ee_m_s': self.ee_m_s, 'jaw_m_s': (self.jaw_m_s,)}
        for name, entries in values.items():
            size = 3 if name in ('vehicle_m_s', 'ee_m_s') else 1
            if len(entries) != size or not all(math.isfinite(v) and v >= 0.0 for v in entries):
                msg = f'pilot limit {name}: expected {size} finite value(s) >= 0, got {entries}'
                raise ValueError(msg)


@dataclass(frozen=True)
class Demand:
    """Fractions of the pilot limits asked for, each in [-1, 1] (``clipped`` makes it so)."""

    surge: float = 0.0
    sway: float = 0.0
    heave: float = 0.0
    yaw: float = 0.0
    arm_x: float = 0.0
    arm_y: float = 0.0
    arm_z: float = 0.0
    jaw: float = 0.0

    @classmethod
    def from_values(cls, values: dict[str, float]) -> Demand:
        """A demand from ``{axis: value}``, clipped; absent axes are 0."""
        unknown = set(values) - set(INPUT_AXES)
        if unknown:
            msg = f'unknown input axes {sorted(unknown)}; known: {", ".join(INPUT_AXES)}'
            raise ValueError(msg)
        return cls(**{axis: clip_unit(value) for axis, value in values.items()})

    def as_tuple(self) -> tuple[float, ...]:
        """The values in ``INPUT_AXES`` order."""
        return tuple(getattr(self, f.name) for f in fields(self))

    @property
    def vehicle_is_zero(self) -> bool:
        """No vehicle motion asked for."""
        return self.surge == self.sway == self.heave == self.yaw == 0.0

    @property
    def arm_is_zero(self) -> bool:
        """No end-effector motion asked for."""
        return self.arm_x == self.arm_y == self.arm_z == 0.0


@dataclass(frozen=True)
class PilotCommand:
    """Velocities for the pilot topics, SI units.

    Attributes:
        vehicle_twist: (u, v, w, p, q, r) in base_link_frd (m/s, rad/s); p and q always 0.
        ee_velocity_m_s: End-effector velocity (m/s) in the pilot's chosen frame.
        jaw_m_s: Jaw opening velocity (m/s, + opens).
    """

    vehicle_twist: tuple[float, float, float, float, float, float]
    ee_velocity_m_s: tuple[float, float, float]
    jaw_m_s: float


def clip_unit(value: float) -> float:
    """``value`` clipped to [-1, 1]; NaN (a device glitch) is 0, never a jump."""
    if math.isnan(value):
        return 0.0
    return max(-1.0, min(1.0, float(value)))


def command(demand: Demand, limits: PilotLimits, gear: float) -> PilotCommand:
    """Scale a demand by the gear (a fraction in (0, 1]) and the limits.

    Raises:
        ValueError: A gear outside (0, 1].
    """
    if not 0.0 < gear <= 1.0:
        msg = f'speed gear: expected a fraction in (0, 1], got {gear}'
        raise ValueError(msg)
    d = Demand.from_values({axis: getattr(demand, axis) for axis in INPUT_AXES})
    u_max, v_max, w_max = limits.vehicle_m_s
    return PilotCommand(
        vehicle_twist=(gear * u_max * d.surge, gear * v_max * d.sway, gear * w_max * d.heave,
                       0.0, 0.0, gear * limits.yaw_rad_s * d.yaw),
        ee_velocity_m_s=(gear * limits.ee_m_s[0] * d.arm_x, gear * limits.ee_m_s[1] * d.arm_y,
                         gear * limits.ee_m_s[2] * d.arm_z),
        jaw_m_s=gear * limits.jaw_m_s * d.jaw,
    )


def gear_after(index: int, action: str) -> int:
    """The gear index (into ``GEARS``) after a gear action; other actions leave it.

    ``gear_1``..``gear_3`` select a gear, ``gear_up`` and ``gear_down`` step within GEARS.
    """
    if action.startswith('gear_') and action[5:].isdigit():
        return max(0, min(len(GEARS) - 1, int(action[5:]) - 1))
    step = {'gear_up': 1, 'gear_down': -1}.get(action, 0)
    return max(0, min(len(GEARS) - 1, index + step))


class PublishGate:
    """Which topics to publish this tick: a moving part always, a part just stopped once.

    A part (vehicle, arm, jaw) that moves is published at every tick; the tick it stops, one
    zero is published, then nothing: the controller's deadman (0.3 s without a message) then
    holds the pose, which a stream of zeros would prevent.
    """

    PARTS = ('vehicle', 'arm', 'jaw')

    def __init__(self) -> None:
        self._moving = dict.fromkeys(self.PARTS, False)

    def parts_to_publish(self, demand: Demand) -> tuple[str, ...]:
        """The parts to publish for this demand, in ``PARTS`` order."""
        moving = {'vehicle': not demand.vehicle_is_zero, 'arm': not demand.arm_is_zero,
                  'jaw': demand.jaw != 0.0}
        out = tuple(part for part in self.PARTS if moving[part] or self._moving[part])
        self._moving = moving
        return out

    def stop_all(self) -> tuple[str, ...]:
        """Every part, to publish one zero each now (the stop key); then all are still.

        Zeros neither take control nor cancel a running task (docs/piloting.md, "Modes and
        hand-over"): they stop what the pilot drives; c or h end a task.
        """
        self._moving = dict.fromkeys(self.PARTS, False)
        return self.PARTS
