"""The planned generalized force of one experiment over time (levels held between changes).

Two shapes, both scaled by the axis' largest force ``maximum`` (``uvms_identify.plan``):

- ``steps_and_chirp`` (every axis; with ``level`` roll, pitch, yaw): steps of alternating
  sign and rising
  amplitude (steady speeds at several levels for the quadratic damping, a sign change every
  step keeps the excursion small), a free decay, a chirp about a static offset (+ then -:
  the |v| v regressor is only consistent with an offset, arXiv 2204.04973; the chirp
  separates added mass from damping) and a final free decay.
- ``doublets`` (with ``level``: surge, sway, heave): the excursion bound (the DVL's bottom
  lock) holds the heave steps to 17 N and 0.22 m/s, where the quadratic damping is a third
  of the drag (through the twin stand it came out 28 % off). Doublets (+L for T, -L for
  2 T, +L for T) return to the start after each, so a large force fits in a small
  excursion: the vehicle reaches several steady speeds within T (the time constant
  (m + A) / (2 d_q |v|) is about 0.3 s in heave and 0.4 s in surge at the planned speeds).
  A chirp about zero follows (an offset would carry the vehicle away).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

STEP_LEVELS = (0.3, -0.3, 0.6, -0.6, 1.0, -1.0, 0.45, -0.45)
STEP_S = 2.5
DECAY_S = 3.0
CHIRP_S = 16.0
CHIRP_OFFSET = 0.5
CHIRP_AMPLITUDE = 0.4
CHIRP_HZ = (0.1, 0.6)
CHIRP_STEP_S = 0.2
FINAL_DECAY_S = 4.0
DURATION_S = len(STEP_LEVELS) * STEP_S + DECAY_S + CHIRP_S + FINAL_DECAY_S
#: Heave doublets: amplitude (fraction of the largest force) and half-length T (s) of each.
DOUBLETS = ((0.35, 1.2), (0.6, 1.0), (1.0, 0.8), (0.8, 0.9), (0.5, 1.1), (1.0, 0.7))
HEAVE_CHIRP_AMPLITUDE = 0.8
HEAVE_CHIRP_HZ = (0.4, 1.2)


def _chirp(times: list[float], levels: list[float], t: float, maximum: float, offset: float,
           amplitude: float, hz: tuple[float, float], duration_s: float) -> float:
    """Append a linear chirp about ``+offset`` then ``-offset``; the time after it."""
    phase = 0.0
    f0, f1 = hz
    steps = round(duration_s / CHIRP_STEP_S)
    for k in range(steps):
        fraction = k / steps
        frequency = f0 + (f1 - f0) * fraction
        sign = 1.0 if fraction < 0.5 else -1.0
        times.append(t)
        levels.append(maximum * (sign * offset + amplitude * math.sin(phase)))
        phase += 2.0 * math.pi * frequency * CHIRP_STEP_S
        t += CHIRP_STEP_S
    return t


def steps_and_chirp(maximum: float) -> tuple[FloatArray, FloatArray]:
    """Level start times (s) and generalized forces of the steps-and-chirp experiment."""
    times: list[float] = []
    levels: list[float] = []
    t = 0.0
    for level in STEP_LEVELS:
        times.append(t)
        levels.append(level * maximum)
        t += STEP_S
    times.append(t)
    levels.append(0.0)
    t += DECAY_S
    t = _chirp(times, levels, t, maximum, CHIRP_OFFSET, CHIRP_AMPLITUDE, CHIRP_HZ, CHIRP_S)
    times.append(t)
    levels.append(0.0)
    return np.array(times), np.array(levels)


def doublets(maximum: float) -> tuple[FloatArray, FloatArray]:
    """Level start times (s) and forces of the doublets experiment (``DURATION_S`` long)."""
    times: list[float] = []
    levels: list[float] = []
    t = 0.0
    for k, (amplitude, half_s) in enumerate(DOUBLETS):
        sign = 1.0 if k % 2 == 0 else -1.0  # alternate the first direction
        for share, length in ((1.0, half_s), (-1.0, 2.0 * half_s), (1.0, half_s)):
            times.append(t)
            levels.append(sign * share * amplitude * maximum)
            t += length
        times.append(t)
        levels.append(0.0)
        t += 1.5  # a free decay after each
    chirp_s = DURATION_S - t - FINAL_DECAY_S
    t = _chirp(times, levels, t, maximum, 0.0, HEAVE_CHIRP_AMPLITUDE, HEAVE_CHIRP_HZ, chirp_s)
    times.append(t)
    levels.append(0.0)
    return np.array(times), np.array(levels)
