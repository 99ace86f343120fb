"""Discrete filters of the controller: the filtered ("dirty") derivative."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from uvms_control.core.errors import ControlParameterError

FloatArray = npt.NDArray[np.float64]


class DirtyDerivative:
    """Filtered derivative s / (τ s + 1), τ = 1 / (2π f_c), by backward Euler.

    The paper (sec. 6) warns that the force derivative of eq. 39 amplifies sensor noise. A
    derivative rolled off by a first-order low-pass at f_c differentiates the slow force
    trajectory and attenuates noise above f_c. Backward Euler is stable for any step, so it
    tolerates the irregular steps of the real-time trigger mode:

        y_k = (τ y_{k-1} + x_k - x_{k-1}) / (τ + Δt)

    The first sample initialises the filter with a zero derivative.

    Example:
        >>> f = DirtyDerivative(cutoff_hz=20.0, size=1)
        >>> for k in range(200):  # a ramp of 100 units/s sampled at 1 kHz
        ...     y = f.update(np.array([0.1 * k]), 0.001)
        >>> round(float(y[0]), 3)
        100.0
    """

    def __init__(self, cutoff_hz: float, size: int = 3) -> None:
        if not (math.isfinite(cutoff_hz) and cutoff_hz > 0.0):
            raise ControlParameterError(
                'hybrid.force_derivative_cutoff_hz', cutoff_hz, '(0, inf) Hz'
            )
        self.tau = 1.0 / (2.0 * math.pi * cutoff_hz)
        self._x_prev = np.zeros(size)
        self._y = np.zeros(size)
        self._initialised = False

    def reset(self) -> None:
        """Forget the past: the next sample restarts the filter."""
        self._initialised = False
        self._y[:] = 0.0

    @property
    def value(self) -> FloatArray:
        """Last output (units of x per second)."""
        return self._y

    def update(self, x: FloatArray, dt: float) -> FloatArray:
        """Feed sample x taken dt seconds after the previous one; return the derivative."""
        if not self._initialised or dt <= 0.0:
            if not self._initialised:
                self._x_prev[:] = x
                self._initialised = True
            return self._y
        self._y = (self.tau * self._y + (x - self._x_prev)) / (self.tau + dt)
        self._x_prev[:] = x
        return self._y
