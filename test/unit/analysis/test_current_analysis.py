"""The ocean current in the analysis: its series, metrics, report columns and vehicle panel."""

from __future__ import annotations

import numpy as np
import pytest
from uvms_analysis.metrics import compute_metrics
from uvms_analysis.plots import figure_vehicle_motion
from uvms_analysis.report import format_report
from uvms_analysis.series import CurrentSeries, OdometrySeries, Run, run_from_messages

T = np.linspace(0.0, 2.0, 5)


def _run(current: CurrentSeries | None) -> Run:
    """A run with a still vehicle, and the given current."""
    n = T.size
    quaternion = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    odometry = OdometrySeries(T, np.zeros((n, 3)), quaternion, np.zeros((n, 3)),
                              np.zeros((n, 3)), np.zeros((n, 3)))
    return Run('current', odometry=odometry, current=current)


CURRENT = CurrentSeries(T, np.array([[0.0, 0.2, 0.0], [0.0, 0.3, 0.0], [0.0, 0.1, 0.0],
                                     [0.0, 0.2, 0.0], [0.0, 0.2, 0.0]]))


def test_current_metrics_are_its_mean_and_largest_speed() -> None:
    """current_speed = mean |v_c|, current_speed_max = max |v_c| (m/s); n/a in still water."""
    metrics = compute_metrics(_run(CURRENT))
    assert metrics.current_speed == pytest.approx(0.2)
    assert metrics.current_speed_max == pytest.approx(0.3)
    still = compute_metrics(_run(None))
    assert still.current_speed is None and still.current_speed_max is None


def test_report_has_the_current_columns() -> None:
    """CSV keys current_speed_m_s and current_speed_max_m_s carry the values."""
    rows = format_report([compute_metrics(_run(CURRENT))], 'csv').splitlines()
    header, values = rows[0].split(','), rows[1].split(',')
    assert float(values[header.index('current_speed_m_s')]) == pytest.approx(0.2)
    assert float(values[header.index('current_speed_max_m_s')]) == pytest.approx(0.3)


def test_vehicle_figure_gets_a_current_panel_only_with_a_current() -> None:
    """Three panels (position, attitude, current: north, east, down, speed) with a current."""
    with_current = figure_vehicle_motion(_run(CURRENT))
    assert with_current is not None and len(with_current.axes) == 3
    labels = [line.get_label() for line in with_current.axes[2].get_lines()]
    assert labels == ['north', 'east', 'down', 'speed']
    np.testing.assert_allclose(with_current.axes[2].get_lines()[1].get_ydata(),
                               CURRENT.velocity[:, 1])
    still = figure_vehicle_motion(_run(None))
    assert still is not None and len(still.axes) == 2


def test_current_messages_become_a_series() -> None:
    """TwistStamped on /uvms/ocean/current: t from the stamps, linear part as velocity."""
    from types import SimpleNamespace as Ns

    def twist(t_ns: int, y: float) -> Ns:
        stamp = Ns(sec=t_ns // 10**9, nanosec=t_ns % 10**9)
        return Ns(header=Ns(stamp=stamp), twist=Ns(linear=Ns(x=0.0, y=y, z=0.0)))

    run = run_from_messages('r', [('/uvms/ocean/current', 0, twist(0, 0.2)),
                                  ('/uvms/ocean/current', 0, twist(10**9, 0.25))])
    assert run.current is not None
    np.testing.assert_allclose(run.current.t, [0.0, 1.0])
    np.testing.assert_allclose(run.current.velocity[:, 1], [0.2, 0.25])


def test_thrust_saturation_metric_is_the_smallest_scale() -> None:
    """saturation_scale_min: the smallest wrench scale of the allocator over the run."""
    from uvms_analysis.series import ThrusterSeries

    p = np.zeros((T.size, 8))
    thrusters = ThrusterSeries(T, p, p, p, p, p, np.array([1.0, 1.0, 0.7, 0.9, 1.0]))
    run = Run('saturated', thrusters=thrusters)
    assert compute_metrics(run).saturation_scale_min == pytest.approx(0.7)
