"""Thruster fault detection from ESC feedback, and the effectiveness estimate η̂.

The detector runs a nominal model of every thruster (``ThrusterBank``, eq. 11-15) on the
thrusts the allocation commanded and compares its propeller speed Ω_model with the speed the
ESC measures (``thruster_faults.EscSensor``): the residual r = Ω_meas − Ω_model (and the
current residual, reported but not used to decide). A thruster is declared faulty once
|r| exceeds max(``speed_threshold_rad_s``, ``relative_threshold`` |Ω_model|) for
``persistence_s`` without a break; the declaration is latched (``reset`` clears it).

Effectiveness: at a bollard state T = α_2 Ω |Ω| (eq. 11), so the thrust the thruster gives
over what the model expects is ρ = Ω_meas |Ω_meas| / (Ω_model |Ω_model|). After a
declaration, while the fault shows (|r| over the threshold and |Ω_model| over
``min_speed_rad_s``), η̂ follows ρ through a first-order filter of time constant
``estimate_time_constant_s``; a ρ outside [0, 1] (pushing the wrong way, or more than told:
stuck) counts as 0, and an η̂ under ``failed_below`` is 0: the thruster is out of the
allocation. Before any declaration η̂ is 1, so sensor noise never moves the allocation.

In this emulation the nominal model is the very model the plant side integrates, so without a
fault the residual is the sensor noise alone; a real thruster adds model error (advance
speed, temperature, wear), which the relative threshold is meant to absorb (not tested here).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from uvms_model.jit import kernel

from uvms_thrusters.errors import ThrusterParameterError
from uvms_thrusters.thruster_dynamics import ThrusterBank, ThrusterModelParameters

FloatArray = npt.NDArray[np.float64]

STATUS_OK, STATUS_DEGRADED, STATUS_FAILED = 0, 1, 2


@kernel
def residual_step(measured_speed: FloatArray, measured_current: FloatArray,
                  omega_model: FloatArray, current_model: FloatArray, speed_residual: FloatArray,
                  current_residual: FloatArray, over_s: FloatArray, over: npt.NDArray[np.bool_],
                  status: npt.NDArray[np.uint8], detected_at_s: FloatArray, dt: float, t_s: float,
                  speed_threshold: float, relative_threshold: float,
                  persistence_s: float) -> bool:
    """Residuals, persistence and new declarations of one step, in place (module docstring).

    Returns:
        Whether any thruster is declared (this step or before).
    """
    declared = False
    for i in range(omega_model.size):
        speed_residual[i] = measured_speed[i] - omega_model[i]
        current_residual[i] = measured_current[i] - current_model[i]
        threshold = max(speed_threshold, relative_threshold * abs(omega_model[i]))
        over[i] = abs(speed_residual[i]) > threshold
        over_s[i] = over_s[i] + dt if over[i] else 0.0
        if status[i] == STATUS_OK and over[i] and over_s[i] >= persistence_s:
            status[i] = STATUS_DEGRADED
            detected_at_s[i] = t_s
        declared = declared or status[i] != STATUS_OK
    return declared


#: Time constants of the η̂ filter after a declaration when its estimate is reported as
#: settled (5: within 1 % of a step, e^-5).
SETTLE_TIME_CONSTANTS = 5.0


@dataclass(frozen=True)
class DetectionParameters:
    """Thresholds of the detector (parameters ``fault_detection.*``, docs/controller.md).

    Attributes:
        speed_threshold_rad_s: Smallest speed residual that counts (rad/s).
        relative_threshold: Residual threshold as a share of |Ω_model| (-).
        persistence_s: How long the residual must stay over the threshold (s).
        min_speed_rad_s: Least |Ω_model| at which η̂ is updated (rad/s).
        estimate_time_constant_s: Time constant of the η̂ filter (s).
        failed_below: η̂ under this is taken as 0 (-).
    """

    speed_threshold_rad_s: float = 15.0
    relative_threshold: float = 0.15
    persistence_s: float = 0.1
    min_speed_rad_s: float = 20.0
    estimate_time_constant_s: float = 0.1
    failed_below: float = 0.15

    def __post_init__(self) -> None:
        for name, value, lo, hi in (
            ('speed_threshold_rad_s', self.speed_threshold_rad_s, 0.0, math.inf),
            ('relative_threshold', self.relative_threshold, 0.0, 1.0),
            ('persistence_s', self.persistence_s, 0.0, 60.0),
            ('min_speed_rad_s', self.min_speed_rad_s, 0.0, math.inf),
            ('estimate_time_constant_s', self.estimate_time_constant_s, 1e-4, 60.0),
            ('failed_below', self.failed_below, 0.0, 1.0),
        ):
            if not (math.isfinite(value) and lo <= value <= hi):
                raise ThrusterParameterError(f'fault_detection.{name}', value, f'[{lo}, {hi}]')


class ThrusterFaultDetector:
    """Residuals, persistence, latched declarations and η̂ for p thrusters.

    Example:
        >>> detector = ThrusterFaultDetector(DetectionParameters(), ThrusterModelParameters(), 2)
        >>> bank = ThrusterBank(ThrusterModelParameters(), 2)
        >>> command = np.array([50.0, 50.0])
        >>> for k in range(500):  # thruster 1 off from 0.5 s on
        ...     _ = bank.step(np.array([50.0, 0.0 if k >= 250 else 50.0]), 0.002)
        ...     _ = detector.update(command, bank.omega, bank.motor_current, 0.002, k * 0.002)
        >>> detector.status.tolist(), bool(0.5 < detector.detected_at_s[1] < 0.7)
        ([0, 2], True)
    """

    def __init__(self, params: DetectionParameters, model: ThrusterModelParameters,
                 count: int) -> None:
        self.params = params
        self.model = ThrusterBank(model, count)
        self.count = count
        self.effectiveness = np.ones(count)
        self.status = np.zeros(count, dtype=np.uint8)
        self.detected_at_s = np.full(count, np.nan)
        #: Time of each thruster's last status change (s): its declaration, then degraded or
        #: failed as η̂ settles, or recovered; NaN before any.
        self.changed_at_s = np.full(count, np.nan)
        self._status_before = np.zeros(count, dtype=np.uint8)
        #: Whether each declared thruster's η̂ has had ``SETTLE_TIME_CONSTANTS`` time
        #: constants since its declaration (its value then means what it says).
        self.settled = np.zeros(count, dtype=np.bool_)
        self.speed_residual = np.zeros(count)
        self.current_residual = np.zeros(count)
        self._over_s = np.zeros(count)
        self._over = np.zeros(count, dtype=np.bool_)
        self._ratio = np.ones(count)

    def reset(self) -> None:
        """Clear every declaration and the model state: all thrusters healthy again."""
        self.model.reset()
        self.effectiveness[:] = 1.0
        self.status[:] = STATUS_OK
        self.detected_at_s[:] = np.nan
        self.changed_at_s[:] = np.nan
        self.settled[:] = False
        self.speed_residual[:] = 0.0
        self.current_residual[:] = 0.0
        self._over_s[:] = 0.0
        self._ratio[:] = 1.0

    def restart_model(self) -> None:
        """Stop the nominal model (the thrusters were restarted); declarations stay."""
        self.model.reset()
        self._over_s[:] = 0.0

    def update(self, commanded: FloatArray, measured_speed: FloatArray,
               measured_current: FloatArray, dt: float, t_s: float) -> bool:
        """One step: advance the model on the commanded thrusts, compare, decide.

        Args:
            commanded: Desired thrusts the allocation sent to the ESCs this step (N).
            measured_speed: Ω the ESCs report after the step (rad/s).
            measured_current: i_m the ESCs report (A).
            dt: Step length (s).
            t_s: Time of the step (s), kept as the detection time.

        Returns:
            Whether η̂ changed (the allocation should be redone on it).
        """
        p = self.params
        model = self.model
        model.step(commanded, dt)
        np.copyto(self._status_before, self.status)
        omega_model = model.omega
        if not residual_step(measured_speed, measured_current, omega_model, model.motor_current,
                             self.speed_residual, self.current_residual, self._over_s,
                             self._over, self.status, self.detected_at_s, float(dt), float(t_s),
                             p.speed_threshold_rad_s, p.relative_threshold, p.persistence_s):
            return False
        over = self._over
        before = self.effectiveness.copy()
        declared = self.status != STATUS_OK
        excited = declared & over & (np.abs(omega_model) > p.min_speed_rad_s)
        if np.any(excited):
            m = omega_model[excited]
            rho = measured_speed[excited] * np.abs(measured_speed[excited]) / (m * np.abs(m))
            rho = np.where((rho >= 0.0) & (rho <= 1.0), rho, 0.0)
            gain = min(1.0, dt / p.estimate_time_constant_s) if dt > 0.0 else 0.0
            self._ratio[excited] += gain * (rho - self._ratio[excited])
        eta = np.where(declared, self._ratio, 1.0)
        eta[eta < p.failed_below] = 0.0
        self.effectiveness[:] = eta
        self.status[declared] = np.where(eta[declared] == 0.0, STATUS_FAILED, STATUS_DEGRADED)
        self.changed_at_s[self.status != self._status_before] = t_s
        self.settled[:] = declared & (
            t_s - self.detected_at_s >= SETTLE_TIME_CONSTANTS * p.estimate_time_constant_s)
        return not np.array_equal(before, self.effectiveness)
