"""Figures of a sweep: one PNG per metric, a heatmap over two axes or a line over one.

Drawn on ``matplotlib.figure.Figure`` with the Agg canvas, without pyplot (as ``plots``).

A cell (or a point of the line) is the mean of the metric over the seeds that ran. Cells
where a seed failed are grey with a cross hatch (``xx``) and the label ``failed``; cells
where a seed ran unstable (``table.stability``) carry a red diagonal hatch (``//``), cells
where a seed ended before settling (``table.ended_early``) an orange dotted hatch (``..``),
and the colour scale spans the other cells (a marked cell beyond it shows saturated); in
line plots failed points are red crosses at the bottom, unstable ones open red circles and
those that ended early open orange squares. The legend lists the marks a figure uses.
Sweeps over three or more axes get the table only.

A line plot's axis is logarithmic where it was given as ``logspace`` or its positive values
span a decade or more (``log_scale``). Legible at any grid size: a heatmap is at least
``_MIN_FIGSIZE_IN``, axis labels are the full parameter names wrapped at their dots and
underscores, and the colour bar (line plots: the y axis) carries the metric's label and unit
from ``uvms_analysis.report.COLUMNS``.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Rectangle
from uvms_analysis.report import COLUMNS

from uvms_sweep.sweep_file import Axis, Sweep, SweepPoint, axis_labels
from uvms_sweep.table import ENDED_BEFORE_SETTLING, metric_value

FIGURE_DIR = 'figures'
_DPI = 110
#: Smallest heatmap (width, height) in inches: room for wrapped labels and the legend.
_MIN_FIGSIZE_IN = (6.4, 4.8)
#: Characters per inch of a 10 pt axis label, to wrap a label to the length of its axis.
_LABEL_CHARS_PER_IN = 11.0
#: Marks of the cells: (legend label, face colour, hatch, edge colour).
_FAILED = ('failed', '0.6', 'xx', '0.3')
_UNSTABLE = ('unstable', 'none', '//', 'red')
_ENDED = (ENDED_BEFORE_SETTLING, 'none', '..', 'darkorange')
#: Ratio of the largest to the smallest positive value from which a line plot's axis is log.
_DECADE = 10.0


def metric_label(metric: str) -> str:
    """A metric's heading and unit as ``uvms report`` shows them, e.g. ``overshoot (%)``.

    Example:
        >>> metric_label('settling_time_s')
        'settling time (s)'
    """
    column = next((column for column in COLUMNS if column.key == metric), None)
    if column is None:
        return metric
    label = column.label.replace('-\n', '').replace('\n', ' ')
    return f'{label} ({column.unit})' if column.unit else label


def wrap_name(name: str, width: int) -> str:
    """A dotted parameter name on lines of at most ``width`` characters where it can be.

    Lines break after a dot or an underscore, so that no part of the name is lost.

    Example:
        >>> print(wrap_name('controller.hybrid.force_derivative_cutoff_hz', 20))
        controller.hybrid.
        force_derivative_
        cutoff_hz
    """
    lines = ['']
    for piece in re.findall(r'[^._]+[._]?|[._]', name):
        if lines[-1] and len(lines[-1]) + len(piece) > width:
            lines.append('')
        lines[-1] += piece
    return '\n'.join(lines)


def log_scale(axis: Axis) -> bool:
    """Whether a line plot draws ``axis`` on a log scale.

    Yes for an axis given as ``logspace``, and for positive numbers that span a decade or
    more (a list ``[1.0e+4, 1.0e+5]`` of stiffnesses): on a linear scale their small values
    crowd into one corner.

    Example:
        >>> log_scale(Axis('simulator.contact.stiffness_n_m', (1.0e4, 1.0e5)))
        True
        >>> log_scale(Axis('controller.model.mass_scale', (0.5, 1.0, 1.5)))
        False
    """
    if axis.spacing == 'logspace':
        return True
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in axis.values):
        return False
    values = np.array(axis.values, dtype=float)
    return bool(values.size > 1 and np.all(values > 0.0)
                and values.max() >= _DECADE * values.min())


#: Unit suffixes of parameter names (longest first) and how a label writes them.
_UNITS = (('_n_s_m', 'N s/m'), ('_m_s2', 'm/s²'), ('_m_s', 'm/s'), ('_n_m', 'N/m'),
          ('_rad', 'rad'), ('_deg', 'deg'), ('_hz', 'Hz'), ('_n', 'N'), ('_m', 'm'),
          ('_s', 's'))


def parameter_label(name: str) -> str:
    """A parameter key in words, its unit in brackets: the last two parts of the key.

    Example:
        >>> parameter_label('simulator.contact.stiffness_n_m')
        'contact stiffness (N/m)'
        >>> parameter_label('controller.model.mass_scale')
        'model mass scale'
    """
    parts = name.split('.')
    last, unit = parts[-1], ''
    for suffix, text in _UNITS:
        if last.endswith(suffix) and len(last) > len(suffix):
            last, unit = last[:-len(suffix)], f' ({text})'
            break
    words = ' '.join([*parts[-2:-1], last]).replace('_', ' ')
    return words + unit


def _axis_label(axis: Axis, length_in: float) -> str:
    """An axis in words over its full key (wrapped to ``length_in`` inches), log spacing said."""
    name = axis.name + (' (log spaced)' if axis.spacing == 'logspace' else '')
    return (parameter_label(axis.name) + '\n'
            + wrap_name(name, max(12, int(length_in * _LABEL_CHARS_PER_IN))))


def _legend(fig: Figure, marks: Sequence[tuple[str, str, str, str]]) -> None:
    """Legend of the cell marks used, below the axes."""
    if not marks:
        return
    handles = [Patch(facecolor=face, fill=face != 'none', hatch=hatch, edgecolor=edge,
                     label=label) for label, face, hatch, edge in marks]
    fig.legend(handles=handles, loc='lower center', ncol=len(handles), fontsize=8,
               frameon=False)


def draw_figures(
    sweep: Sweep, points: Sequence[SweepPoint], rows: Mapping[str, Mapping[str, str]],
    directory: Path,
) -> list[Path]:
    """Draw DIR/figures/METRIC.png for every metric of the sweep; returns the files.

    Args:
        sweep: The sweep.
        points: Its grid points (with seeds).
        rows: Table rows by point id (points without a row are drawn empty).
        directory: The sweep's output directory.
    """
    if len(sweep.axes) > 2:
        return []
    out = directory / FIGURE_DIR
    out.mkdir(parents=True, exist_ok=True)
    files = []
    for metric in sweep.metrics:
        path = out / f'{metric}.png'
        metric_figure(sweep, points, rows, metric).savefig(path, dpi=_DPI)
        files.append(path)
    return files


def metric_figure(
    sweep: Sweep, points: Sequence[SweepPoint], rows: Mapping[str, Mapping[str, str]],
    metric: str,
) -> Figure:
    """The figure of one metric over a sweep of one or two axes (see ``draw_figures``)."""
    shape = tuple(len(axis.values) for axis in sweep.axes)
    total = np.zeros(shape)
    count = np.zeros(shape)
    failed = np.zeros(shape, dtype=bool)
    unstable = np.zeros(shape, dtype=bool)
    ended = np.zeros(shape, dtype=bool)
    for point in points:
        row = rows.get(point.point_id)
        if row is None:
            continue
        if row['status'] != 'done':
            failed[point.index] = True
            continue
        unstable[point.index] |= row.get('stable') == 'no'
        ended[point.index] |= row.get('reason') == ENDED_BEFORE_SETTLING
        value = metric_value(row, metric)
        if value is not None:
            total[point.index] += value
            count[point.index] += 1
    with np.errstate(invalid='ignore', divide='ignore'):
        mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    if len(sweep.axes) == 1:
        return _line(sweep, metric, mean, failed, unstable, ended)
    return _heatmap(sweep, metric, mean, failed, unstable, ended)


def _title(sweep: Sweep, metric: str) -> str:
    """Figure title: the metric as ``uvms report`` names it, and the sweep."""
    return f'{metric_label(metric)} over {sweep.name}'


def _heatmap(
    sweep: Sweep, metric: str, mean: np.ndarray, failed: np.ndarray, unstable: np.ndarray,
    ended: np.ndarray,
) -> Figure:
    """Heatmap: first axis along x, second along y, value labels in small grids."""
    x_axis, y_axis = sweep.axes
    nx, ny = mean.shape
    width_in = max(1.2 + 0.9 * nx + 1.5, _MIN_FIGSIZE_IN[0])
    height_in = max(1.2 + 0.6 * ny + 0.8, _MIN_FIGSIZE_IN[1]) + 0.3  # two-line x label
    fig = Figure(figsize=(width_in, height_in))
    ax = fig.subplots()
    grid = np.ma.masked_invalid(mean.T)
    # Colours span the stable cells, so that a diverged run does not flatten the map; the
    # marked cells beyond that range show saturated (their labels give the values).
    steady = mean[np.isfinite(mean) & ~unstable & ~ended]
    limits = (float(steady.min()), float(steady.max())) if steady.size else (None, None)
    image = ax.imshow(grid, origin='lower', aspect='auto', cmap='viridis', vmin=limits[0],
                      vmax=limits[1])
    ax.set_facecolor('0.85')
    fig.colorbar(image, ax=ax, label=metric_label(metric))
    for i in range(nx):
        for j in range(ny):
            if failed[i, j]:
                ax.add_patch(Rectangle((i - 0.5, j - 0.5), 1, 1, facecolor='0.6',
                                       hatch='xx', edgecolor='0.3', linewidth=0.0))
                ax.text(i, j, 'failed', ha='center', va='center', fontsize=7, color='k')
                continue
            for marked, (_, _, hatch, edge) in ((unstable, _UNSTABLE), (ended, _ENDED)):
                if marked[i, j]:
                    ax.add_patch(Rectangle((i - 0.5, j - 0.5), 1, 1, fill=False, hatch=hatch,
                                           edgecolor=edge, linewidth=0.0))
            if np.isfinite(mean[i, j]) and nx * ny <= 100:
                value = mean[i, j]
                shade = float(np.clip(image.norm(value), 0.0, 1.0))
                light = shade < 0.5 if np.isfinite(shade) else True
                ax.text(i, j, f'{value:.3g}', ha='center', va='center', fontsize=7,
                        color='w' if light else 'k')
            elif not np.isfinite(mean[i, j]):
                ax.text(i, j, 'n/a', ha='center', va='center', fontsize=7, color='0.4')
    ax.set_xticks(range(nx), axis_labels(x_axis), rotation=45 if nx > 6 else 0)
    ax.set_yticks(range(ny), axis_labels(y_axis))
    # Axes span about the figure less the colour bar and margins (tight_layout fits them).
    ax.set_xlabel(_axis_label(x_axis, width_in - 2.5))
    ax.set_ylabel(_axis_label(y_axis, height_in - 1.8))
    ax.set_title(_title(sweep, metric), fontsize=10)
    fig.tight_layout(rect=(0.0, 0.07, 1.0, 1.0))
    _legend(fig, [mark for used, mark in ((failed, _FAILED), (unstable, _UNSTABLE),
                                          (ended, _ENDED)) if used.any()])
    return fig


def _line(
    sweep: Sweep, metric: str, mean: np.ndarray, failed: np.ndarray, unstable: np.ndarray,
    ended: np.ndarray,
) -> Figure:
    """Line plot over one axis: numeric values on their own scale, others by position."""
    (axis,) = sweep.axes
    numeric = all(isinstance(v, int | float) and not isinstance(v, bool) for v in axis.values)
    x = np.array(axis.values, dtype=float) if numeric else np.arange(len(axis.values), dtype=float)
    fig = Figure(figsize=(6.4, 4.0))
    ax = fig.subplots()
    ax.plot(x, mean, 'o-', color='tab:blue', label=metric_label(metric))
    finite = mean[np.isfinite(mean)]
    bottom = float(finite.min()) if finite.size else 0.0
    if failed.any():
        ax.plot(x[failed], np.full(int(failed.sum()), bottom), 'x', color='red', markersize=10,
                label='failed')
    if unstable.any():
        ax.plot(x[unstable], mean[unstable], 'o', markerfacecolor='none', color='red',
                markersize=12, label='unstable')
    if ended.any():
        ax.plot(x[ended], mean[ended], 's', markerfacecolor='none', color='darkorange',
                markersize=12, label=ENDED_BEFORE_SETTLING)
    if numeric and log_scale(axis):
        ax.set_xscale('log')
    if not numeric:
        ax.set_xticks(x, axis_labels(axis))
    ax.set_xlabel(_axis_label(axis, 5.0))
    ax.set_ylabel(metric_label(metric))
    ax.set_title(_title(sweep, metric), fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
