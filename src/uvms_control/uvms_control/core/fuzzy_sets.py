"""Membership functions of the fuzzy switch (paper Fig. 4): trapezoids and the default sets."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from uvms_model.jit import kernel

from uvms_control.core.errors import ControlParameterError

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Trapezoid:
    """Trapezoidal membership function: 0 outside [a, d], 1 on [b, c], linear in between.

    ``a = b = -inf`` makes a left shoulder, ``c = d = +inf`` a right shoulder and ``b == c``
    a triangle.

    Example:
        >>> Trapezoid.triangle(0.0, 0.5, 1.0).scalar(0.25)
        0.5
    """

    a: float
    b: float
    c: float
    d: float
    name: str = 'membership'

    def __post_init__(self) -> None:
        corners = (self.a, self.b, self.c, self.d)
        if (
            any(math.isnan(x) for x in corners)
            or not (self.a <= self.b <= self.c <= self.d)
            or self.b == math.inf
            or self.c == -math.inf
        ):
            raise ControlParameterError(
                self.name, list(corners), 'corners a <= b <= c <= d, not NaN, with a finite core'
            )

    @classmethod
    def left_shoulder(
        cls, full_until: float, zero_from: float, name: str = 'membership'
    ) -> Trapezoid:
        """Set that is 1 up to ``full_until`` and 0 from ``zero_from`` on."""
        return cls(-math.inf, -math.inf, full_until, zero_from, name)

    @classmethod
    def right_shoulder(
        cls, zero_until: float, full_from: float, name: str = 'membership'
    ) -> Trapezoid:
        """Set that is 0 up to ``zero_until`` and 1 from ``full_from`` on."""
        return cls(zero_until, full_from, math.inf, math.inf, name)

    @classmethod
    def triangle(
        cls, left: float, peak: float, right: float, name: str = 'membership'
    ) -> Trapezoid:
        """Triangle with feet at ``left`` and ``right`` and its peak at ``peak``."""
        return cls(left, peak, peak, right, name)

    def __call__(self, x: npt.ArrayLike) -> FloatArray:
        """Membership degree of each element of ``x``, in [0, 1]."""
        x = np.asarray(x, dtype=np.float64)
        if self.b > self.a:
            rise = (x - self.a) / (self.b - self.a)
        else:
            rise = np.where(x >= self.a, 1.0, 0.0)
        if self.d > self.c:
            fall = (self.d - x) / (self.d - self.c)
        else:
            fall = np.where(x <= self.d, 1.0, 0.0)
        result: FloatArray = np.clip(np.minimum(rise, fall), 0.0, 1.0)
        return result

    def scalar(self, x: float) -> float:
        """Membership degree of one value (no numpy: the controller's per-step path)."""
        return float(trapezoid_membership(self.a, self.b, self.c, self.d, x))


@kernel
def trapezoid_membership(a: float, b: float, c: float, d: float, x: float) -> float:
    """Degree of x in the trapezoid with feet a, d and shoulders b, c (compiled)."""
    if b > a:
        rise = (x - a) / (b - a)
    else:
        rise = 1.0 if x >= a else 0.0
    if d > c:
        fall = (d - x) / (d - c)
    else:
        fall = 1.0 if x <= d else 0.0
    return min(max(min(rise, fall), 0.0), 1.0)


def _default_force_small() -> Trapezoid:
    return Trapezoid.left_shoulder(0.1, 0.5, 'fuzzy.force_ratio_small')


def _default_force_medium() -> Trapezoid:
    return Trapezoid.triangle(0.1, 0.5, 0.9, 'fuzzy.force_ratio_medium')


def _default_force_large() -> Trapezoid:
    return Trapezoid.right_shoulder(0.5, 0.9, 'fuzzy.force_ratio_large')


def _default_velocity_slow() -> Trapezoid:
    return Trapezoid.left_shoulder(0.05, 0.15, 'fuzzy.normal_velocity_slow')


def _default_velocity_fast() -> Trapezoid:
    return Trapezoid.right_shoulder(0.05, 0.15, 'fuzzy.normal_velocity_fast')


def _default_weight_small() -> Trapezoid:
    return Trapezoid.triangle(-0.5, 0.0, 0.5, 'fuzzy.weight_small')


def _default_weight_medium() -> Trapezoid:
    return Trapezoid.triangle(0.0, 0.5, 1.0, 'fuzzy.weight_medium')


def _default_weight_large() -> Trapezoid:
    return Trapezoid.triangle(0.5, 1.0, 1.5, 'fuzzy.weight_large')


@dataclass(frozen=True)
class FuzzySwitchParameters:
    """Membership functions of the fuzzy switch (paper Fig. 4) and the no-rule answer.

    Defaults (our reading of Fig. 4; the paper prints no numbers):
    force ratio F_e/F_d: FS left shoulder 1 below 0.1, 0 above 0.5; FM triangle 0.1-0.5-0.9;
    FL right shoulder 0 below 0.5, 1 above 0.9. Normal velocity v_e (m/s): VS left shoulder
    1 below 0.05, 0 above 0.15; VF its complement. The 0.05 m/s knee keeps a wall that
    recedes at the paper's Case III speed (0.05 m/s) "slow", so force tracking holds on it.
    Weight: WS, WM, WL triangles centred on 0, 0.5 and 1 with half-width 0.5. WS and WL
    extend outside [0, 1] so that a single fully firing rule defuzzifies exactly to its
    centre; W stays in [0, 1] because each set is symmetric about a centre inside [0, 1].
    """

    force_small: Trapezoid = field(default_factory=_default_force_small)
    force_medium: Trapezoid = field(default_factory=_default_force_medium)
    force_large: Trapezoid = field(default_factory=_default_force_large)
    velocity_slow: Trapezoid = field(default_factory=_default_velocity_slow)
    velocity_fast: Trapezoid = field(default_factory=_default_velocity_fast)
    weight_small: Trapezoid = field(default_factory=_default_weight_small)
    weight_medium: Trapezoid = field(default_factory=_default_weight_medium)
    weight_large: Trapezoid = field(default_factory=_default_weight_large)
    no_rule_weight: float = 1.0

    def __post_init__(self) -> None:
        if not 0.0 <= self.no_rule_weight <= 1.0:
            raise ControlParameterError('fuzzy.no_rule_weight', self.no_rule_weight, '[0, 1]')
        for out in (self.weight_small, self.weight_medium, self.weight_large):
            if not (math.isfinite(out.a) and math.isfinite(out.d) and out.d > out.a):
                raise ControlParameterError(
                    out.name, [out.a, out.b, out.c, out.d], 'a finite output set with d > a'
                )
