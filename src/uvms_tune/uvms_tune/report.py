"""The tune's report: default, hand-tuned and tuned gains on the training and held-out sets.

``report.md`` holds the table (objective and worst J, mean RMS force error / F_d, overshoot
and settling time, failed runs: every figure over all the runs of a row, failures counted,
nothing averaged over only the runs that passed), a stated line where there are no held-out
runs, whether the best trial's run made again reproduced it, and every scenario run's
figures of each set; ``figures/`` holds the best objective against trial, each gain against
the objective, and the tuned run's normal force (ground truth) beside the defaults'.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from optuna.trial import FrozenTrial

from uvms_tune.objective import FIGURE_KEYS, GROUND_TRUTH, ScenarioFigures, figure

#: The gain sets of the report, in table order.
SETS = ('defaults', 'hand_tuned', 'tuned')
#: The figures computed from the normal contact force.
FORCE_KEYS = ('force_rms_error_N', 'overshoot_percent', 'settling_time_s', 'first_contact_s',
              'contact_count')


@dataclass
class SetFigures:
    """One gain set's figures on the training and held-out runs."""

    name: str
    train: list[ScenarioFigures]
    held_out: list[ScenarioFigures]


def _ground_truth_figure(item: ScenarioFigures, key: str) -> float | None:
    """A run's figure, None where missing or (a force figure) not of the ground-truth force."""
    if key in FORCE_KEYS and item.metrics.get('force_source') != GROUND_TRUTH:
        return None
    value = figure(item.metrics, key)
    if value is not None and key == 'force_rms_error_N':
        f_d = figure(item.metrics, 'desired_force_N')
        return value / abs(f_d) if f_d else None
    return value


def summary_row(name: str, split: str, figures: Sequence[ScenarioFigures],
                worst_weight: float) -> str:
    """One markdown row: the set, the split and its figures over all of its runs.

    Nothing is averaged over only the runs that passed: the objective and worst J are n/a
    when any run failed (a failed run has no J), and a figure is n/a when any run lacks it
    (or has it from the controller's estimate, not the ground truth), with the count.
    """
    total = len(figures)
    if not total:
        return f'| {name} | {split} | no runs | | | | | 0 of 0 |'
    failed = sum(1 for f in figures if f.score is None)
    scores = [float(f.score) for f in figures if f.score is not None]
    if failed:
        objective = worst = f'n/a ({failed} of {total} failed)'
    else:
        objective = f'{(1 - worst_weight) * sum(scores) / total + worst_weight * max(scores):.4g}'
        worst = f'{max(scores):.4g}'

    def mean(key: str) -> str:
        values = [_ground_truth_figure(f, key) for f in figures]
        missing = sum(1 for value in values if value is None)
        if missing:
            return f'n/a ({missing} of {total} without)'
        return f'{sum(float(v) for v in values if v is not None) / total:.4g}'

    return (f'| {name} | {split} | {objective} | {worst} | {mean("force_rms_error_N")} | '
            f'{mean("overshoot_percent")} | {mean("settling_time_s")} | '
            f'{failed} of {total} |')


def reproduction_differences(trial: Sequence[Mapping[str, Any]],
                             again: Sequence[Mapping[str, Any]]) -> list[str]:
    """How runs made again differ from the same runs of a trial (``as_dict`` summaries).

    Runs are matched by label; J, the reason and every figure are compared (numbers to a
    relative 1e-9: the runs are lockstep and seeded, so they should be equal). One line per
    difference; empty when the runs reproduce.
    """
    by_label = {item['label']: item for item in trial}
    lines = []
    for item in again:
        label = item['label']
        if label not in by_label:
            lines.append(f'`{label}`: not a run of the trial')
            continue
        for key in ('score', 'reason', *FIGURE_KEYS):
            was, now = by_label[label].get(key), item.get(key)
            if not _same(was, now):
                lines.append(f'`{label}` {"J" if key == "score" else key}: trial {_show(was)}, '
                             f'again {_show(now)}')
    return lines


def _same(was: Any, now: Any) -> bool:
    if isinstance(was, (int, float)) and isinstance(now, (int, float)):
        return math.isclose(float(was), float(now), rel_tol=1e-9, abs_tol=1e-12)
    return bool(was == now)


def _show(value: Any) -> str:
    if value is None or value == '':
        return 'none'
    return f'{value:.6g}' if isinstance(value, float) else str(value)


def reproduction_text(label: str, differences: Sequence[str]) -> list[str]:
    """The report's section on the best trial's run made again."""
    lines = ['## Reproduction of the best trial', '',
             f"The best trial's first training run (`{label}`), run again with the tuned gains "
             'for `figures/force.png` (`rerun_figures` in `provenance.json`):']
    if differences:
        lines += ['**differs from the trial** (the runs are lockstep and seeded: a difference '
                  'means the figures above do not reproduce):', '',
                  *(f'- {line}' for line in differences)]
    else:
        lines.append("gave the trial's J, reason and figures again (to a relative 1e-9).")
    return lines


def report_text(title: str, sets: Sequence[SetFigures], worst_weight: float,
                notes: Sequence[str], reproduction: Sequence[str] = ()) -> str:
    """The markdown report; ``reproduction`` (``reproduction_text``) follows the table."""
    held_out = any(item.held_out for item in sets)
    lines = [f'# Tune report: {title}', '', *notes, '',
             '| gains | scenarios | objective | worst J | RMS F error / F_d | overshoot (%) | '
             'settling (s) | failed |',
             '| --- | --- | --- | --- | --- | --- | --- | --- |']
    for item in sets:
        lines.append(summary_row(item.name, 'train', item.train, worst_weight))
        if held_out:
            lines.append(summary_row(item.name, 'held-out', item.held_out, worst_weight))
    lines += ['', "Objective: the tune file's weighted sum J per run, (1 - w) mean + w worst "
              'over all the runs of the row, n/a when any run failed (a failed run has no J). '
              'Each other column is its mean over all the runs of the row, failed ones '
              'included, and n/a when a run lacks the figure (or has it only from the '
              "controller's force estimate: every force figure is of the simulator's "
              'ground-truth contact force).', '']
    if not held_out:
        lines += ['**No held-out runs**: the tune file sets no `held_out:` runs, so nothing in '
                  'this report shows how the gains do on runs they were not tuned on.', '']
    if reproduction:
        lines += [*reproduction, '']
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
            force = normal_force(load_run(file), 'contact')
            if force is not None:
                ax.plot(force.t, force.force, label=label)
    ax.set_xlabel('time (s)')
    ax.set_ylabel('normal contact force (N)')
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
