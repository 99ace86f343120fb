"""Health of the estimate for /diagnostics: DVL lost, position covariance growing (pure)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from uvms_navigation.eskf import ErrorStateEkf

OK, WARN, ERROR = 0, 1, 2
"""Levels, as diagnostic_msgs/DiagnosticStatus numbers them."""


@dataclass(frozen=True)
class HealthLimits:
    """When the estimate is reported degraded.

    Attributes:
        dvl_timeout_s: Time without an accepted DVL velocity after which the DVL is lost (s).
        position_sigma_warn_m: Horizontal position std above which the estimate warns (m).
        position_sigma_error_m: Horizontal position std above which it is an error (m).
    """

    dvl_timeout_s: float = 2.0
    position_sigma_warn_m: float = 0.5
    position_sigma_error_m: float = 2.0


class HealthMonitor:
    """Judges the filter once per report: DVL age, horizontal sigma, growth of the velocity one.

    Without a position fix the horizontal position sigma of dead reckoning always grows
    slowly, which is no fault; a velocity sigma growing without the DVL is, and so is a
    position sigma above the limits.
    """

    def __init__(self, limits: HealthLimits | None = None) -> None:
        self.limits = limits if limits is not None else HealthLimits()
        self._last_sigma: float | None = None

    def report(self, ekf: ErrorStateEkf) -> tuple[int, str, dict[str, float | int | bool]]:
        """Level, one-line message and values (sigmas in m and m/s, DVL age in s)."""
        sigma_h = math.sqrt(max(float(ekf.cov[0, 0]), float(ekf.cov[1, 1])))
        sigma_v = math.sqrt(float(max(ekf.cov[3, 3], ekf.cov[4, 4], ekf.cov[5, 5])))
        age = (math.inf if ekf.last_dvl_ns is None else (ekf.t_ns - ekf.last_dvl_ns) * 1e-9)
        dvl_lost = age > self.limits.dvl_timeout_s
        # With the DVL the velocity sigma saws between its samples; only without it does a
        # rise from one report to the next mean growth.
        growing = dvl_lost and self._last_sigma is not None and sigma_v > self._last_sigma
        self._last_sigma = sigma_v
        values: dict[str, float | int | bool] = {
            'position_sigma_m': sigma_h, 'velocity_sigma_m_s': sigma_v,
            'dvl_age_s': age, 'dvl_lost': dvl_lost, 'covariance_growing': growing,
            'dvl_rejected': ekf.dvl_rejected}
        if sigma_h > self.limits.position_sigma_error_m:
            return ERROR, f'horizontal position sigma {sigma_h:.2f} m', values
        problems = []
        if dvl_lost:
            problems.append('DVL lost' if ekf.last_dvl_ns is None or math.isinf(age)
                            else f'DVL lost for {age:.1f} s')
        if growing:
            problems.append(f'covariance growing (velocity sigma {sigma_v:.3f} m/s)')
        if sigma_h > self.limits.position_sigma_warn_m:
            problems.append(f'horizontal position sigma {sigma_h:.2f} m')
        if problems:
            return WARN, ', '.join(problems), values
        return OK, 'tracking', values
