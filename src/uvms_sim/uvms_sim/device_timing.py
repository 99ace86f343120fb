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
    """

    rate_hz: float = 0.0
    latency_s: float = 0.0
    jitter_s: float = 0.0

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
            SimParameterError: A jitter above its latency, or a command latency (commands
                have only a rate), naming the parameter.
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
            signals[name] = SignalTiming(rate, latency, jitter)
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
            parts.append(f'{name} {rate}{late}')
        return 'device timing: ' + ', '.join(parts)


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
        self._latency_ns = round(timing.latency_s * 1e9)
        self._jitter_ns = round(timing.jitter_s * 1e9)
        self._rng = np.random.default_rng(seed) if self._jitter_ns > 0 else None
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

    def _latency(self) -> int:
        if self._rng is None:
            return self._latency_ns
        return self._latency_ns + round(float(self._rng.uniform(-1.0, 1.0)) * self._jitter_ns)


class CommandHold(Generic[T]):
    """A command applied at the device's own rate: latched at each slot, held in between.

    Args:
        rate_hz: Applications per second; 0 applies every command at once.

    >>> hold = CommandHold(50.0)
    >>> [hold.at(t_ms * 1_000_000, t_ms) for t_ms in (0, 1, 19, 20, 21, 39, 40)]
    [0, 0, 0, 20, 20, 20, 40]
    """

    def __init__(self, rate_hz: float) -> None:
        self._period_ns = round(1e9 / rate_hz) if rate_hz > 0.0 else 0
        self._next_ns: int | None = None
        self._held: T | None = None

    def at(self, t_ns: int, command: T) -> T:
        """The command the device applies at plant time ``t_ns`` given the latest ``command``."""
        if self._period_ns == 0:
            return command
        if self._next_ns is None or t_ns >= self._next_ns or self._held is None:
            self._held = command
            slot = t_ns // self._period_ns
            self._next_ns = (slot + 1) * self._period_ns
        return self._held
