"""What ``uvms identify fit`` writes: hydrodynamics.yaml, report.md and the figures."""

from __future__ import annotations

import datetime
import hashlib
import math
import subprocess
from pathlib import Path

import numpy as np
import yaml
from numpy.typing import NDArray

from uvms_identify.actuator_output import report_lines
from uvms_identify.identify import HORIZONS_S, Identification, driven
from uvms_identify.known_terms import ZERO_HULL, model_with_hull, net_buoyancy_n
from uvms_identify.predict import simulate
from uvms_identify.recording import gaps_text
from uvms_identify.regressor import (
    ADDED_MASS,
    AXES,
    BUOYANCY,
    BUOYANCY_MOMENT,
    LINEAR_DAMPING,
    PARAMETER_NAMES,
    QUADRATIC_DAMPING,
    unit,
)
from uvms_identify.robot_data import ROOT_LINK

FloatArray = NDArray[np.float64]


def git_commit() -> str:
    """The commit of the source checkout this runs from, or 'unknown'."""
    try:
        result = subprocess.run(['git', 'rev-parse', 'HEAD'], cwd=Path(__file__).parent,
                                capture_output=True, text=True, check=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return 'unknown'
    return result.stdout.strip() or 'unknown'


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open('rb') as stream:
        for block in iter(lambda: stream.read(1 << 20), b''):
            digest.update(block)
    return digest.hexdigest()[:16]


def _vector(values: FloatArray) -> str:
    return '[' + ', '.join(f'{float(v):.6g}' for v in values) + ']'


def hull_entry(result: Identification) -> dict[str, object]:
    """The hull's entry of the identified hydrodynamics file (coefficients form)."""
    theta = result.fit.theta
    robot = result.robot
    buoyancy = float(theta[BUOYANCY])
    volume = buoyancy / (robot.water_density_kg_m3 * robot.gravity_m_s2)
    center = theta[BUOYANCY_MOMENT] / buoyancy if buoyancy > 0.0 else np.zeros(3)
    return {'added_mass': 'coefficients',
            'added_mass_kg': [float(v) for v in theta[ADDED_MASS]],
            'linear_damping': [float(v) for v in theta[LINEAR_DAMPING]],
            'quadratic_damping': [float(v) for v in theta[QUADRATIC_DAMPING]],
            'displaced_volume_m3': float(volume),
            'center_of_buoyancy_m': [float(v) for v in center]}


def provenance(result: Identification, figures: list[Path]) -> list[str]:
    """Comment lines: when, from which commit, the recordings (sha256 prefix), the figures."""
    return [
        f'# Written {datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")} from '
        f'commit {git_commit()}.',
        '# Recordings (sha256 prefix):',
        *(f'#   {path} ({_sha256(path)})' for path in result.recordings),
        '# Fit figures: ' + ', '.join(p.name for p in figures) + ' (beside report.md).',
    ]


def write_hydrodynamics(result: Identification, out: Path, figures: list[Path]) -> Path:
    """DIR/hydrodynamics.yaml: the robot folder's file with the identified hull, provenance."""
    robot = result.robot
    tree = yaml.safe_load(robot.files.hydrodynamics.read_text(encoding='utf-8'))
    hull = hull_entry(result)
    fit = result.fit
    lines = [
        f'# Hydrodynamic parameters of robot {robot.name}: the hull ({ROOT_LINK}) identified by',
        '# `uvms identify fit` (docs/identification.md); the arm links as in the robot folder.',
        *provenance(result, figures),
        '# Prior (terms the data could not identify keep it): '
        f'{robot.files.hydrodynamics}',
        f'# Thrust delay: {1000 * result.delay_s:+.0f} ms (the recorded thrust at t acts at '
        "t + delay; fitted with the terms, not a key of this file); the thrusters' gain and "
        'lag: thrusters.yaml and report.md.',
        '# Per term: fitted value +- 95 % CI, or why it kept the prior:',
    ]
    for j, name in enumerate(PARAMETER_NAMES):
        ci = '' if math.isnan(fit.ci95[j]) else f' +- {fit.ci95[j]:.3g}'
        lines.append(f'#   {name} = {fit.theta[j]:.4g}{ci} {unit(j)} ({fit.status[j]})')
    lines += [
        '',
        f'{ROOT_LINK}:',
        '  added_mass: coefficients',
        f'  added_mass_kg: {_vector(np.array(hull["added_mass_kg"]))}  # -X_u_dot, -Y_v_dot, '
        '-Z_w_dot (kg); -K_p_dot, -M_q_dot, -N_r_dot (kg m^2)',
        f'  linear_damping: {_vector(np.array(hull["linear_damping"]))}  # -X_u, -Y_v, -Z_w '
        '(N s/m); -K_p, -M_q, -N_r (N m s/rad)',
        f'  quadratic_damping: {_vector(np.array(hull["quadratic_damping"]))}  # (N s^2/m^2; '
        'N m s^2/rad^2)',
        f'  displaced_volume_m3: {hull["displaced_volume_m3"]:.6g}  # hull buoyancy '
        f'{fit.theta[BUOYANCY]:.4g} N / (rho g)',
        f'  center_of_buoyancy_m: {_vector(np.array(hull["center_of_buoyancy_m"]))}  # '
        f'base_link_frd (m)',
        '',
    ]
    others = {link: entry for link, entry in tree.items() if link != ROOT_LINK}
    text = '\n'.join(lines) + yaml.safe_dump(others, sort_keys=False)
    path = out / 'hydrodynamics.yaml'
    path.write_text(text, encoding='utf-8')
    return path


def write_figures(result: Identification, out: Path) -> list[Path]:
    """One PNG per held-out part: measured and predicted velocity per axis."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    model = model_with_hull(result.robot, ZERO_HULL)
    paths = []
    for series in result.held_out:
        if len(series.t_s) < 3:
            continue
        steps = len(series.t_s) - 1
        identified = simulate(model, result.fit.theta, driven(series, result.thrust), 0,
                              steps)
        current = simulate(model, result.prior, series, 0, steps)
        figure, axes = plt.subplots(3, 2, figsize=(11, 8), sharex=True)
        for axis in range(6):
            ax = axes[axis % 3, axis // 3]
            ax.plot(series.t_s, series.nu[:, axis], 'k', lw=1.2, label='measured (DVL/IMU)')
            ax.plot(series.t_s, identified[:, axis], 'C0', lw=1.0, label='identified')
            ax.plot(series.t_s, current[:, axis], 'C3--', lw=1.0, label='robot folder')
            ax.set_ylabel(f'{AXES[axis]} ({"m/s" if axis < 3 else "rad/s"})')
            ax.grid(alpha=0.3)
        axes[2, 0].set_xlabel('time in recording (s)')
        axes[2, 1].set_xlabel('time in recording (s)')
        axes[0, 0].legend(fontsize=8)
        figure.suptitle(f'{series.source.name}: held-out part, velocity predicted from its start')
        figure.tight_layout()
        stem = f'{series.source.stem}_velocity'
        count = sum(p.stem.startswith(stem) for p in paths)
        path = out / (f'{stem}.png' if count == 0 else f'{stem}_{count + 1}.png')
        figure.savefig(path, dpi=90)
        plt.close(figure)
        paths.append(path)
    return paths


def write_report(result: Identification, out: Path, figures: list[Path]) -> Path:
    """DIR/report.md: per axis the fit, its 95 % CI, R^2 and the held-out errors."""
    fit = result.fit
    robot = result.robot
    lines = [f'# Identification of robot {robot.name}', '',
             f'Recordings: {", ".join(str(p) for p in result.recordings)}; '
             f'{fit.samples} samples fitted (the first '
             f'{100 * (1 - 0.3):.0f} % of each), condition number {fit.condition_number:.3g} '
             "(column-normalized). Prior and comparison: the robot folder's "
             f'{robot.files.hydrodynamics}.', '',
             'Gaps left out (with the smoothing window around each): '
             f'{gaps_text(result.gaps_s)}.', '',
             f'Thrust delay: {1000 * result.delay_s:+.0f} ms: the recorded thrusts fit best as '
             'acting this much later (negative: earlier) than stamped; searched over '
             '-40..+80 ms with the thrusters\' gain and lag and the terms ("Actuators" below); '
             'the held-out predictions of the identified model use them, those of the robot '
             'folder do not.', '',
             '## Terms', '',
             '| term | identified | 95 % CI | robot folder | change | status |',
             '| --- | --- | --- | --- | --- | --- |']
    for j, name in enumerate(PARAMETER_NAMES):
        ci = 'n/a' if math.isnan(fit.ci95[j]) else f'+- {fit.ci95[j]:.3g}'
        prior = result.prior[j]
        change = f'{100 * (fit.theta[j] - prior) / prior:+.0f} %' if prior else 'n/a'
        lines.append(f'| {name} ({unit(j)}) | {fit.theta[j]:.4g} | {ci} | {prior:.4g} | '
                     f'{change} | {fit.status[j]} |')
    buoyancy = float(fit.theta[BUOYANCY])
    center = fit.theta[BUOYANCY_MOMENT] / buoyancy if buoyancy > 0 else np.zeros(3)
    net = net_buoyancy_n(robot, buoyancy)
    net_prior = net_buoyancy_n(robot, float(result.prior[BUOYANCY]))
    lines += ['', f'Net buoyancy (hull and arm links minus the weight, level, arm at its start '
              f'pose): {net:+.3g} N identified, {net_prior:+.3g} N robot folder; hull '
              f'buoyancy {buoyancy:.4g} N at the centre of buoyancy {_vector(center)} m '
              '(base_link_frd).', '',
              'Well determined (95 % CI within 10 % of the value): '
              + (', '.join(n for j, n in enumerate(PARAMETER_NAMES) if fit.well_determined(j))
                 or 'none') + '.', '',
              '## Per axis', '',
              '| axis | R^2 (force) | residual std | '
              + ' | '.join(f'held-out {h:g} s: identified / robot folder' for h in HORIZONS_S)
              + ' |', '| --- | --- | --- | ' + ' | '.join('---' for _ in HORIZONS_S) + ' |']
    for axis in range(6):
        speed = 'm/s' if axis < 3 else 'rad/s'
        cells = []
        for horizon in HORIZONS_S:
            mine = result.errors.get(('identified', horizon))
            theirs = result.errors.get(('current', horizon))
            if mine is None or theirs is None:
                cells.append('n/a')
            else:
                cells.append(f'{mine[axis]:.3g} / {theirs[axis]:.3g} {speed}')
        lines.append(f'| {AXES[axis]} | {fit.r2[axis]:.3f} | '
                     f'{fit.residual_std[axis]:.3g} {"N" if axis < 3 else "N m"} | '
                     + ' | '.join(cells) + ' |')
    windows = ', '.join(f'{count} windows of {h:g} s' for h, count in result.windows.items())
    lines += ['', f'Held-out errors: RMS of the velocity error at the horizon, predicted from '
              f'the measured velocity and attitude with the recorded thrusts and arm ({windows}, '
              'the last 30 % of each recording; each axis over the recordings that excite it '
              'most, all recordings for an axis none excites most).', '',
              *report_lines(result), '## Figures', '']
    lines += [f'![{p.stem}]({p.name})' for p in figures]
    path = out / 'report.md'
    path.write_text('\n'.join(lines) + '\n', encoding='utf-8')
    return path
