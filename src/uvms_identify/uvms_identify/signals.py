"""Signals on one time grid: resampling, Savitzky-Golay smoothing and differentiation."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_filter  # type: ignore[import-untyped]

FloatArray = NDArray[np.float64]


def resample(t_s: FloatArray, values: FloatArray, grid_s: FloatArray) -> FloatArray:
    """Linear interpolation of ``values`` (N, k) sampled at ``t_s`` onto ``grid_s``."""
    values = np.asarray(values, dtype=float)
    flat = values.reshape(len(t_s), -1)
    out = np.column_stack([np.interp(grid_s, t_s, column) for column in flat.T])
    result: FloatArray = out.reshape((len(grid_s), *values.shape[1:]))
    return result


def smooth_and_differentiate(values: FloatArray, dt_s: float, window_s: float,
                             order: int = 3) -> tuple[FloatArray, FloatArray]:
    """Savitzky-Golay smoothed values and first derivative along axis 0 (same shape).

    Args:
        values: Uniformly sampled signal (N, k).
        dt_s: Sample period (s).
        window_s: Window length (s), rounded to an odd number of samples > order.
        order: Polynomial order.
    """
    window = max(round(window_s / dt_s) | 1, (order + 2) | 1)
    smooth = savgol_filter(values, window, order, axis=0, mode='interp')
    derivative = savgol_filter(values, window, order, deriv=1, delta=dt_s, axis=0,
                               mode='interp')
    return np.asarray(smooth, float), np.asarray(derivative, float)


def quaternion_to_matrix(q_xyzw: FloatArray) -> FloatArray:
    """Rotation matrices (N, 3, 3) of unit quaternions (N, 4) given as x, y, z, w."""
    q = np.asarray(q_xyzw, dtype=float)
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    x, y, z, w = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], axis=1)


def euler_zyx(rotations: FloatArray) -> FloatArray:
    """Roll, pitch, yaw (N, 3) (rad) of rotation matrices (N, 3, 3), R = Rz Ry Rx."""
    r = np.asarray(rotations, dtype=float)
    roll = np.arctan2(r[:, 2, 1], r[:, 2, 2])
    pitch = -np.arcsin(np.clip(r[:, 2, 0], -1.0, 1.0))
    yaw = np.arctan2(r[:, 1, 0], r[:, 0, 0])
    return np.column_stack([roll, pitch, yaw])


def rpy_matrix(roll: float, pitch: float, yaw: float) -> FloatArray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) (3, 3)."""
    cr, sr, cp, sp = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])
