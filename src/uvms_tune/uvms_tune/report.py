"""The tune's report: default, hand-tuned and tuned gains on the training and held-out sets.

``report.md`` holds the table (mean and worst objective, mean RMS force error / F_d,
overshoot and settling time, failed runs) and every scenario run's figures of the tuned
gains; ``figures/`` holds the best objective against trial, each gain against the objective,
and the tuned run's normal force beside the defaults'.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from optuna.trial import FrozenTrial

from uvms_tune.objective import ScenarioFigures

#: The gain sets of the report, in table order.
SETS = ('defaults', 'hand_tuned', 'tuned')


@dataclass
class SetFigures:
    """One gain set's figures on the training and held-out runs."""

    name: str
    train: list[ScenarioFigures]
    held_out: list[ScenarioFigures]


def summary_row(name: str, split: str, figures: Sequence[ScenarioFigures],
                worst_weight: float) -> str:
    """One markdown row: the set, the split and its aggregated figures."""
    if not figures:
        return f'| {name} | {split} | - | - | - | - | - | 0 |'
    ok = [f for f in figures if f.score is not None]
    failed = len(figures) - len(ok)

    def mean(key: str, scale: float = 1.0) -> str:
        values = [float(f.metrics[key]) * scale / (abs(float(f.metrics['desired_force_N']))
                                                   if key == 'force_rms_error_N' else 1.0)
                  for f in ok if f.metrics.get(key) is not None]
        return f'{sum(values) / len(values):.4g}' if values else 'n/a'

    scores = [float(f.score) for f in ok if f.score is not None]
    objective = ((1 - worst_weight) * sum(scores) / len(scores) + worst_weight * max(scores)
                 if scores and not failed else math.nan)
    worst = max(scores) if scores else math.nan
    return (f'| {name} | {split} | {objective:.4g} | {worst:.4g} | '
            f'{mean("force_rms_error_N")} | {mean("overshoot_percent")} | '
            f'{mean("settling_time_s")} | {failed} |')


def report_text(title: str, sets: Sequence[SetFigures], worst_weight: float,
                notes: Sequence[str]) -> str:
    """The markdown report."""
    lines = [f'# Tune report: {title}', '', *notes, '',
             '| gains | scenarios | objective | worst J | RMS F error / F_d | overshoot (%) | '
             'settling (s) | failed |',
             '| --- | --- | --- | --- | --- | --- | --- | --- |']
    for item in sets:
        lines.append(summary_row(item.name, 'train', item.train, worst_weight))
        lines.append(summary_row(item.name, 'held-out', item.held_out, worst_weight))
    lines += ['', "Objective: the tune file's weighted sum per run, (1 - w) mean + w worst over "
              'the runs (n/a where a run failed); the other columns are means over the runs '
              'that did not fail.', '']
    for item in sets:
        lines += [f'## {item.name}: every run', '',
                  '| run | split | J | RMS F error (N) | F_d (N) | overshoot (%) | settling (s) '
                  '| reason |', '| --- | --- | --- | --- | --- | --- | --- | --- |']
        for split, figures in (('train', item.train), ('held-out', item.held_out)):
            for f in figures:
                m = f.metrics
                lines.append(f'| {f.label} | {split} | {_num(f.score)} | '
                             f'{_num(m.get("force_rms_error_N"))} | '
                             f'{_num(m.get("desired_force_N"))} | '
                             f'{_num(m.get("overshoot_percent"))} | '
                             f'{_num(m.get("settling_time_s"))} | {f.reason} |')
        lines.append('')
    return '\n'.join(lines)


def _num(value: Any) -> str:
    return 'n/a' if value is None else f'{float(value):.4g}'


def draw_figures(out_dir: Path, trials: Sequence[FrozenTrial], gains: Sequence[Any],
                 recordings: Mapping[str, bytes]) -> list[Path]:
    """best_objective.png, gains.png and (with recordings) force.png in out_dir/figures."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    directory = out_dir / 'figures'
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    feasible = [t for t in trials if t.value is not None and
                all(v <= 0 for v in t.constraints.values())]
    infeasible = [t for t in trials if t not in feasible]
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    ax.plot([t.number for t in feasible], [t.value for t in feasible], 'o', color='tab:blue',
            label='feasible trial')
    best, xs, ys = math.inf, [], []
    for t in sorted(feasible, key=lambda t: t.number):
        best = min(best, float(t.value or math.inf))
        xs.append(t.number)
        ys.append(best)
    ax.step(xs, ys, where='post', color='black', label='best so far')
    if infeasible:
        top = max([float(t.value or 0) for t in feasible], default=1.0)
        ax.plot([t.number for t in infeasible], [top] * len(infeasible), 'x', color='tab:red',
                label='infeasible (unstable or failed)')
    ax.set_xlabel('trial')
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.set_ylabel('objective (-)')
    ax.legend()
    fig.tight_layout()
    written.append(directory / 'best_objective.png')
    fig.savefig(written[-1], dpi=100)
    plt.close(fig)
    fig, axes = plt.subplots(1, len(gains), figsize=(3.2 * len(gains), 3.2), squeeze=False)
    for ax, gain in zip(axes[0], gains, strict=True):
        ax.plot([t.params[gain.name] for t in feasible], [t.value for t in feasible], 'o',
                color='tab:blue')
        ax.set_xlabel(gain.name.replace('.', '.\n'))
        if gain.log:
            ax.set_xscale('log')
            ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    axes[0][0].set_ylabel('objective (-)')
    fig.tight_layout()
    written.append(directory / 'gains.png')
    fig.savefig(written[-1], dpi=100)
    plt.close(fig)
    if recordings:
        written.append(_force_figure(directory / 'force.png', recordings))
    return written


def _force_figure(path: Path, recordings: Mapping[str, bytes]) -> Path:
    """The normal force of each recorded run (label -> MCAP bytes) on one axis."""
    import matplotlib.pyplot as plt
    from uvms_analysis.metrics import normal_force
    from uvms_analysis.series import load_run

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    with tempfile.TemporaryDirectory(prefix='uvms-tune-') as tmp:
        for label, data in recordings.items():
            file = Path(tmp) / f'{label}.mcap'
            file.write_bytes(data)
            force = normal_force(load_run(file))
            if force is not None:
                ax.plot(force.t, force.force, label=label)
    ax.set_xlabel('time (s)')
    ax.set_ylabel('normal contact force (N)')
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
