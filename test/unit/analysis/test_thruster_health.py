"""Tests of the thruster-health analysis: injected faults from metadata, zero times, figure."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
from uvms_analysis.plots import figure_thrusters
from uvms_analysis.series import Run, ThrusterSeries
from uvms_analysis.thruster_health import (
    InjectedFault,
    first_zero_after,
    health_series,
    injected_faults,
)

PARAMETERS = """/uvms/thruster_allocator:
  ros__parameters:
    fault_injection:
      thrusters: index=0 kind=off at_s=11.0; index=5 kind=efficiency value=0.3 at_s=12.5
"""


def test_injected_faults_are_read_from_the_run_metadata() -> None:
    """The allocator's fault_injection.thrusters of the uvms record, as the run had it."""
    faults = injected_faults({'uvms': {'parameters': PARAMETERS}})
    assert faults == [InjectedFault(0, 'off', 0.0, 11.0),
                      InjectedFault(5, 'efficiency', 0.3, 12.5)]
    assert injected_faults({}) == []
    assert injected_faults({'uvms': {'parameters': 'x: [unclosed'}}) == []


def test_first_zero_after_is_where_the_value_stays_zero() -> None:
    """A value that touches zero and comes back does not count; the last return to 0 does."""
    t = np.arange(8) * 0.5
    values = np.array([3.0, 2.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0])
    assert first_zero_after(t, values, 0.5) == 2.0
    assert first_zero_after(t, np.ones(8), 0.5) is None
    assert first_zero_after(t, values, 10.0) is None


def health_messages(n: int) -> list[SimpleNamespace]:
    """Fake ThrusterHealth messages: thruster 1 fails at sample n // 2."""
    msgs = []
    for k in range(n):
        failed = k >= n // 2
        msgs.append(SimpleNamespace(
            status=[0, 2 if failed else 0], effectiveness=[1.0, 0.0 if failed else 1.0],
            detected_at_s=[math.nan, 0.5 if failed else math.nan], fully_actuated=True))
    return msgs


def test_thruster_figure_gains_a_health_panel() -> None:
    """With thrusters/health the figure has a third panel: η̂ with fault and detection lines."""
    t = np.linspace(0.0, 1.0, 11)
    thrust = np.ones((11, 2))
    thrusters = ThrusterSeries(t, thrust, thrust, thrust, thrust, thrust, np.ones(11))
    health = health_series(t, health_messages(11))
    metadata = {'uvms': {'parameters': PARAMETERS.replace('index=5', 'index=1')}}
    with_health = figure_thrusters(Run('x', thrusters=thrusters, health=health,
                                       metadata=metadata))
    without = figure_thrusters(Run('x', thrusters=thrusters))
    assert with_health is not None and without is not None
    assert len(with_health.axes) == 3 and len(without.axes) == 2
    labels = with_health.axes[2].get_legend_handles_labels()[1]
    assert {'fault injected', 'fault detected'} <= set(labels)
    assert health.effectiveness[-1].tolist() == [1.0, 0.0]


def test_thruster_figure_legend_leaves_the_title_clear() -> None:
    """The legend's box and the title's box do not overlap once drawn (issue 42)."""
    t = np.linspace(0.0, 1.0, 11)
    thrust = np.ones((11, 8))
    thrusters = ThrusterSeries(t, thrust, thrust, thrust, thrust, thrust, np.ones(11))
    fig = figure_thrusters(Run('bluerov2_alpha5_thruster_fault', thrusters=thrusters))
    assert fig is not None
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    title = fig.axes[0].title.get_window_extent(renderer)
    [legend] = fig.legends
    assert not title.overlaps(legend.get_window_extent(renderer))
