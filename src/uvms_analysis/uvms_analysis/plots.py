"""`uvms plot`: the paper's figures (Cui & Sarkar, sec. 5) as PNG files from a recording.

Figures are drawn on ``matplotlib.figure.Figure`` objects with the Agg canvas, without pyplot,
so no display and no global figure state are involved.

| file | paper figure |
| --- | --- |
| trajectory_xz.png | 7, 13: end-effector path in the x-z plane with the wall |
| force_response.png | 8, 9, 11, 12, 15: contact force F_e against F_d |
| position_errors_weight.png | 10: position errors X_d - X and fuzzy weight W |
| vehicle_motion.png | 14: vehicle position and attitude change |
| thrusters.png | (extra) thrusts, propeller speeds; η̂, faults and detections (health) |
| pilot_session.png | (extra, where a pilot drove) vehicle, heading, arm, force by mode |
| fuzzy_membership.png | 4: membership functions of the fuzzy switch (``--fuzzy``) |
| fuzzy_surface.png | 5: switching surface W(F_e/F_d, v_e) (``--fuzzy``) |
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from uvms_analysis.figure_style import FIGSIZE_TALL, _figure, _save
from uvms_analysis.fuzzy_plots import plot_fuzzy
from uvms_analysis.metrics import SETTLING_BAND, compute_metrics, contact_intervals, normal_force
from uvms_analysis.pilot_plots import PILOT_SESSION_FIGURE, figure_pilot_session
from uvms_analysis.series import AnalysisError, CurrentSeries, FloatArray, Run, load_run
from uvms_analysis.thruster_health import draw_health_panel, injected_faults

AXIS_COLORS = ('tab:red', 'tab:green', 'tab:blue')

#: Line widths (pt) of the force figure: measured force wide underneath, ground truth thin on top.
MEASURED_FORCE_WIDTH = 2.6
GROUND_TRUTH_FORCE_WIDTH = 0.9


class PlotError(Exception):
    """A figure cannot be drawn as asked."""


def _shade_contact(ax: Axes, run: Run, label: bool = True) -> None:
    """Shade the time intervals in which the end effector touches the wall."""
    force = normal_force(run)
    if force is None:
        return
    for i, (start, stop) in enumerate(contact_intervals(force.in_contact)):
        end = force.t[min(stop, force.t.size - 1)]
        ax.axvspan(
            force.t[start],
            end,
            color='tab:orange',
            alpha=0.12,
            linewidth=0,
            label='in contact' if label and i == 0 else None,
        )


def figure_trajectory(run: Run) -> Figure | None:
    """End-effector path in the x-z plane of map_ned with the wall (paper Figs. 7 and 13)."""
    if run.controller is None and run.ee_pose is None:
        return None
    fig = _figure()
    ax = fig.add_subplot()
    if run.controller is not None:
        X_d = run.controller.X_d
        ax.plot(X_d[:, 0], X_d[:, 2], '--', color='0.4', label='desired $X_d$')
    if run.ee_pose is not None:
        t, X = run.ee_pose.t, run.ee_pose.position
    else:
        assert run.controller is not None
        t, X = run.controller.t, run.controller.X
    ax.plot(X[:, 0], X[:, 2], color='tab:blue', linewidth=1.8, label='actual $X$')
    ax.plot(X[0, 0], X[0, 2], 'o', color='tab:blue', label=f'start (t = {t[0]:.1f} s)')
    if run.contact is not None and run.contact.t.size:
        _draw_wall(ax, run, t, X)
    ax.set_aspect('equal', adjustable='datalim')
    ax.invert_yaxis()
    ax.set_xlabel('x (m), map_ned north, towards the wall')
    ax.set_ylabel('z (m), map_ned down')
    ax.set_title(f'End-effector trajectory in the x-z plane: {run.name}')
    ax.grid(True, alpha=0.4)
    ax.legend(loc='best', fontsize='small')
    return fig


def _draw_wall(ax: Axes, run: Run, t: FloatArray, X: FloatArray) -> None:
    """Wall surface (and its motion), and the points where contact starts and ends."""
    assert run.contact is not None
    contact = run.contact
    wall = contact.wall_position
    z_lo, z_hi = float(np.min(X[:, 2])), float(np.max(X[:, 2]))
    margin = 0.1 * max(z_hi - z_lo, 0.05)
    ax.vlines(
        wall[0],
        z_lo - margin,
        z_hi + margin,
        color='k',
        linewidth=2.5,
        label=f'wall at t = {contact.t[0]:.1f} s',
    )
    if float(np.ptp(wall)) > 1e-4:
        # Where the moving wall was while the end effector touched it: its surface at the
        # contact point. Out of contact the wall's x at the end effector's depth means nothing.
        z_at_wall_time = np.interp(contact.t, t, X[:, 2])
        ax.plot(
            np.where(contact.in_contact, wall, np.nan),
            z_at_wall_time,
            color='0.3',
            linewidth=1.2,
            label='wall at the contact point',
        )
        ax.vlines(
            wall[-1],
            z_lo - margin,
            z_hi + margin,
            color='k',
            linewidth=1.2,
            linestyles=':',
            label=f'wall at t = {contact.t[-1]:.1f} s',
        )
    for i, (start, stop) in enumerate(contact_intervals(contact.in_contact)):
        t_start, t_end = contact.t[start], contact.t[stop - 1]
        start_x, start_z = np.interp(t_start, t, X[:, 0]), np.interp(t_start, t, X[:, 2])
        end_x, end_z = np.interp(t_end, t, X[:, 0]), np.interp(t_end, t, X[:, 2])
        ax.plot(
            start_x,
            start_z,
            'v',
            color='tab:green',
            markersize=9,
            label='contact starts' if i == 0 else None,
        )
        ax.plot(
            end_x,
            end_z,
            '^',
            color='tab:red',
            markersize=9,
            label='contact ends' if i == 0 else None,
        )


def figure_force_response(run: Run) -> Figure | None:
    """Contact force along the wall normal against the desired force (Figs. 8, 9, 11, 12, 15)."""
    if run.controller is None and run.contact is None:
        return None
    fig = _figure()
    ax = fig.add_subplot()
    _shade_contact(ax, run)
    # Without sensor noise the two forces coincide: the measured force is drawn wide underneath
    # and the ground truth thin, dashed and on top, so that both stay visible.
    if run.controller is not None:
        ctrl = run.controller
        ax.plot(
            ctrl.t,
            ctrl.F_e[:, 0],
            color='tab:blue',
            linewidth=MEASURED_FORCE_WIDTH,
            zorder=2,
            label='$F_e$ measured (controller)',
        )
    if run.contact is not None:
        ax.plot(
            run.contact.t,
            run.contact.force[:, 0],
            '--',
            color='k',
            linewidth=GROUND_TRUTH_FORCE_WIDTH,
            zorder=3,
            label='$F_e$ ground truth (simulator)',
        )
    metrics = compute_metrics(run)
    if run.controller is not None:
        f_d = run.controller.F_d[:, 0]
        ax.plot(run.controller.t, f_d, '--', color='tab:red', linewidth=1.4, label='$F_d$')
        ax.fill_between(
            run.controller.t,
            f_d * (1 - SETTLING_BAND),
            f_d * (1 + SETTLING_BAND),
            color='tab:red',
            alpha=0.10,
            linewidth=0,
            label=f'$F_d$ ± {SETTLING_BAND:.0%}',
        )
    lines = [
        f'{label}: {value}'
        for label, value in (
            ('peak', _fmt(metrics.peak_force, 'N')),
            ('overshoot', _fmt(metrics.overshoot, '%')),
            ('impact peak', _fmt(metrics.impact_peak_force, 'N')),
            ('settling', _fmt(metrics.settling_time, 's', 3)),
        )
    ]
    ax.text(
        0.99,
        0.5,
        '\n'.join(lines),
        transform=ax.transAxes,
        va='center',
        ha='right',
        fontsize='small',
        bbox={'boxstyle': 'round', 'facecolor': 'white', 'alpha': 0.85},
    )
    ax.set_xlabel('time t (s)')
    ax.set_ylabel('contact force along the wall normal x (N)')
    ax.set_title(f'Force response: {run.name}')
    ax.grid(True, alpha=0.4)
    ax.legend(loc='center left', fontsize='small')
    return fig


def _fmt(value: float | None, unit: str, digits: int = 1) -> str:
    """A metric for an annotation, 'n/a' for None."""
    return 'n/a' if value is None else f'{value:.{digits}f} {unit}'


def figure_position_errors(run: Run) -> Figure | None:
    """Position errors X_d - X per axis and the fuzzy weight W over time (paper Fig. 10)."""
    if run.controller is None:
        return None
    ctrl = run.controller
    error_mm = (ctrl.X_d - ctrl.X) * 1e3
    fig = _figure(FIGSIZE_TALL)
    axes = fig.subplots(4, 1, sharex=True)
    for k, (ax, axis) in enumerate(zip(axes[:3], 'XYZ', strict=True)):
        _shade_contact(ax, run, label=k == 0)
        ax.plot(ctrl.t, error_mm[:, k], color=AXIS_COLORS[k], label=f'${axis}_d - {axis}$')
        ax.set_ylabel(f'{axis.lower()} error (mm)')
        ax.grid(True, alpha=0.4)
        ax.legend(loc='upper right', fontsize='small')
    _shade_contact(axes[3], run, label=False)
    axes[3].plot(ctrl.t, ctrl.W, color='tab:purple', label='W (1 impedance, 0 hybrid)')
    axes[3].set_ylim(-0.05, 1.05)
    axes[3].set_ylabel('weight W (-)')
    axes[3].set_xlabel('time t (s)')
    axes[3].grid(True, alpha=0.4)
    axes[3].legend(loc='upper right', fontsize='small')
    axes[0].set_title(f'Position errors (map_ned) and fuzzy weight: {run.name}')
    return fig


def figure_vehicle_motion(run: Run) -> Figure | None:
    """Vehicle position and attitude change from the start over time (paper Fig. 14).

    With an ocean current in the recording, a third panel shows it (map_ned, m/s).
    """
    if run.odometry is None or run.odometry.t.size == 0:
        return None
    odom = run.odometry
    current = run.current if run.current is not None and run.current.t.size else None
    fig = _figure(FIGSIZE_TALL)
    axes = fig.subplots(2 if current is None else 3, 1, sharex=True)
    ax_p, ax_a = axes[0], axes[1]
    _shade_contact(ax_p, run)
    _shade_contact(ax_a, run, label=False)
    if current is not None:
        _draw_current(axes[2], run, current)
    displacement_mm = (odom.position - odom.position[0]) * 1e3
    for k, axis in enumerate('xyz'):
        ax_p.plot(odom.t, displacement_mm[:, k], color=AXIS_COLORS[k],
                  label=f'{axis} - {axis}$_0$ ({odom.position[0, k]:+.3f} m)')
    rpy_deg = np.degrees(np.unwrap(odom.rpy, axis=0) - odom.rpy[0])
    for k, angle in enumerate(('roll φ', 'pitch θ', 'yaw ψ')):
        ax_a.plot(odom.t, rpy_deg[:, k], color=AXIS_COLORS[k],
                  label=f'{angle} ({math.degrees(odom.rpy[0, k]):+.2f}° at start)')
    ax_p.set_ylabel('position change, map_ned (mm)')
    ax_a.set_ylabel('attitude change (deg)')
    axes[-1].set_xlabel('time t (s)')
    ax_p.set_title(f'Vehicle motion during force control: {run.name}')
    for ax in axes:
        ax.grid(True, alpha=0.4)
        ax.legend(loc='best', fontsize='small')
    return fig


def _draw_current(ax: Axes, run: Run, current: CurrentSeries) -> None:
    """The ocean current's components in map_ned (m/s) and its speed."""
    _shade_contact(ax, run, label=False)
    for k, axis in enumerate(('north', 'east', 'down')):
        ax.plot(current.t, current.velocity[:, k], color=AXIS_COLORS[k], label=f'{axis}')
    ax.plot(current.t, np.linalg.norm(current.velocity, axis=1), color='black', lw=0.8,
            ls='--', label='speed')
    ax.set_ylabel('ocean current, map_ned (m/s)')


