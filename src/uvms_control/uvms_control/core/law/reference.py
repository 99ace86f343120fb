"""Reference generators: the paper's half-circle path and the contact-force set-point.

Paper sec. 5.1-5.2: a circular trajectory of radius 0.1 m in the task space "with zero
initial velocity and acceleration", toward the wall, down along it and back (Fig. 7), and a
desired contact force of 150 N.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from uvms_control.core.errors import ControlParameterError

FloatArray = npt.NDArray[np.float64]


def quintic_time_scaling(sigma: float) -> tuple[float, float, float]:
    """Quintic time scaling s(σ) = 10σ³ - 15σ⁴ + 6σ⁵ and its first two derivatives.

    s, ds/dσ and d²s/dσ² are 0, 0, 0 at σ = 0 and 1, 0, 0 at σ = 1 (rest to rest with zero
    acceleration at both ends); σ is clipped to [0, 1].

    Example:
        >>> quintic_time_scaling(0.5)
        (0.5, 1.875, 0.0)
    """
    if sigma <= 0.0:
        return 0.0, 0.0, 0.0
    if sigma >= 1.0:
        return 1.0, 0.0, 0.0
    s2 = sigma * sigma
    s3 = s2 * sigma
    return (
        s3 * (10.0 - 15.0 * sigma + 6.0 * s2),
        s2 * (30.0 - 60.0 * sigma + 30.0 * s2),
        sigma * (60.0 - 180.0 * sigma + 120.0 * s2),
    )


def _unit(name: str, vector: npt.ArrayLike) -> FloatArray:
    v = np.asarray(vector, dtype=np.float64).reshape(-1)
    norm = float(np.linalg.norm(v)) if v.size == 3 else 0.0
    if v.size != 3 or not np.all(np.isfinite(v)) or norm < 1e-9:
        raise ControlParameterError(name, list(v), 'a finite non-zero 3-vector')
    unit: FloatArray = v / norm
    return unit


class HalfCircleReference:
    """Half circle X_d(s) = c + r (sin(πs) n - cos(πs) d), c = X0 + r d (paper Fig. 7).

    Starts at X0 at rest, moves along n (toward the wall) and d (down in map_ned) to
    X0 + r n + r d at s = 1/2, and ends at rest at X0 + 2 r d. The arc parameter follows a
    quintic time scaling over ``duration`` after ``start_delay``, so velocity and
    acceleration are zero at both ends, as the paper asks.

    Args:
        radius: r (m).
        duration: time to run the half circle (s).
        start_delay: time at X0 before the motion starts (s).
        toward: n, direction toward the environment in map_ned (default +x, the wall normal).
        sweep: d, direction of the diameter in map_ned (default +z, down); its component
            along n is removed.

    Example:
        >>> ref = HalfCircleReference(radius=0.1, duration=10.0, start_delay=0.0)
        >>> x_d, _, _ = ref.evaluate(5.0, np.zeros(3))
        >>> np.round(x_d, 6).tolist()
        [0.1, 0.0, 0.1]
    """

    def __init__(
        self,
        radius: float = 0.1,
        duration: float = 20.0,
        start_delay: float = 2.0,
        toward: npt.ArrayLike = (1.0, 0.0, 0.0),
        sweep: npt.ArrayLike = (0.0, 0.0, 1.0),
    ) -> None:
        if not (math.isfinite(radius) and radius > 0.0):
            raise ControlParameterError('reference.radius_m', radius, '(0, inf) m')
        if not (math.isfinite(duration) and duration > 0.0):
            raise ControlParameterError('reference.duration_s', duration, '(0, inf) s')
        if not (math.isfinite(start_delay) and start_delay >= 0.0):
            raise ControlParameterError('reference.start_delay_s', start_delay, '[0, inf) s')
        n = _unit('hybrid.force_direction', toward)
        d = _unit('reference.sweep_direction', sweep)
        d = d - float(n @ d) * n
        if float(np.linalg.norm(d)) < 1e-6:
            raise ControlParameterError(
                'reference.sweep_direction',
                list(np.asarray(sweep)),
                'a direction not parallel to n',
            )
        self.radius = radius
        self.duration = duration
        self.start_delay = start_delay
        self.toward: FloatArray = n
        self.sweep: FloatArray = d / float(np.linalg.norm(d))
        self._n: list[float] = self.toward.tolist()
        self._d: list[float] = self.sweep.tolist()

    def evaluate(self, t: float, start: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Reference X_d, X_d_dot, X_d_ddot (m, m/s, m/s²) at time t after the start.

        Args:
            t: time since the reference started (s).
            start: X0, the starting end-effector position in map_ned (m).
        """
        values = np.array(self.evaluate_floats(t, start.tolist())).reshape(3, 3)
        return values[0], values[1], values[2]

    def evaluate_floats(self, t: float, start: Sequence[float]) -> list[float]:
        """``evaluate`` as nine plain floats [X_d, X_d_dot, X_d_ddot] (the control step's path)."""
        s, ds, dds = quintic_time_scaling((t - self.start_delay) / self.duration)
        s_dot = ds / self.duration
        s_ddot = dds / (self.duration * self.duration)
        angle = math.pi * s
        sin_a, cos_a = math.sin(angle), math.cos(angle)
        r = self.radius
        # Position, velocity and acceleration along n and d.
        p_n, p_d = r * sin_a, r * (1.0 - cos_a)
        v_n, v_d = r * math.pi * cos_a * s_dot, r * math.pi * sin_a * s_dot
        a_n = r * math.pi * (cos_a * s_ddot - math.pi * sin_a * s_dot * s_dot)
        a_d = r * math.pi * (sin_a * s_ddot + math.pi * cos_a * s_dot * s_dot)
        (n0, n1, n2), (d0, d1, d2) = self._n, self._d
        x0, x1, x2 = start
        return [
            x0 + (p_n * n0 + p_d * d0),
            x1 + (p_n * n1 + p_d * d1),
            x2 + (p_n * n2 + p_d * d2),
            v_n * n0 + v_d * d0,
            v_n * n1 + v_d * d1,
            v_n * n2 + v_d * d2,
            a_n * n0 + a_d * d0,
            a_n * n1 + a_d * d1,
            a_n * n2 + a_d * d2,
        ]


