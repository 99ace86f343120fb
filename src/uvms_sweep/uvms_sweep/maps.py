"""Figures of a sweep: one PNG per metric, a heatmap over two axes or a line over one.

Drawn on ``matplotlib.figure.Figure`` with the Agg canvas, without pyplot (as ``plots``).

A cell (or a point of the line) is the mean of the metric over the seeds that ran. Cells
where a seed failed are grey with a cross hatch (``xx``) and the label ``failed``; cells
where a seed ran unstable (``sweep_table.stability``) carry a diagonal hatch (``//``), and
the colour scale spans the other cells (an unstable cell beyond it shows saturated); in
line plots failed points are red crosses at the bottom and unstable ones open red circles.
Sweeps over three or more axes get the table only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Rectangle

from uvms_sweep.sweep_file import Sweep, SweepPoint, axis_labels
from uvms_sweep.table import metric_value

FIGURE_DIR = 'figures'
_DPI = 110


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
    shape = tuple(len(axis.values) for axis in sweep.axes)
    files = []
    for metric in sweep.metrics:
        total = np.zeros(shape)
        count = np.zeros(shape)
        failed = np.zeros(shape, dtype=bool)
        unstable = np.zeros(shape, dtype=bool)
        for point in points:
            row = rows.get(point.point_id)
            if row is None:
                continue
            if row['status'] != 'done':
                failed[point.index] = True
                continue
            unstable[point.index] |= row.get('stable') == 'no'
            value = metric_value(row, metric)
            if value is not None:
                total[point.index] += value
                count[point.index] += 1
        with np.errstate(invalid='ignore', divide='ignore'):
            mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
        path = out / f'{metric}.png'
        if len(sweep.axes) == 1:
            _line(sweep, metric, mean, failed, unstable, path)
        else:
            _heatmap(sweep, metric, mean, failed, unstable, path)
        files.append(path)
    return files


def _title(sweep: Sweep, metric: str) -> str:
    """Figure title: metric and sweep."""
    return f'{metric} over {sweep.name}'


def _heatmap(
    sweep: Sweep, metric: str, mean: np.ndarray, failed: np.ndarray, unstable: np.ndarray,
    path: Path,
) -> None:
    """Heatmap: first axis along x, second along y, value labels in small grids."""
    x_axis, y_axis = sweep.axes
    nx, ny = mean.shape
    fig = Figure(figsize=(1.2 + 0.9 * nx + 1.5, 1.2 + 0.6 * ny + 0.8))
    ax = fig.subplots()
    grid = np.ma.masked_invalid(mean.T)
    # Colours span the stable cells, so that a diverged run does not flatten the map; the
    # unstable cells beyond that range show saturated (their labels give the values).
    steady = mean[np.isfinite(mean) & ~unstable]
    limits = (float(steady.min()), float(steady.max())) if steady.size else (None, None)
    image = ax.imshow(grid, origin='lower', aspect='auto', cmap='viridis', vmin=limits[0],
                      vmax=limits[1])
    ax.set_facecolor('0.85')
    fig.colorbar(image, ax=ax, label=metric)
    for i in range(nx):
        for j in range(ny):
            if failed[i, j]:
                ax.add_patch(Rectangle((i - 0.5, j - 0.5), 1, 1, facecolor='0.6',
                                       hatch='xx', edgecolor='0.3', linewidth=0.0))
                ax.text(i, j, 'failed', ha='center', va='center', fontsize=7, color='k')
                continue
            if unstable[i, j]:
                ax.add_patch(Rectangle((i - 0.5, j - 0.5), 1, 1, fill=False, hatch='//',
                                       edgecolor='red', linewidth=0.0))
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
    ax.set_xlabel(x_axis.name + (' (log spaced)' if x_axis.spacing == 'logspace' else ''))
    ax.set_ylabel(y_axis.name + (' (log spaced)' if y_axis.spacing == 'logspace' else ''))
    ax.set_title(_title(sweep, metric), fontsize=10)
    handles = [Patch(facecolor='0.6', hatch='xx', edgecolor='0.3', label='failed'),
               Patch(fill=False, hatch='//', edgecolor='red', label='unstable')]
    fig.tight_layout(rect=(0.0, 0.07, 1.0, 1.0))
    fig.legend(handles=handles, loc='lower center', ncol=2, fontsize=8, frameon=False)
    fig.savefig(path, dpi=_DPI)


def _line(
    sweep: Sweep, metric: str, mean: np.ndarray, failed: np.ndarray, unstable: np.ndarray,
    path: Path,
) -> None:
    """Line plot over one axis: numeric values on their own scale, others by position."""
    (axis,) = sweep.axes
    numeric = all(isinstance(v, int | float) and not isinstance(v, bool) for v in axis.values)
    x = np.array(axis.values, dtype=float) if numeric else np.arange(len(axis.values), dtype=float)
    fig = Figure(figsize=(6.4, 4.0))
    ax = fig.subplots()
    ax.plot(x, mean, 'o-', color='tab:blue', label=metric)
    finite = mean[np.isfinite(mean)]
    bottom = float(finite.min()) if finite.size else 0.0
    if failed.any():
        ax.plot(x[failed], np.full(int(failed.sum()), bottom), 'x', color='red', markersize=10,
                label='failed')
    if unstable.any():
        ax.plot(x[unstable], mean[unstable], 'o', markerfacecolor='none', color='red',
                markersize=12, label='unstable')
    if axis.spacing == 'logspace':
        ax.set_xscale('log')
    if not numeric:
        ax.set_xticks(x, axis_labels(axis))
    ax.set_xlabel(axis.name)
    ax.set_ylabel(metric)
    ax.set_title(_title(sweep, metric), fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=_DPI)
