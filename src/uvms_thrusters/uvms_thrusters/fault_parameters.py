"""Parameters of thruster fault injection, ESC telemetry and fault detection (allocator node).

``fault_injection.thrusters`` and ``fault_detection.accommodate`` can be set at run time
(docs/controller.md "Thruster faults"); the others are read at configure.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from uvms_common.parameter_spec import ParameterSpec

from uvms_thrusters.allocation import ThrusterAllocator
from uvms_thrusters.errors import ThrusterParameterError
from uvms_thrusters.fault_detection import DetectionParameters, ThrusterFaultDetector
from uvms_thrusters.thruster_faults import (
    PARAMETER,
    EscSensor,
    ThrusterFaultInjector,
    parse_faults,
)

_DEFAULTS = DetectionParameters()

FAULT_PARAMETER_SPECS: list[ParameterSpec] = [
    ParameterSpec(
        PARAMETER, '',
        'Injected thruster faults (plant side), "index=I kind=K [value=V] at_s=T" joined by '
        '";": kind off, efficiency (value eta in [0, 1]), stuck (value a thrust, N) or '
        'saturation (value a thrust limit, N); at_s node-clock seconds; index from 0 in the '
        "order of the robot's thrusters.yaml. Settable at run time; '' for none.",
        read_only=False,
    ),
    ParameterSpec('esc.speed_noise_rad_s', 1.0,
                  'Standard deviation of the propeller speed the ESCs report (rad/s).',
                  0.0, 1000.0),
    ParameterSpec('esc.current_noise_a', 0.05,
                  'Standard deviation of the motor current the ESCs report (A).', 0.0, 100.0),
    ParameterSpec('esc.seed', 0, 'Seed of the ESC telemetry noise.', 0, 2**31 - 1),
    ParameterSpec('fault_detection.enabled', True,
                  'Detect thruster faults from the ESC feedback (false: eta_hat stays 1).'),
    ParameterSpec(
        'fault_detection.accommodate', True,
        'Allocate on T diag(eta_hat) (true) or on T as if every thruster were healthy '
        '(false: detection and reporting only). Settable at run time.',
        read_only=False,
    ),
    ParameterSpec('fault_detection.speed_threshold_rad_s', _DEFAULTS.speed_threshold_rad_s,
                  'Smallest propeller speed residual that counts as a fault (rad/s).',
                  0.0, 1e4),
    ParameterSpec('fault_detection.relative_threshold', _DEFAULTS.relative_threshold,
                  'Speed residual threshold as a share of the model speed |Omega_model| (-).',
                  0.0, 1.0),
    ParameterSpec('fault_detection.persistence_s', _DEFAULTS.persistence_s,
                  'How long the residual must stay over the threshold to declare a fault (s).',
                  0.0, 60.0),
    ParameterSpec('fault_detection.min_speed_rad_s', _DEFAULTS.min_speed_rad_s,
                  'Least model speed at which eta_hat is updated (rad/s).', 0.0, 1e4),
    ParameterSpec('fault_detection.estimate_time_constant_s',
                  _DEFAULTS.estimate_time_constant_s,
                  'Time constant of the eta_hat filter (s).', 1e-4, 60.0),
    ParameterSpec('fault_detection.failed_below', _DEFAULTS.failed_below,
                  'An eta_hat under this is 0: the thruster is out of the allocation (-).',
                  0.0, 1.0),
    ParameterSpec('fault_detection.health_rate_hz', 20.0,
                  'Rate of thrusters/health (Hz), and at once on every change of status.',
                  0.1, 10000.0),
]


@dataclass(frozen=True)
class FaultSettings:
    """The validated values of ``FAULT_PARAMETER_SPECS``."""

    faults: str
    speed_noise_rad_s: float
    current_noise_a: float
    seed: int
    enabled: bool
    accommodate: bool
    detection: DetectionParameters
    health_rate_hz: float


def fault_settings(values: Mapping[str, object], count: int) -> FaultSettings:
    """Check the values (as declared) against the specs and the thruster count.

    Raises:
        ThrusterParameterError: naming the parameter, its value and the valid range.
    """
    for spec in FAULT_PARAMETER_SPECS:
        value = values[spec.name]
        if spec.min_value is not None and spec.max_value is not None and not (
                isinstance(value, int | float) and spec.min_value <= value <= spec.max_value):
            raise ThrusterParameterError(spec.name, value,
                                        f'[{spec.min_value}, {spec.max_value}]')
    text = str(values[PARAMETER])
    parse_faults(text, count)

    def number(name: str) -> float:
        return float(values[f'fault_detection.{name}'])  # type: ignore[arg-type]

    return FaultSettings(
        faults=text,
        speed_noise_rad_s=float(values['esc.speed_noise_rad_s']),  # type: ignore[arg-type]
        current_noise_a=float(values['esc.current_noise_a']),  # type: ignore[arg-type]
        seed=int(values['esc.seed']),  # type: ignore[call-overload]
        enabled=bool(values['fault_detection.enabled']),
        accommodate=bool(values['fault_detection.accommodate']),
        detection=DetectionParameters(
            speed_threshold_rad_s=number('speed_threshold_rad_s'),
            relative_threshold=number('relative_threshold'),
            persistence_s=number('persistence_s'),
            min_speed_rad_s=number('min_speed_rad_s'),
            estimate_time_constant_s=number('estimate_time_constant_s'),
            failed_below=number('failed_below'),
        ),
        health_rate_hz=number('health_rate_hz'),
    )


def equip(allocator: ThrusterAllocator, settings: FaultSettings) -> None:
    """Give the allocator its injected faults, ESC telemetry and detector."""
    count = allocator.params.n_thrusters
    allocator.injector = ThrusterFaultInjector(parse_faults(settings.faults, count), count)
    allocator.esc = EscSensor(count, settings.speed_noise_rad_s, settings.current_noise_a,
                              settings.seed)
    allocator.detector = ThrusterFaultDetector(
        settings.detection, allocator.params.thruster, count) if settings.enabled else None
    allocator.accommodate = settings.accommodate
    if allocator.detector is not None:
        # Load the detector's kernel now, not in the first control period (as the allocator).
        zeros = np.zeros(count)
        allocator.detector.update(zeros, zeros, zeros, 0.0, 0.0)
        allocator.detector.reset()


def set_accommodation(allocator: ThrusterAllocator, accommodate: bool) -> None:
    """Switch the use of η̂ in the allocation on or off at run time."""
    allocator.accommodate = accommodate
    detector = allocator.detector
    allocator.set_effectiveness(detector.effectiveness if accommodate and detector is not None
                                else [1.0] * allocator.params.n_thrusters)