class ForcePhase(enum.IntEnum):
    """State of the force set-point."""

    IDLE = 0
    RAMP_UP = 1
    RELEASE = 2


@dataclass(frozen=True)
class ForceSetpointSample:
    """Desired normal force and its derivatives (eq. 39 needs F_d, F_d_dot, F_d_ddot)."""

    f_d: float
    f_d_dot: float
    f_d_ddot: float
    phase: ForcePhase


class ForceSetpoint:
    """Desired contact force along n: a smooth ramp to the set-point once contact is made.

    The ramp starts when the measured normal force first reaches ``contact_threshold``
    (model-free contact detection: no wall position is assumed), from the force measured at
    that instant, and reaches ``magnitude`` after ``ramp_time`` along a quintic, so F_d, its
    first and its second derivative are continuous (eq. 39 feeds F_d_ddot forward). Ramping
    from the measured force avoids the force-error step that a set-point active from the start
    would put into the PID at first contact; the fuzzy switch keeps the impedance law in
    charge until the contact force has grown.

    With ``start_immediately`` the ramp starts from ``start_force`` (zero unless a task with a
    force takes over from another) at the first update instead, without
    waiting for contact: the pure hybrid law (W = 0) needs it, since along n it controls only
    force and would never approach the wall with a zero set-point.

    The set-point is released (ramped to zero) when the position reference, moving away from
    the surface (n·Ẋ_d < 0), retreats behind the point where contact was detected
    (n·X_d < n·X_contact): the task reference then says the end effector should be off the
    surface (the paper's C' -> C). Requiring the reference to recede keeps a reference that
    merely trails the end effector at the moment of contact from releasing at once. The
    set-point re-arms once the measured force falls below half the threshold.

    Example:
        >>> fs = ForceSetpoint(magnitude=150.0, ramp_time=2.0, contact_threshold=5.0)
        >>> fs.update(0.0, 0.0, 1.0, 0.9, 0.0).f_d
        0.0
    """

    def __init__(
        self,
        magnitude: float,
        ramp_time: float,
        contact_threshold: float,
        start_immediately: bool = False,
        start_force: float = 0.0,
    ) -> None:
        if not (math.isfinite(magnitude) and magnitude > 0.0):
            raise ControlParameterError('force_n', magnitude, '(0, inf) N')
        if not (math.isfinite(ramp_time) and ramp_time > 0.0):
            raise ControlParameterError('force_ramp_s', ramp_time, '(0, inf) s')
        if not (math.isfinite(contact_threshold) and 0.0 < contact_threshold < magnitude):
            raise ControlParameterError(
                'force.contact_threshold_n', contact_threshold, f'(0, {magnitude}) N'
            )
        self.magnitude = magnitude
        self.ramp_time = ramp_time
        self.contact_threshold = contact_threshold
        self.start_immediately = start_immediately
        self.start_force = start_force
        self.reset()

    def reset(self) -> None:
        """Return to the idle state (no contact seen yet)."""
        self.phase = ForcePhase.IDLE
        self._armed = True
        self._t0 = 0.0
        self._f0 = 0.0
        self._f1 = 0.0
        self._x_contact: float | None = None
        self._started = False
        self._final = False
        self._duration = self.ramp_time

    @property
    def in_contact_since(self) -> float | None:
        """Time at which the current contact was detected, or None."""
        return self._t0 if self.phase == ForcePhase.RAMP_UP else None

    def _ramp(self, t: float) -> tuple[float, float, float]:
        s, ds, dds = quintic_time_scaling((t - self._t0) / self._duration)
        span = self._f1 - self._f0
        return (
            self._f0 + span * s,
            span * ds / self._duration,
            span * dds / (self._duration * self._duration),
        )

    def desired(self, t: float) -> float:
        """F_d at t (N) without advancing the set-point; 0 while idle."""
        return 0.0 if self.phase == ForcePhase.IDLE else self._ramp(t)[0]

    @property
    def final(self) -> bool:
        """Released for good: the set-point never arms again (``release(final=True)``)."""
        return self._final

    def release(self, t: float, ramp_s: float | None = None, final: bool = False) -> None:
        """Ramp F_d from its value at t (s) down to zero over ``ramp_s`` (s; default ramp_time).

        Ends a task's force (path done, cancel, safety limit); the ramp itself does nothing
        while idle. ``final``: the set-point stays at zero after the ramp and never re-arms on
        a contact (the end of a task, a retreat), where a plain release re-arms once the force
        has fallen under half the threshold (the path leaving the surface and coming back).
        """
        self._final = self._final or final
        if self.phase != ForcePhase.RAMP_UP:
            return
        f_now = self._ramp(t)[0]
        self.phase = ForcePhase.RELEASE
        self._t0, self._f0, self._f1 = t, f_now, 0.0
        self._duration = self.ramp_time if ramp_s is None else ramp_s

    def update(
        self,
        t: float,
        f_normal: float,
        x_normal: float,
        x_d_normal: float,
        x_d_dot_normal: float,
    ) -> ForceSetpointSample:
        """Advance the set-point to time t and return F_d and its derivatives (N, N/s, N/s²).

        Args:
            t: time (s).
            f_normal: measured contact force along n, n·F_e (N).
            x_normal: end-effector position along n, n·X (m).
            x_d_normal: position reference along n, n·X_d (m).
            x_d_dot_normal: reference velocity along n, n·Ẋ_d (m/s).
        """
        in_contact = f_normal >= self.contact_threshold
        if self.phase == ForcePhase.IDLE and not self._final:
            if not self._armed and f_normal < 0.5 * self.contact_threshold:
                self._armed = True
            if self.start_immediately and not self._started:
                self.phase = ForcePhase.RAMP_UP
                self._t0, self._f0, self._f1 = t, self.start_force, self.magnitude
                self._duration = self.ramp_time
                self._x_contact = x_normal if in_contact else None
            elif self._armed and in_contact:
                self.phase = ForcePhase.RAMP_UP
                self._t0, self._f0, self._f1 = t, min(f_normal, self.magnitude), self.magnitude
                self._duration = self.ramp_time
                self._x_contact = x_normal
            self._started = True
        if self.phase == ForcePhase.RAMP_UP and self._x_contact is None and in_contact:
            self._x_contact = x_normal
        if (
            self.phase == ForcePhase.RAMP_UP
            and self._x_contact is not None
            and x_d_dot_normal < 0.0
            and x_d_normal < self._x_contact
        ):
            self.release(t)
        if self.phase == ForcePhase.IDLE:
            sample = ForceSetpointSample(0.0, 0.0, 0.0, ForcePhase.IDLE)
        else:
            f_d, f_d_dot, f_d_ddot = self._ramp(t)
            sample = ForceSetpointSample(f_d, f_d_dot, f_d_ddot, self.phase)
            if self.phase == ForcePhase.RELEASE and t - self._t0 >= self._duration:
                self.phase = ForcePhase.IDLE
                self._armed = False
        return sample
