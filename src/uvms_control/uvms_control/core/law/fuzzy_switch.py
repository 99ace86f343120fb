"""Fuzzy switch between impedance and hybrid position/force control (paper sec. 4.3).

The switch maps the force ratio F_e/F_d and the end-effector velocity v_e along the
environment normal to the weight W of the blend F_c = W F_IP + (1 - W) F_H (eq. 2), with the
paper's three rules (sec. 4.3):

    IF F_e/F_d is FS AND v_e is VF THEN W is WL
    IF F_e/F_d is FM               THEN W is WM
    IF F_e/F_d is FL AND v_e is VS THEN W is WS

Inference is Mamdani: min for AND, clipping implication, max aggregation, centroid
defuzzification. The centroid is computed exactly (the aggregated set is piecewise linear, so
integrating it between its kinks is exact), which keeps W(F_e/F_d, v_e) continuous and cheap.

Sign convention: v_e is the end-effector velocity along the unit normal n pointing from the
end effector into the environment (the direction in which it pushes), so approaching the wall
is positive. Receding (v_e < 0) is "slow" (VS): it carries no impact risk.

Where no rule fires (a small force while moving slowly, or a large force while still
approaching fast), the paper gives no answer. We answer W = 1, the impedance law: it is the
law designed for free motion and impacts, while the hybrid law's force loop acts on a force
error that is meaningless before a stable contact exists. To keep W continuous at the edges of
the rule supports, the rule-base output is blended with that answer by the degree to which the
rules cover the input, m = min(1, sum of the rule strengths): W = m W_centroid + (1 - m) W_none.
Wherever the rules cover the input fully (m = 1: one rule fires fully, or neighbouring rules
share it, as FM and FL do between their cores), W is exactly the paper's min-max-centroid
inference; a hard switch to W_none where no rule fires would jump at the edges of FM.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from uvms_model.jit import kernel

from uvms_control.core.fuzzy_sets import (
    FuzzySwitchParameters,
    Trapezoid,
    trapezoid_membership,
)

FloatArray = npt.NDArray[np.float64]
#: Grid points per block of ``FuzzySwitch.surface``.
_SURFACE_BLOCK_POINTS = 8192


@kernel
def rule_strengths_scalar(
    corners: FloatArray, force_ratio: float, normal_velocity: float
) -> tuple[float, float, float]:
    """The three rules' strengths at one sample (sec. 4.3), min for AND (compiled).

    ``corners`` rows (a, b, c, d): FS, FM, FL on the force ratio, then VS, VF on the velocity.
    Rules: FS and VF -> WL; FM -> WM; FL and VS -> WS.
    """
    m = np.empty(5)
    for k in range(5):
        x = force_ratio if k < 3 else normal_velocity
        m[k] = trapezoid_membership(corners[k, 0], corners[k, 1], corners[k, 2], corners[k, 3], x)
    return min(m[0], m[4]), m[1], min(m[2], m[3])


def _clipped_trapezoid(line: tuple[float, float, float, float, float], x: float) -> float:
    """Value at x of a trapezoid clipped at height h, given as (a, p, q, d, h)."""
    a, p, q, d, h = line
    if x <= a or x >= d:
        return 0.0
    if x < p:
        return h * (x - a) / (p - a)
    if x <= q:
        return h
    return h * (d - x) / (d - q)


def _envelope_integrals(
    lines: list[tuple[float, float, float, float, float]],
) -> tuple[float, float]:
    """Area and first moment of the upper envelope of clipped trapezoids (a, p, q, d, h).

    Between consecutive corners every clipped set is linear, so the envelope can only kink
    at the corners and where two sets cross; it is integrated exactly between those points.
    """
    xs = sorted({x for line in lines for x in line[:4]})
    points: list[tuple[float, float]] = []
    prev: list[float] = []
    for i, x in enumerate(xs):
        values = [_clipped_trapezoid(line, x) for line in lines]
        if i > 0:
            x_prev = xs[i - 1]
            for j in range(len(lines)):
                for k in range(j + 1, len(lines)):
                    d0 = prev[j] - prev[k]
                    d1 = values[j] - values[k]
                    if d0 * d1 < 0.0:
                        xc = x_prev + (x - x_prev) * d0 / (d0 - d1)
                        points.append((xc, max(_clipped_trapezoid(line, xc) for line in lines)))
        points.append((x, max(values)))
        prev = values
    points.sort()
    area = 0.0
    moment = 0.0
    for (x0, g0), (x1, g1) in itertools.pairwise(points):
        dx = x1 - x0
        area += dx * (g0 + g1) / 2.0
        moment += dx * ((2.0 * x0 + x1) * g0 + (x0 + 2.0 * x1) * g1) / 6.0
    return area, moment


def _envelope_integrals_two(
    first: tuple[float, float, float, float, float],
    second: tuple[float, float, float, float, float],
) -> tuple[float, float]:
    """`_envelope_integrals` for two sets, inlined: the control step's usual blend case.

    With two sets a crossing of their sides always lies on the envelope, and there is at
    most one per interval between corners.
    """
    xs = sorted({*first[:4], *second[:4]})
    a1, p1, q1, d1, h1 = first
    a2, p2, q2, d2, h2 = second
    area = moment = 0.0
    x_prev = g_prev = u_prev = v_prev = 0.0
    for i, x in enumerate(xs):
        if x <= a1 or x >= d1:
            u = 0.0
        elif x < p1:
            u = h1 * (x - a1) / (p1 - a1)
        elif x <= q1:
            u = h1
        else:
            u = h1 * (d1 - x) / (d1 - q1)
        if x <= a2 or x >= d2:
            v = 0.0
        elif x < p2:
            v = h2 * (x - a2) / (p2 - a2)
        elif x <= q2:
            v = h2
        else:
            v = h2 * (d2 - x) / (d2 - q2)
        g = u if u > v else v
        if i > 0:
            e0, e1 = u_prev - v_prev, u - v
            if e0 * e1 < 0.0:
                s = e0 / (e0 - e1)
                xc, gc = x_prev + (x - x_prev) * s, u_prev + (u - u_prev) * s
                dx = xc - x_prev
                area += dx * (g_prev + gc)
                moment += dx * ((2.0 * x_prev + xc) * g_prev + (x_prev + 2.0 * xc) * gc)
                x_prev, g_prev = xc, gc
            dx = x - x_prev
            area += dx * (g_prev + g)
            moment += dx * ((2.0 * x_prev + x) * g_prev + (x_prev + 2.0 * x) * g)
        x_prev, g_prev, u_prev, v_prev = x, g, u, v
    return area / 2.0, moment / 6.0


def _line_intersections(sets: Sequence[Trapezoid]) -> list[float]:
    """Abscissae where the sloped sides of two different output sets cross."""
    sides: list[tuple[float, float]] = []  # mu = slope * x + offset
    for s in sets:
        if s.b > s.a:
            sides.append((1.0 / (s.b - s.a), -s.a / (s.b - s.a)))
        if s.d > s.c:
            sides.append((-1.0 / (s.d - s.c), s.d / (s.d - s.c)))
    points = []
    for i, (k1, o1) in enumerate(sides):
        for k2, o2 in sides[i + 1 :]:
            if k1 != k2:
                points.append((o2 - o1) / (k1 - k2))
    return points


class FuzzySwitch:
    """Fuzzy switching law W(F_e/F_d, v_e) of paper sec. 4.3 (Figs. 4 and 5).

    Example:
        >>> switch = FuzzySwitch()
        >>> round(switch.weight(0.5, 0.0), 6)  # FM fires fully: W is WM's centre
        0.5
    """

    def __init__(self, params: FuzzySwitchParameters | None = None) -> None:
        self.params = params if params is not None else FuzzySwitchParameters()
        p = self.params
        # Output sets in rule order: rule 1 -> WL, rule 2 -> WM, rule 3 -> WS.
        self._outputs = (p.weight_large, p.weight_medium, p.weight_small)
        inputs = (p.force_small, p.force_medium, p.force_large, p.velocity_slow, p.velocity_fast)
        self._input_corners = np.array([[s.a, s.b, s.c, s.d] for s in inputs])
        corners = np.array([[s.a, s.b, s.c, s.d] for s in self._outputs])
        self._lo = float(corners[:, 0].min())
        self._hi = float(corners[:, 3].max())
        fixed = [*corners.ravel(), *_line_intersections(self._outputs)]
        self._fixed_points = np.clip(np.array(fixed, dtype=np.float64), self._lo, self._hi)
        # Clipping level h puts kinks at a + (b - a) h and d - (d - c) h on every output set.
        self._rise_a = corners[:, 0]
        self._rise_k = corners[:, 1] - corners[:, 0]
        self._fall_d = corners[:, 3]
        self._fall_k = corners[:, 3] - corners[:, 2]
        self._rise_slope = np.where(
            self._rise_k > 0.0, 1.0 / np.where(self._rise_k > 0.0, self._rise_k, 1.0), 0.0
        )
        self._fall_slope = np.where(
            self._fall_k > 0.0, 1.0 / np.where(self._fall_k > 0.0, self._fall_k, 1.0), 0.0
        )

    def rule_strengths(
        self, force_ratio: npt.ArrayLike, normal_velocity: npt.ArrayLike
    ) -> FloatArray:
        """Firing strengths (..., 3) of the rules (FS and VF, FM, FL and VS), min for AND."""
        p = self.params
        r = np.asarray(force_ratio, dtype=np.float64)
        v = np.asarray(normal_velocity, dtype=np.float64)
        r, v = np.broadcast_arrays(r, v)
        rule_1 = np.minimum(p.force_small(r), p.velocity_fast(v))
        rule_2 = p.force_medium(r)
        rule_3 = np.minimum(p.force_large(r), p.velocity_slow(v))
        return np.stack([rule_1, rule_2, rule_3], axis=-1)

    def _output_membership(self, x: FloatArray) -> FloatArray:
        """Membership (..., K, 3) of the points x (..., K) in the output sets WL, WM, WS."""
        x3 = x[..., np.newaxis]
        rise = np.where(
            self._rise_k > 0.0, (x3 - self._rise_a) * self._rise_slope, (x3 >= self._rise_a) * 1.0
        )
        fall = np.where(
            self._fall_k > 0.0, (self._fall_d - x3) * self._fall_slope, (x3 <= self._fall_d) * 1.0
        )
        result: FloatArray = np.clip(np.minimum(rise, fall), 0.0, 1.0)
        return result

    def defuzzify(self, strengths: npt.ArrayLike) -> FloatArray:
        """Weight W (...) from rule strengths (..., 3): clip, max-aggregate, exact centroid.

        Applies the no-rule blend W = m W_centroid + (1 - m) W_none with m = min(1, sum of
        the strengths) (see the module docstring).
        """
        h = np.asarray(strengths, dtype=np.float64)
        lead = h.shape[:-1]
        # Every kink of the aggregated set max_k min(h_k, mu_k(x)) is a corner of an output
        # set, a crossing of two sides, or where a side reaches a clipping level.
        levels = h[..., np.newaxis, :]  # (..., 1, 3): each level against each set
        rise_pts = self._rise_a[:, np.newaxis] + self._rise_k[:, np.newaxis] * levels
        fall_pts = self._fall_d[:, np.newaxis] - self._fall_k[:, np.newaxis] * levels
        x = np.concatenate(
            [
                np.broadcast_to(self._fixed_points, (*lead, self._fixed_points.size)),
                np.clip(rise_pts.reshape(*lead, -1), self._lo, self._hi),
                np.clip(fall_pts.reshape(*lead, -1), self._lo, self._hi),
            ],
            axis=-1,
        )
        x = np.sort(x, axis=-1)
        g = np.max(np.minimum(self._output_membership(x), h[..., np.newaxis, :]), axis=-1)
        x0, x1 = x[..., :-1], x[..., 1:]
        g0, g1 = g[..., :-1], g[..., 1:]
        dx = x1 - x0
        area = np.sum(dx * (g0 + g1), axis=-1) / 2.0
        moment = np.sum(dx * ((2.0 * x0 + x1) * g0 + (x0 + 2.0 * x1) * g1), axis=-1) / 6.0
        m = np.minimum(np.sum(h, axis=-1), 1.0)
        safe_area = np.where(area > 0.0, area, 1.0)
        centroid = np.where(area > 0.0, moment / safe_area, self.params.no_rule_weight)
        w: FloatArray = np.clip(m * centroid + (1.0 - m) * self.params.no_rule_weight, 0.0, 1.0)
        return w

    def weight(self, force_ratio: float, normal_velocity: float) -> float:
        """Switching weight W in [0, 1] for one sample (sec. 4.3; 1 = impedance, 0 = hybrid).

        Args:
            force_ratio: F_e/F_d, the normal contact force over the desired force (-).
            normal_velocity: v_e, end-effector speed toward the environment (m/s).
        """
        return self.defuzzify_scalar(
            rule_strengths_scalar(self._input_corners, force_ratio, normal_velocity)
        )

    def defuzzify_scalar(self, strengths: Sequence[float]) -> float:
        """Weight W from the three rule strengths, exactly, in plain floats.

        The same inference as `defuzzify` without numpy (a few microseconds instead of tens):
        the aggregated set is the upper envelope of the clipped output trapezoids, integrated
        exactly between its kinks, which are the trapezoids' corners and the crossings of
        their sides.
        """
        m = min(sum(strengths), 1.0)
        w_none = self.params.no_rule_weight
        if m <= 0.0:
            return w_none
        lines = []
        for out, h in zip(self._outputs, strengths, strict=True):
            if h > 0.0:
                lines.append(
                    (out.a, out.a + (out.b - out.a) * h, out.d - (out.d - out.c) * h, out.d, h)
                )
        if len(lines) == 1:
            # One clipped trapezoid (a, 0) (p, h) (q, h) (d, 0): its centroid in closed form.
            a, p, q, d, _ = lines[0]
            area = (p - a) + 2.0 * (q - p) + (d - q)
            moment = (p - a) * (a + 2.0 * p) + 3.0 * (q - p) * (p + q) + (d - q) * (2.0 * q + d)
            centroid = moment / (3.0 * area) if area > 0.0 else w_none
            return min(max(m * centroid + (1.0 - m) * w_none, 0.0), 1.0)
        if len(lines) == 2:
            area, moment = _envelope_integrals_two(lines[0], lines[1])
        else:
            area, moment = _envelope_integrals(lines)
        centroid = moment / area if area > 0.0 else w_none
        return min(max(m * centroid + (1.0 - m) * w_none, 0.0), 1.0)

    def surface(self, force_ratios: npt.ArrayLike, normal_velocities: npt.ArrayLike) -> FloatArray:
        """Input/output surface of the switch (paper Fig. 5).

        Args:
            force_ratios: F_e/F_d samples (n_r,).
            normal_velocities: v_e samples (n_v,) in m/s.

        Returns:
            W on the grid, shape (n_v, n_r): row i is velocity i, column j is ratio j (the
            ``np.meshgrid(force_ratios, normal_velocities)`` layout, ready for plotting).
        """
        ratios = np.asarray(force_ratios, dtype=np.float64)
        velocities = np.asarray(normal_velocities, dtype=np.float64)
        # A few thousand points per block: defuzzify's temporaries (about 30 breakpoints a
        # point) then stay in the cache; the whole of a fine grid at once ran 3-4x slower.
        rows = max(1, _SURFACE_BLOCK_POINTS // max(ratios.size, 1))
        blocks = [self.defuzzify(self.rule_strengths(*np.meshgrid(ratios, velocities[i:i + rows])))
                  for i in range(0, velocities.size, rows)]
        surface: FloatArray = (np.concatenate(blocks, axis=0) if blocks
                               else np.empty((0, ratios.size)))
        return surface
