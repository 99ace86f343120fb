"""Line plots of a sweep: an axis over decades is drawn on a log scale, however it was given."""

from __future__ import annotations

from pathlib import Path

import pytest
from uvms_sweep.maps import log_scale, metric_figure
from uvms_sweep.sweep_file import load_sweep

SWEEP = """\
name: stiffness
scenario: case1_ke1e4
duration_s: 20
axes:
  simulator.contact.stiffness_n_m: {axis}
metrics: [overshoot_percent]
"""


@pytest.mark.parametrize(('axis', 'scale'), [
    ('[1.0e+4, 1.0e+5]', 'log'),  # a list over a decade: the case of issue 33
    ('{logspace: [1.0e+3, 1.0e+6, 4]}', 'log'),
    ('[1.0e+4, 2.0e+4, 3.0e+4]', 'linear'),  # less than a decade
    ('{linspace: [1.0e+4, 5.0e+4, 3]}', 'linear'),
])
def test_line_plot_axis_scale(tmp_path: Path, axis: str, scale: str) -> None:
    """Stiffness 1e4 and 1e5 (and any logspace) on a log x axis; a narrow range stays linear."""
    path = tmp_path / 'sweep.yaml'
    path.write_text(SWEEP.format(axis=axis), encoding='utf-8')
    sweep = load_sweep(path)
    assert log_scale(sweep.axes[0]) == (scale == 'log')
    points = sweep.points('case1_ke1e4', 20.0, 1)
    rows = {p.point_id: {'status': 'done', 'reason': '', 'stable': 'yes',
                         'overshoot_percent': str(1.0 + i)} for i, p in enumerate(points)}
    figure = metric_figure(sweep, points, rows, 'overshoot_percent')
    assert figure.axes[0].get_xscale() == scale
