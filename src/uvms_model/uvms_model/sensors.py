"""Wrist force/torque sensor: Gaussian noise, range saturation, optional low-pass (JR3-like).

Convention: the sensor reports the wrench the end effector exerts ON the environment (the
paper's F_e), in ft_sensor_link, which sits at the tip of link 3 with ee_link's axes; pushing
on the wall reads positive along the wall's outward direction. Order of effects: true
wrench + noise (std = ``noise_fraction`` x range per axis, paper Case II: 0.1 %), clipped
to +-range (the converter saturates), then the optional first-order low-pass (cut-off
``cutoff_hz``), as a JR3's digital filter stages follow its converter.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uvms_model.errors import StateError
from uvms_model.parameters import SensorParameters

FloatArray = NDArray[np.float64]


def _triple(name: str, value: ArrayLike) -> FloatArray:
    array = np.asarray(value, dtype=float)
    if array.shape != (3,):
        raise StateError(f'{name} must have shape (3,), got {array.shape}')
    # A finite sum is the cheap test (a huge finite sum may overflow: then look again).
    if not math.isfinite(sum(array.tolist())) and not np.isfinite(array).all():
        raise StateError(f'{name} must be finite, got {array.tolist()!r}')
    return array


def contact_wrench_in_sensor_frame(
    rot_ned_from_sensor: ArrayLike,
    force_ned: ArrayLike,
    lever_ned: ArrayLike | None = None,
) -> tuple[FloatArray, FloatArray]:
    """True wrench (force, torque) in ft_sensor_link of a contact force given in map_ned.

    Args:
        rot_ned_from_sensor: Orientation of ft_sensor_link in map_ned (3, 3).
        force_ned: Force exerted by the end effector on the environment, map_ned (3,) (N).
        lever_ned: Contact point minus sensor origin, map_ned (3,) (m); None for zero (the
            contact is at the sensor origin, the tip of link 3).

    Returns:
        (force (3,) in N, torque (3,) in N m), both in ft_sensor_link.
    """
    rot = np.asarray(rot_ned_from_sensor, dtype=float)
    if rot.shape != (3, 3):
        raise StateError(f'rot_ned_from_sensor must have shape (3, 3), got {rot.shape}')
    f = _triple('force_ned', force_ned)
    torque_ned = np.zeros(3) if lever_ned is None else np.cross(_triple('lever_ned', lever_ned), f)
    return rot.T @ f, rot.T @ torque_ned


class ForceTorqueSensor:
    """Six-axis wrist sensor with seeded noise, saturation and an optional low-pass filter.

    Deterministic for a given seed: the noise comes from ``numpy.random.Generator(PCG64)``.

    Example:
        >>> sensor = ForceTorqueSensor(SensorParameters(noise_fraction=0.001), seed=7)
        >>> force, torque = sensor.measure([150.0, 0.0, 0.0], [0.0, 0.0, 0.0], dt=1e-3)
    """

    def __init__(self, params: SensorParameters | None = None, seed: int | None = None) -> None:
        self.params = params if params is not None else SensorParameters()
        self._range = np.concatenate(
            (np.array(self.params.force_range_n), np.array(self.params.torque_range_n_m))
        )
        self._low = -self._range
        self._std = self.params.noise_fraction * self._range
        self.reset(seed)

    def reset(self, seed: int | None = None) -> None:
        """Restart the noise sequence (``sensor.seed`` if seed is None) and clear the filter."""
        self._seed = self.params.seed if seed is None else int(seed)
        self._rng = np.random.default_rng(self._seed)
        self._filtered: FloatArray | None = None

    @property
    def noise_std(self) -> FloatArray:
        """Noise standard deviation per axis (6,): force (N) then torque (N m)."""
        return self._std.copy()

    @property
    def full_scale(self) -> FloatArray:
        """Range per axis (6,): force (N) then torque (N m)."""
        return self._range.copy()

    def measure(
        self, force: ArrayLike, torque: ArrayLike, dt: float | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """One reading of the true wrench (force N, torque N m) given in ft_sensor_link.

        Args:
            force: True force (3,) in ft_sensor_link (N).
            torque: True torque (3,) in ft_sensor_link (N m).
            dt: Time since the previous reading (s); required when ``cutoff_hz`` > 0.

        Returns:
            (force (3,), torque (3,)) as read, noisy, saturated and filtered.

        Raises:
            StateError: For a wrong shape or non-finite input, or a missing dt with filter.
        """
        wrench = np.concatenate((_triple('force', force), _triple('torque', torque)))
        if self.params.noise_fraction > 0.0:
            wrench = wrench + self._std * self._rng.standard_normal(6)
        wrench = np.minimum(np.maximum(wrench, self._low), self._range)  # np.clip, cheaper
        if self.params.cutoff_hz > 0.0:
            if dt is None or not math.isfinite(dt) or dt <= 0.0:
                raise StateError(
                    f'dt must be a positive number of seconds when filtering, got {dt!r}'
                )
            if self._filtered is None:
                self._filtered = wrench
            else:
                alpha = 1.0 - math.exp(-2.0 * math.pi * self.params.cutoff_hz * dt)
                self._filtered = self._filtered + alpha * (wrench - self._filtered)
            wrench = self._filtered
        return wrench[:3].copy(), wrench[3:].copy()
