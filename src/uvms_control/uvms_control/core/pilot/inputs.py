"""Pilot messages checked and bounded: finite, a known frame, a fresh stamp, within the limits.

Each refusal has a kind (``Refusal``); ``RefusalLog`` says which ones are new, so the node
names each kind once per topic on the console and counts all of them on /diagnostics.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

#: The vehicle body frame; an empty frame_id means it too.
BODY_FRAMES = ('base_link_frd', '')
#: The frames an end-effector velocity may come in: the body's, or the map's.
EE_FRAMES = (*BODY_FRAMES, 'map_ned')

Vector3 = tuple[float, float, float]


class Refusal(enum.Enum):
    """Why a pilot message was refused."""

    NOT_FINITE = 'not finite'
    UNKNOWN_FRAME = 'unknown frame'
    STALE = 'stale stamp'
    FUTURE = 'stamp in the future'
    CLIPPED = 'beyond the pilot limits (scaled down)'
    INACTIVE = 'controller not active'


class PilotInputError(ValueError):
    """A pilot message refused; ``kind`` says why, the message names the value."""

    def __init__(self, kind: Refusal, message: str) -> None:
        super().__init__(message)
        self.kind = kind


@dataclass(frozen=True)
class PilotTwist:
    """A checked, bounded pilot velocity.

    Attributes:
        linear: m/s, in base_link_frd (``in_body``) or map_ned.
        angular: rad/s, base_link_frd (vehicle twists only; zeros for the end effector).
        in_body: the frame is the vehicle body's.
        clipped: the message was beyond the limits and was scaled down.
    """

    linear: Vector3
    angular: Vector3 = (0.0, 0.0, 0.0)
    in_body: bool = True
    clipped: bool = False

    @property
    def is_zero(self) -> bool:
        """Every component is zero (a stop, not a take-over)."""
        return not any(self.linear) and not any(self.angular)


def scaled_within(vector: Sequence[float], limits: Sequence[float]) -> tuple[Vector3, bool]:
    """The vector scaled down whole until each component is within its limit; and whether it was.

    A component whose limit is 0 is zeroed first (an axis the pilot may not move); the rest
    keeps its direction, so a huge value gives full speed the way it points, never a jump
    sideways.

    Example:
        >>> scaled_within([2.0, 1.0, 5.0], [0.5, 0.5, 0.0])
        ((0.5, 0.25, 0.0), True)
    """
    v = [0.0 if limit == 0.0 else float(x) for x, limit in zip(vector, limits, strict=True)]
    scale = min((limit / abs(x) for x, limit in zip(v, limits, strict=True) if x != 0.0),
                default=1.0)
    changed = any(float(x) != y for x, y in zip(vector, v, strict=True)) or scale < 1.0
    if scale < 1.0:
        v = [x * scale for x in v]
    return (v[0], v[1], v[2]), changed


def check_stamp(topic: str, stamp_s: float, now_s: float, deadman_s: float) -> None:
    """Refuse a stamp older than the deadman or further ahead than it (sender on another clock).

    Raises:
        PilotInputError: STALE or FUTURE, naming the stamp and the controller's time.
    """
    if stamp_s < now_s - deadman_s:
        raise PilotInputError(Refusal.STALE, (
            f'{topic}: stamp {stamp_s:.3f} s is {now_s - stamp_s:.3f} s older than the '
            f'controller clock ({now_s:.3f} s), more than the deadman {deadman_s:g} s'
            + (" (an unset stamp: stamp it with the sender's now)" if stamp_s == 0.0 else '')))
    if stamp_s > now_s + deadman_s:
        raise PilotInputError(Refusal.FUTURE, (
            f'{topic}: stamp {stamp_s:.3f} s is {stamp_s - now_s:.3f} s ahead of the '
            f'controller clock ({now_s:.3f} s): is the sender on the same clock (use_sim_time)?'))


def check_finite(topic: str, values: Sequence[float]) -> None:
    """Raises PilotInputError(NOT_FINITE) naming the values when one is NaN or infinite."""
    if not all(math.isfinite(v) for v in values):
        raise PilotInputError(Refusal.NOT_FINITE,
                              f'{topic}: values must be finite, got {list(values)}')


def vehicle_twist(topic: str, linear: Sequence[float], angular: Sequence[float], frame_id: str,
                  speed_m_s: Sequence[float], rate_rad_s: Sequence[float]) -> PilotTwist:
    """A vehicle body twist checked and scaled within the limits.

    Raises:
        PilotInputError: NOT_FINITE or UNKNOWN_FRAME.
    """
    check_finite(topic, [*linear, *angular])
    if frame_id not in BODY_FRAMES:
        raise PilotInputError(Refusal.UNKNOWN_FRAME, (
            f'{topic}: frame {frame_id!r} refused: a vehicle twist is in {BODY_FRAMES[0]!r} '
            '(or empty)'))
    v, clipped_v = scaled_within(linear, speed_m_s)
    w, clipped_w = scaled_within(angular, rate_rad_s)
    return PilotTwist(v, w, True, clipped_v or clipped_w)


def ee_twist(topic: str, linear: Sequence[float], angular: Sequence[float], frame_id: str,
             speed_m_s: Sequence[float]) -> PilotTwist:
    """An end-effector velocity checked and scaled within the limits (position only).

    The controller's task is the end effector's position: an angular part is ignored (it
    counts as clipped, so it is named once).

    Raises:
        PilotInputError: NOT_FINITE or UNKNOWN_FRAME.
    """
    check_finite(topic, [*linear, *angular])
    if frame_id not in EE_FRAMES:
        raise PilotInputError(Refusal.UNKNOWN_FRAME, (
            f'{topic}: frame {frame_id!r} refused: an end-effector twist is in '
            f'{EE_FRAMES[0]!r} (or empty) or {EE_FRAMES[2]!r}'))
    v, clipped = scaled_within(linear, speed_m_s)
    return PilotTwist(v, (0.0, 0.0, 0.0), frame_id in BODY_FRAMES, clipped or any(angular))


def jaw_speed(topic: str, speed_m_s: float, limit_m_s: float) -> tuple[float, bool]:
    """A jaw speed (m/s, + opens) within the limit, and whether it was clipped.

    Raises:
        PilotInputError: NOT_FINITE.
    """
    check_finite(topic, [speed_m_s])
    bounded = max(-limit_m_s, min(limit_m_s, speed_m_s))
    return bounded, bounded != speed_m_s


@dataclass
class RefusalLog:
    """Which refusals were named already (once per kind and topic) and how many there were."""

    named: set[tuple[str, Refusal]] = field(default_factory=set)
    counts: dict[Refusal, int] = field(default_factory=dict)

    def first(self, topic: str, kind: Refusal) -> bool:
        """Count one refusal; True the first time this kind comes on this topic."""
        self.counts[kind] = self.counts.get(kind, 0) + 1
        if (topic, kind) in self.named:
            return False
        self.named.add((topic, kind))
        return True

    def summary(self) -> str:
        """The counts in one line for /diagnostics ('' when none)."""
        return ', '.join(f'{kind.value}: {count}' for kind, count in self.counts.items())
