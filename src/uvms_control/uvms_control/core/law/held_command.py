"""The contact force to cancel when the arm's command is held for a device slot (eq. 28-30).

Eq. 29 and 35 cancel the measured contact force: F = ... + ζ̂ + F_e, so that the closed loop
(eq. 28) sees M̃ Ẍ = M̂ U. That holds when the command acts at once, for the F_e it was
computed from. On the Alpha 5 it does not: the bus latches one CURRENT command per joint per
slot (77 Hz) and holds it for the slot's 13 ms, and the wrist sensor's reading is one state
(2 ms) old when the controller steps (docs/hardware.md, "Device timing"). Against a stiff
wall (1e4 N/m) the light arm's contact mode is far faster than a slot, so a held command
cancels a force the wall no longer pushes with: measured, 78 times the ideal run's
mid-contact force error.

The remedy measured best (docs/hardware.md, "Device timing"): cancel the contact force
predicted for the middle of the slot the command is held over, h = latency + 1 / (2 rate)
after the sample, by a quadratic through the last three samples (first and second
difference). The force loop itself (eq. 39), the fuzzy switch and the task supervisor keep
the measured F_e. A command rate of 0 is the ideal device: h = 0 and the measured F_e, exactly
as eq. 29.

Pure Python, plain floats: it runs in the control step.
"""

from __future__ import annotations

import math

from uvms_control.core.errors import ControlParameterError

#: A gap between samples longer than this many of the first one restarts the prediction.
RESTART_RATIO = 5.0

Vector3 = tuple[float, float, float]


def held_slot_horizon_s(command_rate_hz: float, force_latency_s: float) -> float:
    """Prediction horizon h (s): the sample's age plus half a held command slot.

    Args:
        command_rate_hz: Rate at which the arm applies commands (Hz), each held until the
            next; 0 for every control step (the ideal device).
        force_latency_s: Age of the force sample when the controller steps (s).

    Returns:
        0 for the ideal device (command rate 0), else ``force_latency_s + 0.5 / rate``.

    Raises:
        ControlParameterError: a negative or non-finite rate or latency.

    >>> round(held_slot_horizon_s(77.0, 0.002), 5)
    0.00849
    >>> held_slot_horizon_s(0.0, 0.002)
    0.0
    """
    if not (math.isfinite(command_rate_hz) and command_rate_hz >= 0.0):
        raise ControlParameterError('arm.command_rate_hz', command_rate_hz, '[0, inf) Hz')
    if not (math.isfinite(force_latency_s) and force_latency_s >= 0.0):
        raise ControlParameterError('arm.force_latency_s', force_latency_s, '[0, inf) s')
    if command_rate_hz == 0.0:
        return 0.0
    return force_latency_s + 0.5 / command_rate_hz


def quadratic_extrapolation(samples: list[tuple[float, Vector3]], horizon_s: float) -> Vector3:
    """The value ``horizon_s`` after the newest sample on the parabola through the last three.

    Newton's form on the (possibly uneven) sample times; with two samples the line through
    them, with one the sample itself.

    Args:
        samples: (t (s), value) pairs, oldest first, at increasing times.
        horizon_s: How far past the newest sample (s).

    >>> quadratic_extrapolation([(0.0, (0.0, 0.0, 0.0)), (1.0, (1.0, 1.0, 1.0)),
    ...                          (2.0, (4.0, 4.0, 4.0))], 1.0)  # t^2 at t = 3
    (9.0, 9.0, 9.0)
    >>> quadratic_extrapolation([(0.0, (1.0, 2.0, 3.0)), (1.0, (2.0, 2.0, 2.0))], 0.5)
    (2.5, 2.0, 1.5)
    """
    t2, f2 = samples[-1]
    if len(samples) == 1 or horizon_s == 0.0:
        return f2
    t1, f1 = samples[-2]
    d1 = tuple((b - a) / (t2 - t1) for a, b in zip(f1, f2, strict=True))
    if len(samples) == 2:
        return (f2[0] + horizon_s * d1[0], f2[1] + horizon_s * d1[1], f2[2] + horizon_s * d1[2])
    t0, f0 = samples[-3]
    d0 = tuple((b - a) / (t1 - t0) for a, b in zip(f0, f1, strict=True))
    # p(t) = f2 + d1 (t - t2) + c (t - t2)(t - t1), c the second divided difference.
    w = horizon_s * (t2 + horizon_s - t1) / (t2 - t0)
    return (f2[0] + horizon_s * d1[0] + w * (d1[0] - d0[0]),
            f2[1] + horizon_s * d1[1] + w * (d1[1] - d0[1]),
            f2[2] + horizon_s * d1[2] + w * (d1[2] - d0[2]))


class HeldCommandForce:
    """The contact force eq. 29 and 35 cancel, predicted for the held command's slot.

    Args:
        horizon_s: h of ``held_slot_horizon_s``; 0 returns each sample unchanged.

    >>> force = HeldCommandForce(0.01)
    >>> [force.update(0.002 * k, (2.0 * k, 0.0, 0.0))[0] for k in range(3)]
    [0.0, 12.0, 14.0]
    """

    def __init__(self, horizon_s: float) -> None:
        if not (math.isfinite(horizon_s) and horizon_s >= 0.0):
            raise ControlParameterError('prediction horizon', horizon_s, '[0, inf) s')
        self.horizon_s = horizon_s
        self._samples: list[tuple[float, Vector3]] = []

    def reset(self) -> None:
        """Forget the samples: the next one restarts the prediction."""
        self._samples = []

    def update(self, t: float, f_e: Vector3) -> Vector3:
        """Take the sample F_e (N) at t (s); return the force predicted h after it.

        A sample at or before the newest one (a re-published state) is not taken again; a gap
        of more than ``RESTART_RATIO`` sample periods restarts from the new sample.
        """
        if self.horizon_s == 0.0:
            return f_e
        samples = self._samples
        if samples:
            gap = t - samples[-1][0]
            if gap <= 0.0:
                return quadratic_extrapolation(samples, self.horizon_s)
            if len(samples) >= 2 and gap > RESTART_RATIO * (samples[-1][0] - samples[-2][0]):
                samples.clear()
        samples.append((t, f_e))
        if len(samples) > 3:
            del samples[0]
        return quadratic_extrapolation(samples, self.horizon_s)
