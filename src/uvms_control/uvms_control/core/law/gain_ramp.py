"""New gains taking over from the old ones over a few control periods, without a bump.

The laws are linear in their gains (P⁻¹K, P⁻¹B_d, P⁻¹ of eq. 30; K_pp, K_pv of eq. 37;
K_fp, K_fi, K_fv, c of eq. 39; K_n, D_n of eq. 24), so moving those gains linearly from the
old to the new values blends the old and new laws' outputs. ``GainRamp`` holds both sets and
the share of the new one; the controller applies what ``advance`` returns at each step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from uvms_control.core.law.fuzzy_switch import FuzzySwitch

FloatArray = npt.NDArray[np.float64]
ForceGains = tuple[float, float, float, float]

#: Control periods over which new gains take over: 50 ms at 500 Hz.
GAIN_RAMP_PERIODS = 25


@dataclass(slots=True)
class GainRamp:
    """Old and new linear gains of a run-time change, blended over GAIN_RAMP_PERIODS steps.

    Attributes:
        law_map: the controller's law map G (9, 19), old and new.
        null_gains: the null-space rows K_n, D_n (2, 6 + n), old and new.
        force_gains: (K_fp, K_fi, K_fv, c), old and new.
        fuzzy: the old fuzzy switch (its W is blended with the new one's).
        steps: steps taken so far.
        share: share of the new gains at the last step (0..1).

    Example:
        >>> ramp = GainRamp((np.zeros(1), np.ones(1)), (np.zeros(1), np.ones(1)),
        ...                 ((0.0,) * 4, (1.0,) * 4), None)  # type: ignore[arg-type]
        >>> ramp.advance()[0].tolist(), ramp.share
        ([0.04], 0.04)
    """

    law_map: tuple[FloatArray, FloatArray]
    null_gains: tuple[FloatArray, FloatArray]
    force_gains: tuple[ForceGains, ForceGains]
    fuzzy: FuzzySwitch
    steps: int = 0
    share: float = 0.0

    @property
    def done(self) -> bool:
        """The new gains are fully in."""
        return self.steps >= GAIN_RAMP_PERIODS

    def advance(self) -> tuple[FloatArray, FloatArray, ForceGains]:
        """One step further: the blended law map, null-space rows and force gains."""
        self.steps += 1
        share = self.share = min(self.steps / GAIN_RAMP_PERIODS, 1.0)
        old_map, new_map = self.law_map
        old_null, new_null = self.null_gains
        (a0, a1, a2, a3), (b0, b1, b2, b3) = self.force_gains
        return (old_map + share * (new_map - old_map), old_null + share * (new_null - old_null),
                (a0 + share * (b0 - a0), a1 + share * (b1 - a1), a2 + share * (b2 - a2),
                 a3 + share * (b3 - a3)))

    def blend_weight(self, W_new: float, force_ratio: float, v_e: float) -> float:
        """W between the old switch's and the new one's, by the share of the new gains."""
        if self.share >= 1.0:
            return W_new
        return self.share * W_new + (1.0 - self.share) * self.fuzzy.weight(force_ratio, v_e)
