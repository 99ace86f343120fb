"""The T200 thrust curve: thrust (N) <-> ESC pulse width (µs) at a battery voltage.

Pure (numpy, scipy). The table is data of the robot folder (``hardware.yaml``, ``ardusub.t200``:
Blue Robotics' T200 public performance data at 16 V, its dead band and extremes); between its
points the thrust is interpolated by PCHIP (Fritsch-Carlson monotone cubic,
``scipy.interpolate.PchipInterpolator`` computes it), so the curve is monotone wherever the
table is and flat (zero) across the dead band. Other voltages scale the thrust by
``(V / V_table) ** voltage_exponent`` (an assumption stated in ``hardware.yaml``).

The sign of each thruster on the frame is not applied here: the caller multiplies its thrust
by the thruster's direction (+1/-1) once, before ``pwm_from_thrust``::

    curve = T200Curve.from_section(hardware_section('bluerov2_alpha5', 'ardusub')[1]['t200'])
    pwm_us = curve.pwm_from_thrust(direction * thrust_n, voltage_v)   # 1100..1900
    thrust_n = direction * curve.thrust_from_pwm(pwm_us, voltage_v)    # the twin's inverse
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.interpolate import PchipInterpolator  # type: ignore[import-untyped]

FloatArray = npt.NDArray[np.float64]

#: Standard gravity (m/s^2): kgf -> N.
KGF_N = 9.80665
#: Step of the dense table the inverse interpolates on (µs).
GRID_STEP_US = 0.25


@dataclass(frozen=True)
class T200Curve:
    """A thrust-vs-PWM table at one voltage and its voltage scaling.

    Attributes:
        pwm_us: Table pulse widths (µs), increasing, from ``min_pwm_us`` to ``max_pwm_us``.
        thrust_n: Thrust at each (N), non-decreasing, zero across the dead band.
        table_voltage_v: Voltage of the table (V).
        voltage_exponent: Thrust scales as (V / table_voltage_v) ** voltage_exponent.
        min_voltage_v, max_voltage_v: Range the scaling is used in (V); outside, clamped.
        neutral_pwm_us: Zero thrust (µs).
    """

    pwm_us: tuple[float, ...]
    thrust_n: tuple[float, ...]
    table_voltage_v: float = 16.0
    voltage_exponent: float = 1.5
    min_voltage_v: float = 10.0
    max_voltage_v: float = 20.0
    neutral_pwm_us: float = 1500.0

    def __post_init__(self) -> None:
        """Check the table: increasing PWM, non-decreasing thrust, zero at neutral."""
        pwm, thrust = np.asarray(self.pwm_us), np.asarray(self.thrust_n)
        if len(pwm) < 3 or len(pwm) != len(thrust):
            raise ValueError(f'T200 table: {len(pwm)} pulse widths, {len(thrust)} thrusts '
                             '(expected the same number, at least 3)')
        if not (np.all(np.diff(pwm) > 0) and np.all(np.diff(thrust) >= 0)):
            raise ValueError('T200 table: pulse widths must increase and thrusts not decrease')
        if not pwm[0] < self.neutral_pwm_us < pwm[-1]:
            raise ValueError(f'T200 table: neutral {self.neutral_pwm_us} µs outside the table')

    @classmethod
    def from_section(cls, section: Mapping[str, Any]) -> T200Curve:
        """From ``hardware.yaml``'s ``ardusub.t200`` (thrust in kgf there)."""
        return cls(tuple(float(p) for p in section['pwm_us']),
                   tuple(float(f) * KGF_N for f in section['thrust_kgf']),
                   float(section.get('table_voltage_v', 16.0)),
                   float(section.get('voltage_exponent', 1.5)),
                   float(section.get('min_voltage_v', 10.0)),
                   float(section.get('max_voltage_v', 20.0)),
                   float(section.get('neutral_pwm_us', 1500.0)))

    @functools.cached_property
    def _interpolant(self) -> PchipInterpolator:
        """Monotone cubic (PCHIP) through the table: no overshoot between its points."""
        return PchipInterpolator(np.asarray(self.pwm_us, float), np.asarray(self.thrust_n, float))

    @functools.cached_property
    def _grid(self) -> tuple[FloatArray, FloatArray]:
        grid = np.arange(self.pwm_us[0], self.pwm_us[-1] + GRID_STEP_US / 2, GRID_STEP_US)
        return grid, np.asarray(self._interpolant(grid), float)

    @functools.cached_property
    def _branches(self) -> tuple[tuple[FloatArray, FloatArray], tuple[FloatArray, FloatArray]]:
        """(thrust, pwm) of the forward and the reverse branch of `_grid`, found once.

        Each runs from the dead band's edge outwards, where the curve is strictly increasing
        (PCHIP of increasing points), so ``np.interp`` inverts it and clamps at its ends.
        """
        grid, thrust = self._grid
        start = int(np.flatnonzero(thrust <= 0.0)[-1])
        stop = int(np.flatnonzero(thrust >= 0.0)[0])
        return (thrust[start:], grid[start:]), (thrust[:stop + 1], grid[:stop + 1])

    @property
    def min_pwm_us(self) -> float:
        """Shortest pulse (µs): full reverse."""
        return self.pwm_us[0]

    @property
    def max_pwm_us(self) -> float:
        """Longest pulse (µs): full forward."""
        return self.pwm_us[-1]

    def voltage_scale(self, voltage_v: float | None) -> float:
        """Thrust at ``voltage_v`` over thrust at the table's voltage (None/NaN: 1)."""
        if voltage_v is None or not math.isfinite(voltage_v):
            return 1.0
        clamped = min(max(voltage_v, self.min_voltage_v), self.max_voltage_v)
        return float((clamped / self.table_voltage_v) ** self.voltage_exponent)

    def thrust_from_pwm(self, pwm_us: float, voltage_v: float | None = None) -> float:
        """Thrust (N) of a pulse (µs, clamped to the table) at ``voltage_v`` (V)."""
        return float(self.thrusts_from_pwm(np.array([float(pwm_us)]), voltage_v)[0])

    def thrusts_from_pwm(self, pwm_us: FloatArray, voltage_v: float | None = None) -> FloatArray:
        """Thrusts (N) of several pulses (µs, clamped to the table) in one interpolant call."""
        clamped = np.clip(np.asarray(pwm_us, float), self.pwm_us[0], self.pwm_us[-1])
        return np.asarray(self._interpolant(clamped), float) * self.voltage_scale(voltage_v)

    def pwm_from_thrust(self, thrust_n: float, voltage_v: float | None = None) -> float:
        """Pulse (µs) giving ``thrust_n`` (N) at ``voltage_v`` (V), clamped to the table.

        Zero (and NaN) gives neutral; a thrust of either sign starts at the dead band's edge,
        so a small command is not lost in it.
        """
        if not math.isfinite(thrust_n) or thrust_n == 0.0:
            return self.neutral_pwm_us
        target = thrust_n / self.voltage_scale(voltage_v)
        forward, reverse = self._branches  # the branch slices depend on the table alone
        f, g = forward if target > 0.0 else reverse
        return float(np.interp(target, f, g))


