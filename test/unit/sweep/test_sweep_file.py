"""Sweep files: axes expand to the grid the user wrote; bad files name the bad key."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from uvms_sweep.sweep_file import SweepError, expand_axis, load_sweep, point_id
from uvms_sweep.table import stability

SWEEPS = Path(__file__).resolve().parents[3] / 'config' / 'sweeps'
VALID = """\
name: t
scenario: case1_ke1e4
duration_s: 0.5
seeds: [1, 2]
axes:
  simulator.contact.stiffness_n_m: {logspace: [1.0e+3, 1.0e+6, 4]}
  controller.model.mass_scale: {linspace: [0.5, 1.5, 3]}
metrics: [force_rms_error_N, overshoot_percent]
"""


def write(tmp_path: Path, text: str) -> Path:
    """A sweep file with this text."""
    path = tmp_path / 'sweep.yaml'
    path.write_text(text, encoding='utf-8')
    return path


def test_logspace_gives_decades_between_end_values(tmp_path: Path) -> None:
    """{logspace: [1e3, 1e6, 4]} is 1e3, 1e4, 1e5, 1e6 exactly (end values, not exponents)."""
    values, spacing = expand_axis({'logspace': [1.0e3, 1.0e6, 4]}, 'axes.k', tmp_path)
    assert values == (1e3, 1e4, 1e5, 1e6)
    assert spacing == 'logspace'


def test_linspace_matches_numpy(tmp_path: Path) -> None:
    """{linspace: [a, b, n]} gives numpy.linspace(a, b, n)."""
    values, _ = expand_axis({'linspace': [0.5, 1.5, 5]}, 'axes.s', tmp_path)
    np.testing.assert_allclose(values, np.linspace(0.5, 1.5, 5), rtol=1e-12)


def test_list_mixing_int_and_float_becomes_float(tmp_path: Path) -> None:
    """ROS parameters are strictly typed: [1, 2.5] is read as floats."""
    values, spacing = expand_axis([1, 2.5], 'axes.s', tmp_path)
    assert values == (1.0, 2.5) and all(isinstance(v, float) for v in values)
    assert spacing == 'list'


def test_grid_has_every_value_combination_and_seed(tmp_path: Path) -> None:
    """4 x 3 values x 2 seeds = 24 points, each with its own stable id."""
    sweep = load_sweep(write(tmp_path, VALID))
    points = sweep.points('case1_ke1e4', 0.5, 0)
    assert len(points) == 24
    assert len({p.point_id for p in points}) == 24
    assert {p.seed for p in points} == {1, 2}
    combos = {(p.values['simulator.contact.stiffness_n_m'],
               p.values['controller.model.mass_scale']) for p in points}
    assert len(combos) == 12
    again = load_sweep(write(tmp_path, VALID)).points('case1_ke1e4', 0.5, 0)
    assert [p.point_id for p in again] == [p.point_id for p in points]


def test_point_id_changes_with_duration_seed_and_values() -> None:
    """The resume key covers what changes a run's result."""
    base = point_id('case1', 1.0, 1, {'a.b': 1.0})
    assert point_id('case1', 2.0, 1, {'a.b': 1.0}) != base
    assert point_id('case1', 1.0, 2, {'a.b': 1.0}) != base
    assert point_id('case1', 1.0, 1, {'a.b': 1.5}) != base
    assert point_id('case1', 1.0, 1, {'a.b': 1.0}) == base


@pytest.mark.parametrize(('old', 'new', 'key'), [
    ('name: t\n', 'nmae: t\n', "unknown key 'nmae'"),
    ('scenario: case1_ke1e4\n', 'scenario: no_such_case\n', "key 'scenario'"),
    ('duration_s: 0.5\n', 'duration_s: -1\n', "key 'duration_s'"),
    ('seeds: [1, 2]\n', 'seeds: [1, -2]\n', "key 'seeds[1]'"),
    ('{logspace: [1.0e+3, 1.0e+6, 4]}', '{logspace: [0.0, 1.0e+6, 4]}',
     "key 'axes.simulator.contact.stiffness_n_m.logspace'"),
    ('{linspace: [0.5, 1.5, 3]}', '{linspace: [0.5, 1.5]}',
     "key 'axes.controller.model.mass_scale.linspace'"),
    ('controller.model.mass_scale:', 'planner.model.mass_scale:',
     "key 'axes.planner.model.mass_scale': unknown node 'planner'"),
    ('[force_rms_error_N, overshoot_percent]', '[force_rms_error_N, overshot]',
     "key metrics[1]: unknown metric 'overshot'"),
])
def test_bad_sweep_file_names_the_key(tmp_path: Path, old: str, new: str, key: str) -> None:
    """Each schema error stops the sweep with the file and the offending key in the message."""
    assert old in VALID
    path = write(tmp_path, VALID.replace(old, new))
    with pytest.raises(SweepError) as error:
        load_sweep(path)
    assert str(path) in str(error.value)
    assert key in str(error.value)


@pytest.mark.parametrize('name', ['stiffness_model_error', 'noise_filter', 'current'])
def test_shipped_sweeps_follow_the_schema(name: str) -> None:
    """config/sweeps/*.yaml load; their grids are the ones docs/results.md describes."""
    sweep = load_sweep(SWEEPS / f'{name}.yaml')
    assert sweep.name == name
    assert 2 == len(sweep.axes)


@pytest.mark.parametrize(('metrics', 'expected'), [
    ({'contact_count': 0.0, 'desired_force_N': 0.0}, ''),
    ({'contact_count': 1.0, 'desired_force_N': 150.0, 'peak_force_N': 155.0}, 'yes'),
    ({'contact_count': 1.0, 'desired_force_N': 150.0, 'peak_force_N': 22.0}, 'yes'),
    ({'contact_count': 1.0, 'desired_force_N': 150.0, 'peak_force_N': 13800.0}, 'no'),
    ({'contact_count': 3.0, 'desired_force_N': 150.0, 'peak_force_N': 155.0}, 'no'),
])
def test_bouncing_or_surging_force_is_unstable(
    metrics: dict[str, float | None], expected: str
) -> None:
    """Unstable: several contact intervals, or a peak above twice the set-point."""
    assert stability(metrics) == expected


def test_one_axis_sweep_draws_a_line_per_metric_with_failed_points(tmp_path: Path) -> None:
    """One axis: figures/METRIC.png is a line plot; failed and unstable rows do not break it."""
    from matplotlib.image import imread
    from uvms_sweep.maps import draw_figures

    text = VALID.replace('  simulator.contact.stiffness_n_m: {logspace: [1.0e+3, 1.0e+6, 4]}\n',
                         '').replace('seeds: [1, 2]\n', '')
    sweep = load_sweep(write(tmp_path, text))
    points = sweep.points('case1_ke1e4', 0.5, 1)
    rows = {
        points[0].point_id: {'status': 'done', 'stable': 'yes', 'force_rms_error_N': '1.0',
                             'overshoot_percent': '2.0'},
        points[1].point_id: {'status': 'failed', 'reason': 'timeout'},
        points[2].point_id: {'status': 'done', 'stable': 'no', 'force_rms_error_N': '9.0',
                             'overshoot_percent': ''},
    }
    files = draw_figures(sweep, points, rows, tmp_path / 'out')
    assert [f.name for f in files] == ['force_rms_error_N.png', 'overshoot_percent.png']
    assert all(imread(f).shape[0] > 100 for f in files)
