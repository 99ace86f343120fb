"""Thruster fault injection on the plant side: the physical thrusters and their ESCs.

The allocator node hosts two things (docs/architecture.md "Thruster faults"): the allocation,
which is software on the vehicle, and the thruster dynamics (eq. 11-15), which stand for the
physical ESCs, motors and propellers whose actual thrusts go to the simulator. Faults are
injected here, between the allocation's desired thrust and the thruster model; the
allocation side never reads what was injected: it sees only what a real ESC reports
(``EscSensor``: the commanded reference speed, and the measured propeller speed and motor
current with sensor noise).

Kinds, per thruster, from ``at_s`` (node-clock seconds) on; the thruster model then follows
the demand F_m instead of the desired thrust F_td:

- ``off``: the motor gets no drive, F_m = 0 (the speed loop brakes the propeller to rest:
  a faster spin-down than a coasting one).
- ``efficiency`` η in [0, 1]: the motor reaches only the speed of η F_td, F_m = η F_td,
  so the steady thrust is η F_td (a flooded winding, a sagging supply). A propeller-side loss
  at full speed (a broken blade) would show in the current instead: not modelled.
- ``stuck`` at a thrust F_s (N): F_m = F_s whatever is commanded (a seized speed loop).
- ``saturation`` at F_max (N) > 0: F_m = clip(F_td, -F_max, F_max) (a current-limited ESC).

Faults are written ``index=I kind=K [value=V] at_s=T``, several joined by ``;``: the
``fault_injection.thrusters`` parameter, which a scenario's ``faults`` key fills and which
can be set at run time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from uvms_thrusters.errors import ThrusterParameterError

FloatArray = npt.NDArray[np.float64]

#: Fault kinds and what their value is.
FAULT_KINDS = {
    'off': 'no value',
    'efficiency': 'eta in [0, 1]',
    'stuck': 'a finite thrust (N)',
    'saturation': 'a thrust limit > 0 (N)',
}
PARAMETER = 'fault_injection.thrusters'
_FIELDS = ('index', 'kind', 'value', 'at_s')


@dataclass(frozen=True)
class ThrusterFault:
    """One injected fault.

    Attributes:
        index: Thruster index from 0, in the order of the robot's thrusters.yaml.
        kind: One of ``FAULT_KINDS``.
        value: η (efficiency), the thrust (stuck, N), the limit (saturation, N); 0 for off.
        at_s: Node-clock time from which it acts (s).
    """

    index: int
    kind: str
    value: float
    at_s: float

    def describe(self) -> str:
        """The fault in words: ``thruster 0 (T1) off``, ``... at efficiency 0.3``."""
        name = f'thruster {self.index} (T{self.index + 1})'
        what = {'off': 'off', 'efficiency': f'at efficiency {self.value:g}',
                'stuck': f'stuck at {self.value:g} N',
                'saturation': f'saturated at +-{self.value:g} N'}.get(
                    self.kind, f'{self.kind} {self.value:g}')
        return f'{name} {what}'

    def text(self) -> str:
        """The fault as ``parse_faults`` reads it."""
        value = '' if self.kind == 'off' else f' value={self.value!r}'
        return f'index={self.index} kind={self.kind}{value} at_s={self.at_s!r}'


def check_fault(index: object, kind: object, value: object, at_s: object,
                where: str) -> ThrusterFault:
    """A validated fault; ``where`` names it in the error (a parameter or a scenario key).

    Raises:
        ValueError: naming ``where``, the field, its value and what is valid.
    """
    if isinstance(index, bool) or not isinstance(index, int) or index < 0:
        raise ValueError(f'{where}: index {index!r} must be an int >= 0')
    if kind not in FAULT_KINDS:
        raise ValueError(f'{where}: kind {kind!r} must be one of {", ".join(FAULT_KINDS)}')
    assert isinstance(kind, str)
    if isinstance(at_s, bool) or not isinstance(at_s, int | float) or not (
            math.isfinite(at_s) and at_s >= 0.0):
        raise ValueError(f'{where}: at_s {at_s!r} must be a number of seconds >= 0')
    if kind == 'off':
        if value not in (None, 0, 0.0):
            raise ValueError(f'{where}: kind off takes no value, got {value!r}')
        return ThrusterFault(index, kind, 0.0, float(at_s))
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ValueError(f'{where}: kind {kind} needs a value, {FAULT_KINDS[kind]}; '
                         f'got {value!r}')
    if (kind == 'efficiency' and not 0.0 <= value <= 1.0) or (
            kind == 'saturation' and value <= 0.0):
        raise ValueError(f'{where}: value {value!r} of kind {kind} must be {FAULT_KINDS[kind]}')
    return ThrusterFault(index, kind, float(value), float(at_s))


def parse_faults(text: str, count: int | None = None) -> tuple[ThrusterFault, ...]:
    """Faults from ``index=I kind=K [value=V] at_s=T; ...`` ('' for none).

    Args:
        text: The ``fault_injection.thrusters`` parameter.
        count: Number of thrusters, to check the indices (None: unchecked).

    Raises:
        ThrusterParameterError: naming the parameter, the entry and what is valid.
    """
    faults = []
    for n, entry in enumerate(part.strip() for part in text.split(';')):
        if not entry:
            continue
        fields: dict[str, str] = {}
        for item in entry.split():
            key, sep, raw = item.partition('=')
            if not sep or key not in _FIELDS or key in fields:
                raise ThrusterParameterError(
                    PARAMETER, text, f'entries "index=I kind=K [value=V] at_s=T" joined by ";" '
                    f'(entry {n}: {item!r})')
            fields[key] = raw
        try:
            index = int(fields['index']) if 'index' in fields else None
            value = float(fields['value']) if 'value' in fields else None
            at_s = float(fields['at_s']) if 'at_s' in fields else None
            fault = check_fault(index, fields.get('kind'), value, at_s, f'entry {n}')
        except ValueError as error:
            raise ThrusterParameterError(PARAMETER, text, str(error)) from error
        if count is not None and fault.index >= count:
            raise ThrusterParameterError(
                PARAMETER, text, f'entry {n}: index in [0, {count - 1}] ({count} thrusters)')
        faults.append(fault)
    return tuple(sorted(faults, key=lambda f: f.at_s))


def format_faults(faults: tuple[ThrusterFault, ...] | list[ThrusterFault]) -> str:
    """The parameter text of ``faults``."""
    return '; '.join(fault.text() for fault in faults)


class ThrusterFaultInjector:
    """The demand each physical thruster follows, given the desired thrusts and the time.

    Example:
        >>> injector = ThrusterFaultInjector(parse_faults('index=1 kind=efficiency '
        ...                                               'value=0.3 at_s=2'), 3)
        >>> injector.motor_demand(np.array([10.0, 10.0, 10.0]), 1.0).tolist()
        [10.0, 10.0, 10.0]
        >>> injector.motor_demand(np.array([10.0, 10.0, 10.0]), 2.0).tolist()
        [10.0, 3.0, 10.0]
    """

    def __init__(self, faults: tuple[ThrusterFault, ...], count: int) -> None:
        for fault in faults:
            if fault.index >= count:
                raise ThrusterParameterError(PARAMETER, format_faults(faults),
                                            f'indices in [0, {count - 1}] ({count} thrusters)')
        self.faults = tuple(sorted(faults, key=lambda f: f.at_s))
        self.count = count
        self._demand = np.zeros(count)
        self._started = 0

    def newly_started(self, t_s: float) -> tuple[ThrusterFault, ...]:
        """The faults that start acting at t_s and were not returned before (once each)."""
        first = self._started
        while self._started < len(self.faults) and self.faults[self._started].at_s <= t_s:
            self._started += 1
        return self.faults[first:self._started]

    def active(self, t_s: float) -> dict[int, ThrusterFault]:
        """Per thruster index, the fault acting at t_s (the latest started one)."""
        return {f.index: f for f in self.faults if f.at_s <= t_s}

    def motor_demand(self, f_td: FloatArray, t_s: float) -> FloatArray:
        """F_m (p,): the desired thrusts f_td as each faulty thruster follows them at t_s.

        Returns ``f_td`` itself while no fault acts; else the injector's own buffer.
        """
        if not self.faults or self.faults[0].at_s > t_s:
            return f_td
        demand = self._demand
        demand[:] = f_td
        for i, fault in self.active(t_s).items():
            if fault.kind == 'off':
                demand[i] = 0.0
            elif fault.kind == 'efficiency':
                demand[i] = fault.value * f_td[i]
            elif fault.kind == 'stuck':
                demand[i] = fault.value
            else:
                demand[i] = min(max(f_td[i], -fault.value), fault.value)
        return demand


def reference_speed(f_td: FloatArray, alpha_2: tuple[float, float]) -> FloatArray:
    """Ω_r = sign(F) sqrt(|F| / α_2) (eq. 11), α_2 forward for F >= 0 and reverse below."""
    a2 = np.where(f_td >= 0.0, alpha_2[0], alpha_2[1])
    return np.asarray(np.sign(f_td) * np.sqrt(np.abs(f_td) / a2), dtype=np.float64)


@dataclass(frozen=True)
class EscFeedback:
    """What the ESCs report in one step.

    Attributes:
        reference_speed: Ω_r of the commanded thrust (rad/s).
        measured_speed: Ω with sensor noise (rad/s).
        measured_current: i_m with sensor noise (A).
    """

    reference_speed: FloatArray
    measured_speed: FloatArray
    measured_current: FloatArray


class EscSensor:
    """ESC telemetry: propeller speed and motor current with Gaussian noise, seeded.

    Args:
        count: Number of thrusters.
        speed_noise_rad_s: Standard deviation of the measured speed (rad/s).
        current_noise_a: Standard deviation of the measured current (A).
        seed: Seed of the noise (same seed, same readings).
    """

    def __init__(self, count: int, speed_noise_rad_s: float, current_noise_a: float,
                 seed: int) -> None:
        self.count = count
        self.speed_noise = float(speed_noise_rad_s)
        self.current_noise = float(current_noise_a)
        self._rng = np.random.default_rng(seed)
        self._noise = np.zeros((0, 2, count))  # drawn in blocks: one call per _BLOCK steps
        self._next = 0

    def measure(self, reference: FloatArray, omega: FloatArray,
                current: FloatArray) -> EscFeedback:
        """Readings of one step (new arrays)."""
        if self._next >= len(self._noise):
            self._noise = self._rng.standard_normal((_BLOCK, 2, self.count))
            self._next = 0
        noise = self._noise[self._next]
        self._next += 1
        return EscFeedback(reference.copy(), omega + self.speed_noise * noise[0],
                           current + self.current_noise * noise[1])


#: Steps of ESC noise drawn at once.
_BLOCK = 1024
