"""Thruster health of a recording: ``thrusters/health`` as series, injected faults, figures.

The injected faults come from the recording's ``uvms`` metadata (the allocator's
``fault_injection.thrusters`` parameter as the run had it), the detection from the health
topic: what the allocator saw. docs/controller.md "Thruster faults".
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import yaml

FloatArray = npt.NDArray[np.float64]

TOPIC_HEALTH = '/uvms/thrusters/health'
ALLOCATOR = '/uvms/thruster_allocator'


@dataclass(frozen=True)
class HealthSeries:
    """ThrusterHealth samples, arrays (n, p) indexed by thruster.

    Attributes:
        t: Time (s), on the run's time origin.
        status: 0 OK, 1 degraded, 2 failed.
        effectiveness: η̂ (-).
        detected_at_s: Detection time (s of the node clock, not shifted to the run's origin;
            NaN: none), (p,) from the last sample.
        fully_actuated: Whether the allocation had rank 6, (n,).
    """

    t: FloatArray
    status: npt.NDArray[np.uint8]
    effectiveness: FloatArray
    detected_at_s: FloatArray
    fully_actuated: npt.NDArray[np.bool_]


@dataclass(frozen=True)
class InjectedFault:
    """One fault as the run injected it (``fault_injection.thrusters``)."""

    index: int
    kind: str
    value: float
    at_s: float


def health_series(t: FloatArray, msgs: Sequence[Any]) -> HealthSeries:
    """ThrusterHealth messages (uvms_msgs/msg/ThrusterHealth) as a series."""
    p = max((len(m.status) for m in msgs), default=0)
    status = np.array([list(m.status) for m in msgs], dtype=np.uint8).reshape(len(msgs), p)
    eta = np.array([list(m.effectiveness) for m in msgs], dtype=np.float64).reshape(len(msgs), p)
    detected = np.asarray(msgs[-1].detected_at_s if msgs else [], dtype=np.float64)
    return HealthSeries(t=t, status=status, effectiveness=eta, detected_at_s=detected,
                        fully_actuated=np.array([bool(m.fully_actuated) for m in msgs]))


def injected_faults(metadata: dict[str, dict[str, str]]) -> list[InjectedFault]:
    """The faults of a run from its ``uvms`` metadata record (none if it has none)."""
    text = metadata.get('uvms', {}).get('parameters', '')
    try:
        tree = yaml.safe_load(text) if text else {}
        spec = tree[ALLOCATOR]['ros__parameters']['fault_injection']['thrusters']
    except (yaml.YAMLError, KeyError, TypeError):
        return []
    faults = []
    for entry in str(spec).split(';'):
        fields = dict(item.partition('=')[::2] for item in entry.split())
        if 'index' in fields and 'kind' in fields and 'at_s' in fields:
            faults.append(InjectedFault(int(fields['index']), fields['kind'],
                                        float(fields.get('value', 0.0)), float(fields['at_s'])))
    return faults


def first_zero_after(t: FloatArray, values: FloatArray, after_s: float) -> float | None:
    """First time at or after ``after_s`` from which ``values`` stays exactly 0 (None: never)."""
    later = t >= after_s
    nonzero = np.flatnonzero(later & (values != 0.0))
    if not np.any(later):
        return None
    start = int(np.flatnonzero(later)[0]) if nonzero.size == 0 else int(nonzero[-1]) + 1
    return None if start >= t.size else float(t[start])


def draw_health_panel(ax: Any, health: HealthSeries, faults: Sequence[InjectedFault],
                      time_offset_s: float = 0.0) -> None:
    """η̂ of every thruster over time; the injected faults (dashed) and detections (dotted).

    Args:
        ax: A matplotlib Axes.
        health: The health series.
        faults: The injected faults (times in the run's simulated seconds).
        time_offset_s: Simulated time of the run's t = 0 (s).
    """
    for i in range(health.effectiveness.shape[1]):
        ax.step(health.t, health.effectiveness[:, i], where='post', color=f'C{i % 10}',
                linewidth=1.1)
    for n, fault in enumerate(faults):
        ax.axvline(fault.at_s - time_offset_s, color=f'C{fault.index % 10}', linestyle='--',
                   linewidth=1.0, label='fault injected' if n == 0 else None)
    detected = [(i, d - time_offset_s) for i, d in enumerate(health.detected_at_s)
                if math.isfinite(d)]
    for n, (i, d) in enumerate(detected):
        ax.axvline(d, color=f'C{i % 10}', linestyle=':', linewidth=1.4,
                   label='fault detected' if n == 0 else None)
    lost = np.flatnonzero(~health.fully_actuated)
    if lost.size:
        ax.axvspan(health.t[lost[0]], health.t[-1], color='red', alpha=0.1,
                   label='not fully actuated')
    ax.set_ylim(-0.05, 1.1)
    ax.set_ylabel('estimated η̂ (-)')
    if faults or detected:
        ax.legend(loc='lower left', fontsize='small')
