"""Discrete filters of the controller: the filtered ("dirty") derivative."""

from __future__ import annotations

import math

from uvms_control.core.errors import ControlParameterError


class DirtyDerivative:
    """Filtered derivative s / (τ s + 1), τ = 1 / (2π f_c), of a scalar signal, by backward Euler.

    The paper (sec. 6) warns that the force derivative of eq. 39 amplifies sensor noise. A
    derivative rolled off by a first-order low-pass at f_c differentiates the slow force
    trajectory and attenuates noise above f_c. Backward Euler is stable for any step, so it
    tolerates the irregular steps of the real-time trigger mode:

        y_k = (τ y_{k-1} + x_k - x_{k-1}) / (τ + Δt)

    The first sample initialises the filter with a zero derivative. Plain floats: it runs in
    the control step.

    Example:
        >>> f = DirtyDerivative(cutoff_hz=20.0)
        >>> for k in range(200):  # a ramp of 100 units/s sampled at 1 kHz
        ...     y = f.update(0.1 * k, 0.001)
        >>> round(y, 3)
        100.0
    """

    def __init__(self, cutoff_hz: float) -> None:
        if not (math.isfinite(cutoff_hz) and cutoff_hz > 0.0):
            raise ControlParameterError(
                'hybrid.force_derivative_cutoff_hz', cutoff_hz, '(0, inf) Hz'
            )
        self.tau = 1.0 / (2.0 * math.pi * cutoff_hz)
        self._x_prev = 0.0
        self._y = 0.0
        self._initialised = False

    def continue_from(self, other: DirtyDerivative) -> None:
        """Take over another filter's input and output (a new cut-off without a bump)."""
        self._x_prev, self._y, self._initialised = other._x_prev, other._y, other._initialised

    def reset(self) -> None:
        """Forget the past: the next sample restarts the filter."""
        self._initialised = False
        self._y = 0.0

    @property
    def value(self) -> float:
        """Last output (units of x per second)."""
        return self._y

    def update(self, x: float, dt: float) -> float:
        """Feed sample x taken dt seconds after the previous one; return the derivative."""
        if not self._initialised:
            self._x_prev = x
            self._initialised = True
            return self._y
        if dt <= 0.0:
            return self._y
        self._y = (self.tau * self._y + (x - self._x_prev)) / (self.tau + dt)
        self._x_prev = x
        return self._y