def clamp_pwm(pwm_us: float, low_us: float = 1100.0, high_us: float = 1900.0) -> int:
    """A pulse width rounded to whole µs within [low_us, high_us] (NaN: neutral 1500)."""
    if not math.isfinite(pwm_us):
        return 1500
    return round(min(max(pwm_us, low_us), high_us))


@functools.lru_cache(maxsize=4)
def robot_curve(robot_name: str = 'bluerov2_alpha5') -> T200Curve:
    """The T200 curve of a robot folder's ``hardware.yaml`` (``ardusub.t200``)."""
    from uvms_hardware.hardware_config import hardware_section

    return T200Curve.from_section(hardware_section(robot_name, 'ardusub')[1]['t200'])


def pwm_from_thrust(thrust_n: float, voltage_v: float | None,
                    curve: T200Curve | None = None) -> float:
    """Pulse (µs) for ``thrust_n`` (N) at ``voltage_v`` (V); the default robot's curve."""
    return (curve or robot_curve()).pwm_from_thrust(thrust_n, voltage_v)


def thrust_from_pwm(pwm_us: float, voltage_v: float | None,
                    curve: T200Curve | None = None) -> float:
    """Thrust (N) of ``pwm_us`` (µs) at ``voltage_v`` (V); the default robot's curve."""
    return (curve or robot_curve()).thrust_from_pwm(pwm_us, voltage_v)


def curve_from_table(pwm_us: Sequence[float], thrust_kgf: Sequence[float]) -> T200Curve:
    """A 16 V curve from a table in kgf (for tests and tools)."""
    return T200Curve.from_section({'pwm_us': list(pwm_us), 'thrust_kgf': list(thrust_kgf)})