#: Line style and marker per thruster: symmetric thrusters carry the same thrust, so their
#: lines overlap exactly; a dash pattern and markers placed at staggered samples keep each
#: one visible and matched to the legend where colour alone would hide it.
THRUSTER_STYLES = (('-', 'o'), ('--', 's'), ('-.', '^'), ((0, (1, 1)), 'v'),
                   ((0, (5, 1, 1, 1, 1, 1)), 'D'), ((0, (3, 2)), 'P'), ((0, (8, 2)), 'X'),
                   ((0, (1, 2, 4, 2)), '*'))
#: Markers per thruster line (spread over the run, staggered between thrusters).
_THRUSTER_MARKERS = 12


def figure_thrusters(run: Run) -> Figure | None:
    """Actual and allocated thrust and propeller speed of every thruster over time.

    Each thruster has its own colour, dash pattern and marker (``THRUSTER_STYLES``); the
    allocated thrust is the thin, faint line of the same colour.
    """
    if run.thrusters is None or run.thrusters.t.size == 0:
        return None
    thr = run.thrusters
    fig = _figure(FIGSIZE_TALL)
    axes = fig.subplots(2 if run.health is None else 3, 1, sharex=True)
    ax_f, ax_w = axes[0], axes[1]
    if run.health is not None:  # η̂, injected faults and detections (issue 32)
        draw_health_panel(axes[2], run.health, injected_faults(run.metadata),
                          run.time_origin_ns * 1e-9)
    count = thr.actual_thrust.shape[1]
    spacing = max(1, thr.t.size // _THRUSTER_MARKERS)
    for i in range(count):
        linestyle, marker = THRUSTER_STYLES[i % len(THRUSTER_STYLES)]
        style = {'color': f'C{i % 10}', 'linestyle': linestyle}
        marks = {'marker': marker, 'markersize': 4.0, 'fillstyle': 'none',
                 'markevery': (i * spacing // max(count, 1), spacing)}
        ax_f.plot(thr.t, thr.actual_thrust[:, i], linewidth=1.1, label=f'T{i + 1}',
                  **style, **marks)
        ax_f.plot(thr.t, thr.desired_thrust[:, i], linewidth=0.7, alpha=0.45, **style)
        ax_w.plot(thr.t, thr.propeller_speed[:, i], linewidth=1.1, **style, **marks)
    ax_f.plot([], [], color='0.3', linewidth=0.7, alpha=0.45, label='allocated')
    ax_f.set_ylabel('thrust (N)')
    ax_w.set_ylabel('propeller speed Ω (rad/s)')
    axes[-1].set_xlabel('time t (s)')
    ax_f.set_title(f'Thrusters, actual (with markers) and allocated (faint): {run.name}')
    # Under the time axis: beside the axes at the top right the legend covered the title's end.
    fig.legend(*ax_f.get_legend_handles_labels(), loc='outside lower center', fontsize='small',
               ncols=min(count + 1, 9))
    for ax in axes:
        ax.grid(True, alpha=0.4)
    return fig


#: Recording figures by file name, in the order they are written.
RECORDING_FIGURES: dict[str, tuple[Callable[[Run], Figure | None], str]] = {
    'trajectory_xz.png': (figure_trajectory, '/uvms/controller/state or /uvms/ee_pose'),
    'force_response.png': (figure_force_response, '/uvms/controller/state or /uvms/contact'),
    'position_errors_weight.png': (figure_position_errors, '/uvms/controller/state'),
    'vehicle_motion.png': (figure_vehicle_motion, '/uvms/odometry'),
    'thrusters.png': (figure_thrusters, '/uvms/thrusters/state'),
}


def plot_run(run: Run, out_dir: str | Path) -> list[Path]:
    """Write the recording figures of a run into ``out_dir`` (created); returns the files.

    A figure whose topics the run lacks is skipped with a note on stderr.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, (make, needs) in RECORDING_FIGURES.items():
        fig = make(run)
        if fig is None:
            print(f'uvms plot: skipped {name}: the recording has no {needs}', file=sys.stderr)
            continue
        written.append(_save(fig, out / name))
    pilot = figure_pilot_session(run)  # only where a pilot drove: no note otherwise
    if pilot is not None:
        written.append(_save(pilot, out / PILOT_SESSION_FIGURE))
    return written


def plot_recording(path: str | Path, out_dir: str | Path) -> list[Path]:
    """Read a recording and write its figures into ``out_dir``; returns the files.

    Raises:
        AnalysisError: The recording cannot be read.
    """
    run = load_run(path)
    if run.problem is not None:
        print(f'uvms plot: warning: {run.problem}', file=sys.stderr)
    return plot_run(run, out_dir)


# --------------------------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of `uvms plot`."""
    parser = argparse.ArgumentParser(
        prog='uvms plot',
        description="Draw the paper's figures (PNG) from a UVMS recording, and/or the fuzzy "
        'switch (--fuzzy).',
    )
    parser.add_argument('recording', nargs='?', metavar='F.mcap', help='recording to plot')
    parser.add_argument(
        '--out',
        metavar='DIR',
        help='output directory (default: the recording path without .mcap, or ./fuzzy_switch '
        'with --fuzzy alone)',
    )
    parser.add_argument(
        '--fuzzy',
        action='store_true',
        help='also draw the fuzzy switch: membership functions (Fig. 4), surface (Fig. 5)',
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run `uvms plot` with the arguments after the subcommand; returns the exit status.

    Prints each written file on its own line.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else 2
    if args.recording is None and not args.fuzzy:
        print('uvms plot: error: give a recording (F.mcap), --fuzzy, or both', file=sys.stderr)
        return 2
    if args.out is not None:
        out = Path(args.out)
    elif args.recording is not None:
        out = Path(args.recording).with_suffix('')
    else:
        out = Path('fuzzy_switch')
    written: list[Path] = []
    try:
        if args.recording is not None:
            written += plot_recording(args.recording, out)
        if args.fuzzy:
            written += plot_fuzzy(out)
    except (AnalysisError, PlotError, OSError) as exc:
        print(f'uvms plot: error: {exc}', file=sys.stderr)
        return 1
    for path in written:
        print(path)
    return 0


if __name__ == '__main__':
    sys.exit(main())
