"""What the Alpha 5's devices reported, as the bridge's core keeps it and hands it out.

``DeviceFeedback`` is one device's last answers with their arrival times; ``JointSample`` one
joint state made of fresh answers only (``alpha5_core.Alpha5Core.next_joint_state``);
``SampleAges`` how old the answers in the last samples were when they were given. The
protocol has no device clock, so an arrival time on the bridge's clock is the only stamp.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

__all__ = ['DeviceFeedback', 'JointSample', 'SampleAges']

#: Samples whose ages `SampleAges` keeps (at 77 Hz, the last 13 s).
KEPT_SAMPLES = 1024


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


@dataclass
class SampleAges:
    """Ages of the answers in the last `KEPT_SAMPLES` joint states, when each was given.

    A polled bus answers the joints one after another, so one joint state holds answers of
    different ages: its oldest (the stamp it gets) and its newest. What the controller gets is
    as old as these plus the way from the bridge to it (docs/hardware.md, "The Alpha 5 bus").
    """

    oldest_s: deque[float] = field(default_factory=lambda: deque(maxlen=KEPT_SAMPLES))
    newest_s: deque[float] = field(default_factory=lambda: deque(maxlen=KEPT_SAMPLES))
    given: int = 0

    def add(self, t_s: float, answers_s: list[float]) -> None:
        """A joint state given at ``t_s`` of answers that arrived at ``answers_s``."""
        self.oldest_s.append(t_s - min(answers_s))
        self.newest_s.append(t_s - max(answers_s))
        self.given += 1

    def figures_ms(self) -> dict[str, float]:
        """Median and 95th percentile of the oldest and newest answer's age (ms)."""
        out: dict[str, float] = {}
        for name, ages in (('oldest', self.oldest_s), ('newest', self.newest_s)):
            ordered = sorted(ages)
            for label, share in (('p50', 0.5), ('p95', 0.95)):
                at = ordered[min(len(ordered) - 1, int(share * len(ordered)))] if ordered \
                    else math.nan
                out[f'joint_state_age_{name}_ms_{label}'] = round(at * 1e3, 2)
        return out

    def line(self) -> str:
        """One line for the bridge's stop: how many joint states, how old their answers."""
        if not self.given:
            return 'joint states: none given'
        f = self.figures_ms()
        return (f'joint states: {self.given} given; answers in them at giving: the oldest '
                f'{f["joint_state_age_oldest_ms_p50"]} ms (p50), '
                f'{f["joint_state_age_oldest_ms_p95"]} ms (p95), the newest '
                f'{f["joint_state_age_newest_ms_p50"]} ms (p50), '
                f'{f["joint_state_age_newest_ms_p95"]} ms (p95)')
