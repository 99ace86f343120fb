"""Figures of the fuzzy switch (paper Figs. 4 and 5): membership functions, switching surface."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from uvms_analysis.figure_style import FIGSIZE_TALL, _figure, _save

if TYPE_CHECKING:
    from uvms_control.core.fuzzy_sets import Trapezoid
    from uvms_control.core.law.fuzzy_switch import FuzzySwitch


def _default_switch() -> FuzzySwitch:
    """The controller's fuzzy switch with its default parameters."""
    from uvms_control.core.law.fuzzy_switch import FuzzySwitch

    return FuzzySwitch()


def _span(sets: Sequence[Trapezoid], lo: float, hi: float) -> tuple[float, float]:
    """Plot range covering the finite corners of membership functions, at least [lo, hi]."""
    corners = [value for s in sets for value in (s.a, s.b, s.c, s.d) if math.isfinite(value)]
    low, high = min([lo, *corners]), max([hi, *corners])
    pad = 0.1 * (high - low)
    return low - pad, high + pad


def figure_fuzzy_membership(switch: FuzzySwitch) -> Figure:
    """Membership functions of the inputs F_e/F_d, v_e and the output W (paper Fig. 4)."""
    p = switch.params
    fig = _figure(FIGSIZE_TALL)
    axes = fig.subplots(3, 1)
    groups = (
        (
            'force ratio $F_e/F_d$ (-)',
            ((p.force_small, 'FS'), (p.force_medium, 'FM'), (p.force_large, 'FL')),
            (0.0, 1.2),
        ),
        (
            'normal velocity $v_e$ (m/s), positive towards the wall',
            ((p.velocity_slow, 'VS'), (p.velocity_fast, 'VF')),
            (-0.05, 0.2),
        ),
        (
            'switching weight W (-): 1 impedance, 0 hybrid',
            ((p.weight_small, 'WS'), (p.weight_medium, 'WM'), (p.weight_large, 'WL')),
            (0.0, 1.0),
        ),
    )
    for ax, (xlabel, sets, (lo, hi)) in zip(axes, groups, strict=True):
        x_lo, x_hi = _span([s for s, _ in sets], lo, hi)
        x = np.linspace(x_lo, x_hi, 801)
        for k, (membership, label) in enumerate(sets):
            ax.plot(x, membership(x), color=f'C{k}', linewidth=1.8, label=label)
        ax.set_xlim(x_lo, x_hi)
        ax.set_ylim(-0.05, 1.1)
        ax.set_xlabel(xlabel)
        ax.set_ylabel('membership μ (-)')
        ax.grid(True, alpha=0.4)
        ax.legend(loc='center right', fontsize='small')
    axes[2].axvspan(x_lo, 0.0, color='0.85', linewidth=0)
    axes[2].axvspan(1.0, x_hi, color='0.85', linewidth=0)
    axes[0].set_title('Fuzzy switching law: membership functions')
    return fig


def figure_fuzzy_surface(switch: FuzzySwitch) -> Figure:
    """Switching surface W(F_e/F_d, v_e) as a 3-D surface and a contour map (paper Fig. 5)."""
    ratios = np.linspace(0.0, 1.2, 121)
    velocities = np.linspace(-0.05, 0.25, 121)
    W = switch.surface(ratios, velocities)
    rr, vv = np.meshgrid(ratios, velocities)
    fig = _figure((12.0, 5.0))
    ax3 = fig.add_subplot(1, 2, 1, projection='3d')
    ax3.plot_surface(rr, vv, W, cmap='viridis', linewidth=0, antialiased=True)
    ax3.set_xlabel('$F_e/F_d$ (-)')
    ax3.set_ylabel('$v_e$ (m/s)')
    ax3.set_zlabel('W (-)')
    ax3.set_zlim(0.0, 1.0)
    ax3.view_init(elev=30, azim=-60)
    ax3.set_title('$W(F_e/F_d,\\ v_e)$')
    ax2 = fig.add_subplot(1, 2, 2)
    filled = ax2.contourf(rr, vv, W, levels=np.linspace(0.0, 1.0, 21), cmap='viridis')
    lines = ax2.contour(rr, vv, W, levels=[0.1, 0.25, 0.5, 0.75, 0.9], colors='k', linewidths=0.7)
    ax2.clabel(lines, fontsize='x-small')
    fig.colorbar(filled, ax=ax2, label='W (-): 1 impedance, 0 hybrid')
    ax2.set_xlabel('force ratio $F_e/F_d$ (-)')
    ax2.set_ylabel('normal velocity $v_e$ (m/s)')
    ax2.set_title('contour map')
    ax2.grid(True, alpha=0.3)
    fig.suptitle('Fuzzy switching law: input/output surface')
    return fig


def plot_fuzzy(out_dir: str | Path, switch: FuzzySwitch | None = None) -> list[Path]:
    """Write the fuzzy switch figures (paper Figs. 4 and 5) into ``out_dir``; returns the files.

    Args:
        out_dir: Output directory (created).
        switch: The switch to draw; default: the controller's with default parameters.
    """
    switch = switch if switch is not None else _default_switch()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return [
        _save(figure_fuzzy_membership(switch), out / 'fuzzy_membership.png'),
        _save(figure_fuzzy_surface(switch), out / 'fuzzy_surface.png'),
    ]
