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

The quadratic weighs three 2 ms samples 11.1, -26.5 and 16.4 at h = 8.5 ms: a noisy sensor's
noise would enter eq. 29/35 about 33 times larger (the Alpha 5's 0.1 % wrist noise, 0.58 N,
as 19 N: the arm runs away). So the predicted increment p - F_e is weighed by how noisy the
samples are (``prediction_weight``): g = 1 / (1 + (G sigma / e)^2), G the quadratic's noise
gain, e a tolerance (N) and sigma the noise per axis, estimated from the samples' third
differences (0 on any quadratic, 20 sigma^2 for white noise) by their median absolute value
over the last ``NOISE_WINDOW`` samples (a kink of the real force, the contact's onset or a held
command's step, is an outlier there, not noise). A clean sensor gets the whole prediction
(g = 1 on a quadratic: the exact cancellation); a noisy one the measured force, as eq. 29 (at
the devices' rates with the robot's 0.1 % noise that holds: docs/hardware.md). Whatever the
noise, the noise the increment adds has a standard deviation of at most e / 2 (g G sigma peaks
at G sigma = e).

Out of contact a noisy sensor reads only its noise, and eq. 29 cancels it: held over a slot it
moves the arm (bluerov2_alpha5_free_motion: 6.7 mm off its path at the devices' rates against
2.8 mm at ideal devices). So where the measured force's magnitude is within a few sigma of 0
(``free_water_weight``: below 3 sigma, above 6 sigma the force as above, a smooth step between)
the mean of the samples over the last 2 h is cancelled instead (its noise 1 / sqrt(n) of one
sample's). In contact the force as above: any smoothing there lags the stiff wall's force
and the contact bounces (measured, docs/hardware.md). A clean sensor (sigma 0) never averages.

Pure Python, plain floats: it runs in the control step.
"""

from __future__ import annotations

import math
import statistics
from collections import deque

from uvms_control.core.errors import ControlParameterError

#: A gap between samples longer than this many of the first one restarts the prediction.
RESTART_RATIO = 5.0
#: Default tolerance e (N): the prediction's noise, G sigma, at which half the increment is used.
NOISE_TOLERANCE_N = 0.5
#: Default number of third differences whose median absolute value estimates the noise.
NOISE_WINDOW = 32
#: sigma of white noise per median absolute third difference f3 - 3 f2 + 3 f1 - f0: the third
#: difference of unit white noise is normal with variance 20, and a normal's median absolute
#: value is 0.6745 sigma.
MEDIAN_TO_SD = 1.0 / (0.6744897501960817 * math.sqrt(20.0))
#: Below this many noise sigmas of force magnitude the sensor reads free water (its noise).
FREE_WATER_SIGMAS = 3.0
#: Above this many the force is a contact's, cancelled as measured (and predicted).
CONTACT_SIGMAS = 6.0

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


def quadratic_increment_noise_gain(times_s: tuple[float, float, float], horizon_s: float) -> float:
    """Noise gain G of the increment ``quadratic_extrapolation`` adds to the newest sample.

    The increment p - f2 is a weighted sum of the three samples; G is the root of the sum of
    the squared weights: the standard deviation of the increment per unit of white noise.

    Args:
        times_s: The three sample times t0 < t1 < t2 (s).
        horizon_s: How far past t2 (s).

    >>> round(quadratic_increment_noise_gain((0.0, 0.002, 0.004), 0.0085), 1)
    32.7
    >>> quadratic_increment_noise_gain((0.0, 0.002, 0.004), 0.0)
    0.0
    """
    t0, t1, t2 = times_s
    step1, step0 = t2 - t1, t1 - t0
    w = horizon_s * (t2 + horizon_s - t1) / (t2 - t0)
    a2 = (horizon_s + w) / step1
    a0 = w / step0
    return math.sqrt(a2 * a2 + (a2 + a0) ** 2 + a0 * a0)


def third_difference(times_s: tuple[float, ...], values: tuple[float, ...]) -> float:
    """f3 - 3 f2 + 3 f1 - f0 of four samples, as it would be on an even grid of their span.

    6 d^3 times the third divided difference, d their mean spacing: on an even grid exactly
    the third difference; 0 on any quadratic however uneven the times (a sensor whose steps
    skip a sample: the gap is no noise).

    >>> third_difference((0.0, 1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 6.0))
    6.0
    >>> third_difference((0.0, 1.0, 3.0, 4.0), (0.0, 1.0, 9.0, 16.0))  # t^2, a skipped sample
    0.0
    """
    t0, t1, t2, t3 = times_s
    f0, f1, f2, f3 = values
    a, b, c = (f1 - f0) / (t1 - t0), (f2 - f1) / (t2 - t1), (f3 - f2) / (t3 - t2)
    divided = ((c - b) / (t3 - t1) - (b - a) / (t2 - t0)) / (t3 - t0)
    spacing = (t3 - t0) / 3.0
    return 6.0 * spacing ** 3 * divided


def prediction_weight(noise_sd: float, noise_gain: float, tolerance_n: float) -> float:
    """Weight g of the predicted increment: 1 / (1 + (G sigma / e)^2).

    Args:
        noise_sd: Estimated noise standard deviation of the samples, sigma (N).
        noise_gain: Noise gain G of the increment (``quadratic_increment_noise_gain``).
        tolerance_n: e (N): the increment's noise G sigma at which half of it is used; the
            weighted increment's noise g G sigma is at most e / 2 whatever sigma.

    >>> prediction_weight(0.0, 32.8, 0.5)
    1.0
    >>> prediction_weight(0.5 / 32.8, 32.8, 0.5)
    0.5
    >>> prediction_weight(0.58, 32.8, 0.5) < 1e-3
    True
    """
    ratio = noise_gain * noise_sd / tolerance_n
    return 1.0 / (1.0 + ratio * ratio)


def free_water_weight(force_n: float, noise_sd_n: float) -> float:
    """Weight of the measured (and predicted) force against the free-water mean: 0 to 1.

    A smooth step (3 u^2 - 2 u^3) of the force's magnitude from ``FREE_WATER_SIGMAS`` to
    ``CONTACT_SIGMAS`` noise sigmas; 1 for a clean sensor (sigma 0).

    Args:
        force_n: Magnitude of the measured force (N).
        noise_sd_n: Magnitude of the estimated noise sigma over the three axes (N).

    >>> free_water_weight(0.5, 0.7), free_water_weight(5.0, 0.7), free_water_weight(0.5, 0.0)
    (0.0, 1.0, 1.0)
    >>> round(free_water_weight(3.15, 0.7), 6)
    0.5
    """
    if noise_sd_n == 0.0:
        return 1.0
    u = (force_n - FREE_WATER_SIGMAS * noise_sd_n) / (
        (CONTACT_SIGMAS - FREE_WATER_SIGMAS) * noise_sd_n)
    u = min(max(u, 0.0), 1.0)
    return u * u * (3.0 - 2.0 * u)


class HeldCommandForce:
    """The contact force eq. 29 and 35 cancel, predicted for the held command's slot.

    The measured F_e plus the quadratic's increment to h after it, per axis weighed by
    ``prediction_weight`` with the noise estimated from the samples' third differences (their
    median absolute value over the last ``noise_window`` of them); out of contact
    (``free_water_weight``) the mean of the samples of the last ``free_water_window_s``
    instead. Until four samples have come (no noise estimate yet) the measured force, as
    eq. 29.

    Args:
        horizon_s: h of ``held_slot_horizon_s``; 0 returns each sample unchanged.
        noise_tolerance_n: e of ``prediction_weight`` (N).
        noise_window: How many third differences the noise estimate takes.
        free_water_window_s: Span of the free-water mean (s); None: 2 h (at least the held
            slot, h being the latency and half the slot).

    >>> force = HeldCommandForce(0.01)
    >>> [force.update(0.002 * k, (2.0 * k * k, 0.0, 0.0))[0] for k in range(5)]
    [0.0, 2.0, 8.0, 128.0, 162.0]
    """

    def __init__(self, horizon_s: float, noise_tolerance_n: float = NOISE_TOLERANCE_N,
                 noise_window: int = NOISE_WINDOW,
                 free_water_window_s: float | None = None) -> None:
        if not (math.isfinite(horizon_s) and horizon_s >= 0.0):
            raise ControlParameterError('prediction horizon', horizon_s, '[0, inf) s')
        if not (math.isfinite(noise_tolerance_n) and noise_tolerance_n > 0.0):
            raise ControlParameterError('prediction noise tolerance', noise_tolerance_n,
                                        '(0, inf) N')
        if noise_window < 1:
            raise ControlParameterError('prediction noise window', noise_window, '[1, inf)')
        self.horizon_s = horizon_s
        self.noise_tolerance_n = noise_tolerance_n
        self.free_water_window_s = (2.0 * horizon_s if free_water_window_s is None
                                    else free_water_window_s)
        self._recent: deque[tuple[float, Vector3]] = deque()
        self._samples: list[tuple[float, Vector3]] = []
        self._third: tuple[deque[float], deque[float], deque[float]] = (
            deque(maxlen=noise_window), deque(maxlen=noise_window), deque(maxlen=noise_window))
        self._last: Vector3 = (0.0, 0.0, 0.0)

    @property
    def noise_sd(self) -> Vector3:
        """The estimated noise standard deviation per axis (N); 0 before any estimate."""
        a, b, c = self._third
        if not a:
            return (0.0, 0.0, 0.0)
        return (MEDIAN_TO_SD * statistics.median(a), MEDIAN_TO_SD * statistics.median(b),
                MEDIAN_TO_SD * statistics.median(c))

    def reset(self) -> None:
        """Forget the samples and the noise estimate: the next sample restarts both."""
        self._samples = []
        self._recent.clear()
        for third in self._third:
            third.clear()

    def update(self, t: float, f_e: Vector3, now: float | None = None) -> Vector3:
        """Take the sample F_e (N) stamped t (s); return the force predicted h after ``now``.

        ``now`` (s, the step's time; None: t) counts how old the sample already is: a sensor
        streaming on its own clock gives a step no new sample, one or two (measured on the
        twin stand: 29, 45 and 23 % of the steps, the newest 1.4-11 ms old), so the samples
        are taken at their own stamps and the prediction reaches h past the step, not past
        the sample. A sample at or before the newest one (no new sample since the last step,
        a re-published state) is not taken again; a gap of more than ``RESTART_RATIO`` sample
        periods restarts the prediction from the new sample (the noise estimate is kept: the
        sensor's noise has not changed).
        """
        if self.horizon_s == 0.0:
            return f_e
        samples = self._samples
        if samples and t <= samples[-1][0]:  # no new sample since the last step
            if now is None or len(samples) < 4:
                return self._last
            return self._predicted(self.horizon_s + max(now - samples[-1][0], 0.0))
        if len(samples) >= 2 and t - samples[-1][0] > RESTART_RATIO * (
                samples[-1][0] - samples[-2][0]):
            samples.clear()
        samples.append((t, f_e))
        recent = self._recent
        recent.append((t, f_e))
        while recent[0][0] < t - self.free_water_window_s:
            recent.popleft()
        if len(samples) > 4:
            del samples[0]
        if len(samples) < 4:
            self._last = f_e
            return f_e
        times = tuple(ts for ts, _ in samples)
        for i, third in enumerate(self._third):
            third.append(abs(third_difference(times, tuple(f[i] for _, f in samples))))
        return self._predicted(self.horizon_s + (0.0 if now is None else max(now - t, 0.0)))

    def _predicted(self, horizon_s: float) -> Vector3:
        """The newest sample plus its weighed increment ``horizon_s`` after it (`update`)."""
        samples, recent = self._samples, self._recent
        (_, _), (t0, _), (t1, _), (t2, fd) = samples
        gain = quadratic_increment_noise_gain((t0, t1, t2), horizon_s)
        p = quadratic_extrapolation(samples[1:], horizon_s)
        e = self.noise_tolerance_n
        s0, s1, s2 = self.noise_sd
        c0 = fd[0] + prediction_weight(s0, gain, e) * (p[0] - fd[0])
        c1 = fd[1] + prediction_weight(s1, gain, e) * (p[1] - fd[1])
        c2 = fd[2] + prediction_weight(s2, gain, e) * (p[2] - fd[2])
        w = free_water_weight(math.sqrt(fd[0] * fd[0] + fd[1] * fd[1] + fd[2] * fd[2]),
                              math.sqrt(s0 * s0 + s1 * s1 + s2 * s2))
        if w < 1.0:
            n = len(recent)
            m0 = sum(f[0] for _, f in recent) / n
            m1 = sum(f[1] for _, f in recent) / n
            m2 = sum(f[2] for _, f in recent) / n
            c0, c1, c2 = m0 + w * (c0 - m0), m1 + w * (c1 - m1), m2 + w * (c2 - m2)
        self._last = (c0, c1, c2)
        return self._last
