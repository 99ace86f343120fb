"""Thruster health for the allocator node: ``thrusters/health``, /diagnostics, run-time changes.

The only place where the fault core (``thruster_faults``, ``fault_detection``)
meets messages and parameters: the allocator node calls these in a few lines.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.parameter import Parameter
from std_msgs.msg import Header
from uvms_common.diagnostics import ERROR, OK, WARN, Report

from uvms_msgs.msg import ThrusterHealth
from uvms_thrusters.allocation import AllocatorOutput, ThrusterAllocator
from uvms_thrusters.conversions import BASE_LINK_FRD, time_from_ns
from uvms_thrusters.errors import ThrusterParameterError
from uvms_thrusters.fault_parameters import set_accommodation
from uvms_thrusters.thruster_faults import PARAMETER, ThrusterFaultInjector, parse_faults

#: The health topic (relative: /uvms/thrusters/health in the default namespace).
HEALTH_TOPIC = 'thrusters/health'


def _floats(values: Any) -> list[float]:
    return [float(v) for v in np.ravel(values)]


def health_message(t_ns: int, allocator: ThrusterAllocator, output: AllocatorOutput,
                   out: ThrusterHealth | None = None) -> ThrusterHealth:
    """uvms_msgs/ThrusterHealth of one allocator step."""
    msg = out if out is not None else ThrusterHealth(header=Header(frame_id=BASE_LINK_FRD))
    msg.header.stamp = time_from_ns(t_ns)
    p = allocator.params.n_thrusters
    detector = allocator.detector
    msg.status = [int(s) for s in detector.status] if detector is not None else [0] * p
    msg.effectiveness = _floats(detector.effectiveness if detector is not None else np.ones(p))
    esc = output.esc
    msg.measured_speed = _floats(esc.measured_speed) if esc is not None else []
    msg.measured_current = _floats(esc.measured_current) if esc is not None else []
    msg.speed_residual = _floats(detector.speed_residual) if detector is not None else []
    msg.current_residual = _floats(detector.current_residual) if detector is not None else []
    msg.detected_at_s = (_floats(detector.detected_at_s) if detector is not None
                         else [float('nan')] * p)
    msg.rank = allocator.rank
    msg.fully_actuated = allocator.fully_actuated
    msg.accommodating = allocator.accommodate
    return msg


def health_report(allocator: ThrusterAllocator | None) -> Report:
    """/diagnostics: ERROR once not fully actuated, WARN with a fault, else OK."""
    if allocator is None:
        return Report(WARN, 'not configured', {})
    detector = allocator.detector
    values: dict[str, Any] = {
        'rank': allocator.rank, 'fully_actuated': allocator.fully_actuated,
        'accommodating': allocator.accommodate, 'detection': detector is not None,
        'effectiveness': ' '.join(f'{e:.3f}' for e in allocator.effectiveness)}
    faulty: list[int] = []
    if detector is not None:
        faulty = [int(i) for i in np.flatnonzero(detector.status)]
        values['eta_hat'] = ' '.join(f'{e:.3f}' for e in detector.effectiveness)
        for i in faulty:
            values[f'thruster_{i}'] = (
                f'{"failed" if detector.effectiveness[i] == 0.0 else "degraded"}, eta_hat '
                f'{detector.effectiveness[i]:.3f}, detected at {detector.detected_at_s[i]:.3f} s')
    if not allocator.fully_actuated:
        return Report(ERROR, f'thrusters {faulty} lost: rank {allocator.rank} < 6, the vehicle '
                      'cannot produce every wrench', values)
    if faulty:
        return Report(WARN, f'thruster fault on {faulty}'
                      + ('' if allocator.accommodate else ' (accommodation off)'), values)
    return Report(OK, 'all thrusters healthy', values)


def health_change(before: tuple[Any, ...] | None, after: tuple[Any, ...],
                  allocator: ThrusterAllocator) -> tuple[str, str] | None:
    """The console line of a health change: (``WARN`` or ``ERROR``, text), None if none.

    ``before`` and ``after`` are the allocator node's health keys (rank, accommodating,
    detector status bytes). A thruster's fault declared, its estimate settled as degraded or
    failed, or its recovery, is WARN, each at the time of that change; a rank below 6 (the
    vehicle cannot produce every wrench) is ERROR, its return WARN.

    A declaration comes before its estimate: the detector declares a fault when the ESC
    speed stays off the model's (``fault_detection.persistence_s``), with η̂ one filter step
    from 1 (0.98); η̂ then settles over ``estimate_time_constant_s`` and the thruster is
    degraded, or failed once η̂ falls below ``failed_below`` (measured: a thruster switched
    off is declared at 11.106 s and failed at 11.294 s). So the declaration line names no
    state, and each later line its own time.
    """
    if before is None or before == after:
        return None
    detector = allocator.detector
    old = np.zeros(0, np.uint8) if before[2] is None else np.frombuffer(before[2], np.uint8)
    new = np.zeros(0, np.uint8) if after[2] is None else np.frombuffer(after[2], np.uint8)
    parts = [_status_line(detector, int(i), int(old[i]), int(new[i]))
             for i in np.flatnonzero(old != new)] if old.size == new.size else []
    if detector is not None and len(before) > 3 and len(after) > 3 and after[3] is not None:
        was = (np.zeros(0, np.bool_) if before[3] is None
               else np.frombuffer(before[3], np.bool_))
        now = np.frombuffer(after[3], np.bool_)
        if was.size == now.size:
            parts += [f'thruster {i} (T{i + 1}) degraded: eta_hat settled at '
                      f'{detector.effectiveness[i]:.3f}'
                      for i in np.flatnonzero(now & ~was) if new.size > i and new[i] == 1]
    if not allocator.fully_actuated:
        return ERROR, '; '.join([*parts, f'rank {allocator.rank} < 6: the vehicle cannot '
                                 'produce every wrench (a running task ends ACTUATION_LOST)'])
    if before[0] != after[0]:
        parts.append(f'rank {allocator.rank}: every vehicle wrench again')
    if not parts:
        return None
    accommodating = ('allocating around it' if allocator.accommodate
                     else 'accommodation off')
    return WARN, '; '.join(parts) + f' ({accommodating})'


def _status_line(detector: Any, i: int, old: int, new: int) -> str:
    """One thruster's status change, at its time, with η̂ where it means something."""
    name = f'thruster {i} (T{i + 1})'
    at = detector.changed_at_s[i] if detector is not None else float('nan')
    when = f' at {at:.3f} s' if np.isfinite(at) else ''
    eta = detector.effectiveness[i] if detector is not None else float('nan')
    if new == 0:
        return f'{name} recovered{when}'
    if old == 0 and new == 1:
        return (f"{name} fault declared{when}: its ESC speed left the model's; eta_hat "
                'being estimated')
    state = 'failed' if new == 2 else 'degraded'
    if old == 0:
        return f'{name} fault declared{when}: {state} (eta_hat {eta:.3f})'
    return f'{name} {state}{when} (eta_hat {eta:.3f})'


def on_set_fault_parameters(allocator: ThrusterAllocator | None,
                            parameters: list[Parameter]) -> SetParametersResult:
    """Apply ``fault_injection.thrusters`` and ``fault_detection.accommodate`` at run time."""
    for parameter in parameters:
        if parameter.name == PARAMETER:
            count = allocator.params.n_thrusters if allocator is not None else None
            try:
                faults = parse_faults(str(parameter.value), count)
            except ThrusterParameterError as error:
                return SetParametersResult(successful=False, reason=str(error))
            if allocator is not None and count is not None:
                allocator.injector = ThrusterFaultInjector(faults, count)
        elif parameter.name == 'fault_detection.accommodate' and allocator is not None:
            set_accommodation(allocator, bool(parameter.value))
    return SetParametersResult(successful=True)
