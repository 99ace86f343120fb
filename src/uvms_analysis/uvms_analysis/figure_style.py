"""Common frame of `uvms plot`'s figures: standard size and resolution, PNG output."""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

#: Size (in) and resolution (dpi) of single-panel figures: 960 x 600 px.
FIGSIZE = (8.0, 5.0)
FIGSIZE_TALL = (8.0, 8.5)
DPI = 120


def _figure(size: tuple[float, float] = FIGSIZE) -> Figure:
    """A new figure with the standard size and resolution."""
    return Figure(figsize=size, dpi=DPI, layout='constrained')


def _save(fig: Figure, path: Path) -> Path:
    """Write a figure as PNG."""
    fig.savefig(path, dpi=DPI)
    return path
