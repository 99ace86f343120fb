"""Device timing in the simulator: sensors sampled at their rate and delivered late, commands held.

A robot folder's ``device_timing.yaml`` (docs/robots.md, "Device timing") gives, per device
and signal, the rate at which it is sampled, the latency from the sample to its delivery and
that latency's jitter, and the rate at which the devices apply commands. The simulator keeps
it by default (``devices.ideal`` false):

- ``SampleHold``: a sensor signal sampled at its rate on the state grid (the first published
  state at or after each sample instant), delivered at the first state at or after the
  sample's time plus its latency (jittered uniformly in +-jitter by a generator of its own,
  so lockstep runs stay deterministic and the sensor noise draws are untouched), and held in
  between: every state publishes the newest delivered sample, stamped with the state's time
  as the lockstep exchange needs.
- ``StaggeredHold``: the arm's joints as a polled bus gives them (``devices.joint_states.
  staggered``): one joint at a time, evenly over each 1/rate round, the round delivered its
  latency after its last joint, so a joint_states message holds positions of different ages
  (the Alpha 5 bridge publishes one once every joint answered afresh).
- ``CommandHold``: a command latched at the device's own rate (ArduSub's 50 Hz RC loop, the
  arm bus's command slots) and held between latches.

A rate of 0 means with every state (sensors) or every plant step (commands), and a latency of
0 none: a robot that declares no device timing, or ``devices.ideal`` true, keeps the
idealized graph exactly (nothing is sampled, drawn or held). Pure Python: no rclpy.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np

from uvms_sim.errors import SimParameterError

T = TypeVar('T')

SENSORS = ('joint_states', 'wrench', 'imu', 'dvl', 'depth')
"""Sensor signals whose timing a robot may declare (``devices.<signal>.*``)."""
HELD_SENSORS = ('joint_states', 'wrench')
"""Sensors sampled and held on the state grid (imu, dvl, depth keep navigation's rates)."""
COMMANDS = ('thrusts', 'arm_commands')
"""Command signals latched at the devices' own rate (``devices.<signal>.rate_hz``)."""


@dataclass(frozen=True)
class SignalTiming:
    """Timing of one signal.

    Attributes:
        rate_hz: Samples (sensors) or applications (commands) per second; 0: every state
            (sensors) or every plant step (commands).
        latency_s: From a sample to its delivery (s); 0 none.
        jitter_s: Half width of the uniform spread of the latency (s), at most the latency.
        staggered: Joint states only: the joints sampled one at a time over each round
            (``StaggeredHold``), not all at each sample; meaningless at rate 0.
        frame_s: Arm commands only: joint j's torque acts j frames after the first's (a
            bus sends a slot's frames in turn).
    """

    rate_hz: float = 0.0
    latency_s: float = 0.0
    jitter_s: float = 0.0
    staggered: bool = False
    frame_s: float = 0.0

    @property
    def ideal(self) -> bool:
        """True when the signal is neither sampled below the state rate nor delayed."""
        return self.rate_hz == 0.0 and self.latency_s == 0.0

    @property
    def period_ns(self) -> int:
        """Nanoseconds between samples (0 for every state)."""
        return round(1e9 / self.rate_hz) if self.rate_hz > 0.0 else 0


@dataclass(frozen=True)
class DeviceTiming:
    """The device timing the simulator applies.

    Attributes:
        signals: Timing per name of ``SENSORS`` and ``COMMANDS``.
        seed: Seed of the latency jitter draws (the scenario's sensor seed).
    """

    signals: Mapping[str, SignalTiming]
    seed: int = 0

    @property
    def ideal(self) -> bool:
        """True when no signal is sampled, delayed or held."""
        return all(timing.ideal for timing in self.signals.values())

    def __getitem__(self, name: str) -> SignalTiming:
        return self.signals.get(name, SignalTiming())

    @classmethod
    def from_values(cls, values: Mapping[str, Any], seed: int = 0) -> DeviceTiming:
        """Device timing of the simulator's ``devices.*`` parameter values.

        ``devices.ideal`` true gives every signal the ideal timing.

        Raises:
            SimParameterError: A jitter above its latency, or a command latency not below
                one slot of its rate, naming the parameter.
        """
        if values['devices.ideal']:
            return cls({name: SignalTiming() for name in (*SENSORS, *COMMANDS)}, seed)
        signals: dict[str, SignalTiming] = {}
        for name in (*SENSORS, *COMMANDS):
            rate = float(values.get(f'devices.{name}.rate_hz', 0.0))
            latency = float(values.get(f'devices.{name}.latency_s', 0.0))
            jitter = float(values.get(f'devices.{name}.jitter_s', 0.0))
            if jitter > latency:
                msg = (f"parameter 'devices.{name}.jitter_s' = {jitter:g}: above "
                       f'devices.{name}.latency_s = {latency:g} (a delivery before its sample)')
                raise SimParameterError(msg)
            if name in COMMANDS and latency > 0.0 and not latency * rate < 1.0:
                raise SimParameterError(late_command_message(name, latency, rate))
            frame = float(values.get(f'devices.{name}.frame_s', 0.0))
            staggered = bool(values.get(f'devices.{name}.staggered', False))
            signals[name] = SignalTiming(rate, latency, jitter, staggered, frame)
        return cls(signals, seed)

    def summary(self) -> str:
        """One line for the start-up log: what is not ideal."""
        if self.ideal:
            return 'ideal devices'
        parts = []
        for name, timing in self.signals.items():
            if timing.ideal:
                continue
            rate = f'{timing.rate_hz:g} Hz' if timing.rate_hz > 0.0 else 'every state'
            late = (f' +{timing.latency_s * 1e3:g} ms' if timing.latency_s > 0.0 else '')
            late += (f' +{timing.frame_s * 1e3:g} ms a joint' if timing.frame_s > 0.0 else '')
            one_at_a_time = ' one joint at a time' if timing.staggered else ''
            parts.append(f'{name} {rate}{late}{one_at_a_time}')
        return 'device timing: ' + ', '.join(parts)


class LatencyDraws:
    """A signal's latencies (ns): its latency, jittered uniformly by a generator of its own."""

    def __init__(self, timing: SignalTiming, seed: int = 0) -> None:
        self._latency_ns = round(timing.latency_s * 1e9)
        self._jitter_ns = round(timing.jitter_s * 1e9)
        self._rng = np.random.default_rng(seed) if self._jitter_ns > 0 else None

    def __call__(self) -> int:
        """The next sample's latency (ns)."""
        if self._rng is None:
            return self._latency_ns
        return self._latency_ns + round(float(self._rng.uniform(-1.0, 1.0)) * self._jitter_ns)


class SampleHold(Generic[T]):
    """One sensor signal sampled at its rate, delivered after its latency, held in between.

    Args:
        timing: The signal's timing.
        seed: Seed of the latency jitter draws.

    >>> hold = SampleHold(SignalTiming(rate_hz=250.0, latency_s=0.003))
    >>> [hold.at(t_ms * 1_000_000, lambda t=t_ms: t) for t_ms in range(0, 14, 2)]
    [0, 0, 0, 0, 4, 4, 8]
    """

    def __init__(self, timing: SignalTiming, seed: int = 0) -> None:
        self._period_ns = timing.period_ns
        self._latency = LatencyDraws(timing, seed)
        self._next_sample_ns: int | None = None
        self._samples = 0
        self._pending: deque[tuple[int, int, T]] = deque()
        self._held: tuple[int, T] | None = None

    def at(self, t_ns: int, sample: Callable[[], T]) -> T:
        """The value delivered at state time ``t_ns``; ``sample()`` reads the signal now.

        ``sample`` is called only when a sample is due. Before the first delivery the first
        sample is delivered at once (the device's value at start-up, as a bridge's first
        reading).
        """
        if self._next_sample_ns is None or t_ns >= self._next_sample_ns:
            value = sample()
            self._pending.append((t_ns + self._latency(), t_ns, value))
            self._samples += 1
            if self._period_ns > 0:
                start = self._next_sample_ns if self._next_sample_ns is not None else t_ns
                self._next_sample_ns = start + self._period_ns
                while self._next_sample_ns <= t_ns:
                    self._next_sample_ns += self._period_ns
            else:
                self._next_sample_ns = t_ns + 1
        while self._pending and self._pending[0][0] <= t_ns:
            _, sampled_ns, value = self._pending.popleft()
            if self._held is None or sampled_ns >= self._held[0]:
                self._held = (sampled_ns, value)
        if self._held is None:  # start-up: the first sample at once
            _, sampled_ns, value = self._pending.popleft()
            self._held = (sampled_ns, value)
        return self._held[1]

    @property
    def sampled_ns(self) -> int | None:
        """Time of the held sample (ns), None before the first."""
        return None if self._held is None else self._held[0]


class StaggeredHold:
    """The arm's joints as a polled bus gives them: one at a time, each round delivered whole.

    Joint j of a round is sampled at the first state at or after ``start + j * period / n``
    (its device answered then); the round, each joint at its own instant, is delivered at the
    first state at or after its last joint's sample plus the latency (jittered as
    ``SampleHold``'s), and held until the next round is. Before the first delivery the
    joints as sampled at the first state (the bridge's first reading).

    Args:
        timing: The joint states' timing (rate above 0).
        n_joints: Number of arm joints.
        seed: Seed of the latency jitter draws.

    >>> hold = StaggeredHold(SignalTiming(rate_hz=100.0), 2)
    >>> [hold.at(t * 1_000_000, [t, t], [0, 0], [0, 0])[0] for t in range(0, 18, 2)]
    [[0, 0], [0, 0], [0, 0], [0, 6], [0, 6], [0, 6], [0, 6], [0, 6], [10, 16]]
    """

    def __init__(self, timing: SignalTiming, n_joints: int, seed: int = 0) -> None:
        self._period_ns = timing.period_ns
        self._n = n_joints
        self._latency = LatencyDraws(timing, seed)
        self._round_start_ns: int | None = None
        self._next = 0  # the joint asked next
        self._round: list[list[float]] = [[0.0] * n_joints for _ in range(3)]
        self._pending: deque[tuple[int, list[list[float]]]] = deque()
        self._held: list[list[float]] | None = None

    def at(self, t_ns: int, q: list[float], w: list[float],
           tau: list[float]) -> list[list[float]]:
        """[positions, velocities, efforts] of the joints as delivered at state time t_ns.

        ``q``, ``w`` and ``tau`` are the joints' values now (n each).
        """
        if self._round_start_ns is None:
            self._round_start_ns = t_ns
            self._held = [list(q), list(w), list(tau)]
        while self._next < self._n and t_ns >= self._due_ns(self._next):
            j = self._next
            self._round[0][j], self._round[1][j], self._round[2][j] = q[j], w[j], tau[j]
            self._next += 1
            if self._next == self._n:  # the round's last answer: on its way
                self._pending.append((t_ns + self._latency(),
                                      [list(values) for values in self._round]))
                self._next = 0
                self._round_start_ns += self._period_ns
        while self._pending and self._pending[0][0] <= t_ns:
            self._held = self._pending.popleft()[1]
        assert self._held is not None
        return self._held

    def _due_ns(self, joint: int) -> int:
        assert self._round_start_ns is not None
        return self._round_start_ns + (joint * self._period_ns) // self._n


def late_command_message(name: str, latency_s: float, rate_hz: float) -> str:
    """Why a command latency (its last joint's, with ``frame_s``) of a slot or more is refused."""
    return (f"parameter 'devices.{name}.latency_s' = {latency_s:g} (its last joint's, with "
            f'frame_s): not below one slot of devices.{name}.rate_hz = {rate_hz:g} (a '
            'command would be lost)')


class CommandHold(Generic[T]):
    """A command applied at the device's own rate: latched at each slot, held in between.

    Args:
        rate_hz: Applications per second; 0 applies every command at once.
        latency_s: From a slot's latch to the command acting (s), below one slot: the slot's
            frames still on the line. The first command acts at once.
        frame_s: Element j of a command (a sequence) acts j x ``frame_s`` after element 0 (a
            bus sends the joints' frames in turn); 0: all together.

    >>> hold = CommandHold(50.0)
    >>> [hold.at(t_ms * 1_000_000, t_ms) for t_ms in (0, 1, 19, 20, 21, 39, 40)]
    [0, 0, 0, 20, 20, 20, 40]
    >>> late = CommandHold(50.0, 0.005)
    >>> [late.at(t_ms * 1_000_000, t_ms) for t_ms in (0, 1, 20, 24, 25, 40, 45)]
    [0, 0, 0, 0, 20, 20, 40]
    >>> turns = CommandHold(50.0, 0.001, 0.002)
    >>> [turns.at(t_ms * 1_000_000, [t_ms] * 3) for t_ms in (0, 20, 21, 23, 25)]
    [[0, 0, 0], [0, 0, 0], [20, 0, 0], [20, 20, 0], [20, 20, 20]]
    """

    def __init__(self, rate_hz: float, latency_s: float = 0.0, frame_s: float = 0.0) -> None:
        self._period_ns = round(1e9 / rate_hz) if rate_hz > 0.0 else 0
        self._latency_ns = round(latency_s * 1e9)
        self._frame_ns = round(frame_s * 1e9)
        self._next_ns: int | None = None
        self._latched: T | None = None
        self._due_ns = 0
        self._held: T | None = None

    def at(self, t_ns: int, command: T) -> T:
        """The command the device applies at plant time ``t_ns`` given the latest ``command``."""
        if self._period_ns == 0:
            return command
        if self._next_ns is None or t_ns >= self._next_ns:
            self._latched, self._due_ns = command, t_ns + self._latency_ns
            self._next_ns = (t_ns // self._period_ns + 1) * self._period_ns
        if self._latched is not None:
            if self._held is None or (t_ns >= self._due_ns and self._frame_ns == 0):
                self._held, self._latched = self._latched, None
            elif self._frame_ns > 0 and t_ns >= self._due_ns:
                arrived = (t_ns - self._due_ns) // self._frame_ns + 1
                self._held = first_elements_of(self._latched, self._held, arrived)
                if arrived >= len(self._held):  # type: ignore[arg-type]
                    self._latched = None
        assert self._held is not None
        return self._held


def first_elements_of(new: T, old: T, count: int) -> T:
    """``old`` with its first ``count`` elements from ``new`` (a list or a numpy array).

    >>> first_elements_of([1, 2, 3], [0, 0, 0], 2)
    [1, 2, 0]
    """
    mixed = list(new)[:count] + list(old)[count:]  # type: ignore[call-overload]
    return np.array(mixed) if isinstance(new, np.ndarray) else mixed  # type: ignore[return-value]
